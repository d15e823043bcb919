/* Voxel activation (occlusion test, block placement, depth integrals),
 * AVX2: eight voxels a step, the scalar reference's operations in its
 * order (scalar.c), summed-area look-ups by masked gathers (masked so
 * that a culled or empty lane reads nothing). */
#include "kernels.h"

#include <immintrin.h>

/* comparison masks are all-ones (-1) lanes: adding one subtracts 1 */
static inline __m256i ifloor8(__m256 v)
{
    const __m256i i = _mm256_cvttps_epi32(v);
    return _mm256_add_epi32(i, _mm256_castps_si256(_mm256_cmp_ps(v, _mm256_cvtepi32_ps(i), _CMP_LT_OQ)));
}
static inline __m256i iceil8(__m256 v)
{
    const __m256i i = _mm256_cvttps_epi32(v);
    return _mm256_sub_epi32(i, _mm256_castps_si256(_mm256_cmp_ps(v, _mm256_cvtepi32_ps(i), _CMP_GT_OQ)));
}

/* a block's first pixel and phase along one axis (vs_block_place_at) */
static inline void place8(__m256 c, float r0, float phases, __m256i *p, __m256i *q, __m256 *f)
{
    const __m256 l = _mm256_sub_ps(c, _mm256_set1_ps(r0));
    *p = iceil8(l);
    const __m256 s = _mm256_mul_ps(_mm256_sub_ps(_mm256_cvtepi32_ps(*p), l), _mm256_set1_ps(phases));
    *q = _mm256_min_epi32(_mm256_cvttps_epi32(s), _mm256_set1_epi32((int)phases - 1));
    *f = _mm256_sub_ps(s, _mm256_cvtepi32_ps(*q));
}

/* o[k] = t0[k] + f (t1[k] - t0[k]), k < n, t1 = t0 + n (block.c's lerp) */
static inline void lerp8(float *o, const float *t0, int n, float f)
{
    const __m256 fv = _mm256_set1_ps(f);
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    for (int k = 0; k < n; k += 8) {
        const __m256i m = _mm256_cmpgt_epi32(_mm256_set1_epi32(n - k), lane);
        const __m256 a = _mm256_maskload_ps(t0 + k, m), b = _mm256_maskload_ps(t0 + n + k, m);
        _mm256_maskstore_ps(o + k, m, _mm256_add_ps(a, _mm256_mul_ps(fv, _mm256_sub_ps(b, a))));
    }
}

/* lanes h .. h + 7 of the batch; returns their live bits */
static unsigned place_half(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out, int h, int *sr,
                           float *sf)
{
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const __m256 all = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(n - h), lane));
    const __m256i idx = _mm256_mullo_epi32(_mm256_add_epi32(lane, _mm256_set1_epi32(h)), _mm256_set1_epi32(stride));
    const __m256 zf = _mm256_setzero_ps();
    const __m256 x = _mm256_mask_i32gather_ps(zf, xyz, idx, all, 4);
    const __m256 y = _mm256_mask_i32gather_ps(zf, xyz + 1, idx, all, 4);
    const __m256 z = _mm256_mask_i32gather_ps(zf, xyz + 2, idx, all, 4);
    __m256 live = all;
    if (P->sat) {
        const __m256 px = _mm256_set1_ps(P->pad_x), py = _mm256_set1_ps(P->pad_y);
        const __m256i one = _mm256_set1_epi32(1), zero = _mm256_setzero_si256();
        const __m256i tx0 = _mm256_set1_epi32(P->tx0), ty0 = _mm256_set1_epi32(P->ty0);
        const __m256i xa = _mm256_max_epi32(_mm256_sub_epi32(ifloor8(_mm256_sub_ps(x, px)), tx0), zero);
        const __m256i ya = _mm256_max_epi32(_mm256_sub_epi32(ifloor8(_mm256_sub_ps(y, py)), ty0), zero);
        const __m256i xb =
            _mm256_min_epi32(_mm256_sub_epi32(iceil8(_mm256_add_ps(x, px)), tx0), _mm256_set1_epi32(P->tw - 1));
        const __m256i yb =
            _mm256_min_epi32(_mm256_sub_epi32(iceil8(_mm256_add_ps(y, py)), ty0), _mm256_set1_epi32(P->th - 1));
        /* some tile pixel within reach: !(xa > xb || ya > yb) */
        const __m256i none = _mm256_or_si256(_mm256_cmpgt_epi32(xa, xb), _mm256_cmpgt_epi32(ya, yb));
        const __m256 some = _mm256_andnot_ps(_mm256_castsi256_ps(none), all);
        const __m256i ms = _mm256_castps_si256(some);
        const __m256i w = _mm256_set1_epi32(P->tw + 1);
        const __m256i r0 = _mm256_mullo_epi32(ya, w), r1 = _mm256_mullo_epi32(_mm256_add_epi32(yb, one), w);
        const __m256i c1 = _mm256_add_epi32(xb, one);
        const int *sat = P->sat;
        const __m256i s11 = _mm256_mask_i32gather_epi32(zero, sat, _mm256_add_epi32(r1, c1), ms, 4);
        const __m256i s01 = _mm256_mask_i32gather_epi32(zero, sat, _mm256_add_epi32(r0, c1), ms, 4);
        const __m256i s10 = _mm256_mask_i32gather_epi32(zero, sat, _mm256_add_epi32(r1, xa), ms, 4);
        const __m256i s00 = _mm256_mask_i32gather_epi32(zero, sat, _mm256_add_epi32(r0, xa), ms, 4);
        const __m256i sum = _mm256_add_epi32(_mm256_sub_epi32(_mm256_sub_epi32(s11, s01), s10), s00);
        const __m256i area = _mm256_mullo_epi32(_mm256_add_epi32(_mm256_sub_epi32(xb, xa), one),
                                                _mm256_add_epi32(_mm256_sub_epi32(yb, ya), one));
        live = _mm256_andnot_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(sum, area)), some);
    }
    const unsigned bits = (unsigned)_mm256_movemask_ps(live);
    if (!bits) return 0;
    __m256i bx, by, qx, qy;
    __m256 fx, fy;
    place8(x, P->rx0, P->phases, &bx, &qx, &fx);
    place8(y, P->ry0, P->phases, &by, &qy, &fy);
    _mm256_storeu_si256((__m256i *)(out->bx + h), _mm256_sub_epi32(bx, _mm256_set1_epi32(P->ox)));
    _mm256_storeu_si256((__m256i *)(out->by + h), _mm256_sub_epi32(by, _mm256_set1_epi32(P->oy)));
    _mm256_storeu_si256((__m256i *)(out->qx + h), qx);
    _mm256_storeu_si256((__m256i *)(out->qy + h), qy);
    _mm256_storeu_ps(out->fx + h, fx);
    _mm256_storeu_ps(out->fy + h, fy);
    /* the slab tables' rows and fractions (vs_place_slab_x) */
    const __m256 sxv = _mm256_min_ps(
        _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(z, _mm256_set1_ps((float)P->opening * P->slab + P->rz)),
                                    _mm256_set1_ps(P->sscale)),
                      _mm256_setzero_ps()),
        _mm256_set1_ps((float)P->sn));
    const __m256i srv = _mm256_min_epi32(_mm256_cvttps_epi32(sxv), _mm256_set1_epi32(P->sn - 1));
    _mm256_storeu_si256((__m256i *)(void *)(sr + h), srv);
    _mm256_storeu_ps(sf + h, _mm256_sub_ps(sxv, _mm256_cvtepi32_ps(srv)));
    return bits << h;
}

unsigned vs_place_voxels_avx2(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out)
{
    int sr[16];
    float sf[16];
    unsigned live = place_half(xyz, stride, n, P, out, 0, sr, sf);
    if (n > 8) live |= place_half(xyz, stride, n, P, out, 8, sr, sf);
    /* a row pair of the slab tables a live voxel, and its factors */
    for (unsigned m = live; m; m &= m - 1) {
        const int i = __builtin_ctz(m);
        const size_t row = (size_t)sr[i] * P->sw;
        lerp8(out->D[i], P->sd + row, P->sw, sf[i]);
        if (P->with_e) lerp8(out->E[i], P->se + row, P->sw, sf[i]);
        if (!P->colw) continue;
        lerp8(out->cw[i], P->colw + (size_t)out->qx[i] * P->bx, P->bx, out->fx[i]);
        _mm256_storeu_ps(out->cw[i] + P->bx, _mm256_setzero_ps());
        lerp8(out->rw[i], P->roww + (size_t)out->qy[i] * P->ny, P->ny, out->fy[i]);
    }
    return live;
}
