/* Voxel activation (occlusion test, block placement, depth integrals),
 * AVX-512: sixteen voxels a call, the scalar reference's operations in its
 * order (scalar.c), summed-area look-ups by masked gathers (masked so
 * that a culled or empty lane reads nothing). */
#include "kernels.h"

#include <immintrin.h>

static inline __m512i ifloor16(__m512 v)
{
    const __m512i i = _mm512_cvttps_epi32(v);
    return _mm512_mask_sub_epi32(i, _mm512_cmp_ps_mask(v, _mm512_cvtepi32_ps(i), _CMP_LT_OQ), i,
                                 _mm512_set1_epi32(1));
}
static inline __m512i iceil16(__m512 v)
{
    const __m512i i = _mm512_cvttps_epi32(v);
    return _mm512_mask_add_epi32(i, _mm512_cmp_ps_mask(v, _mm512_cvtepi32_ps(i), _CMP_GT_OQ), i,
                                 _mm512_set1_epi32(1));
}

/* a block's first pixel and phase along one axis (vs_block_place_at) */
static inline void place16(__m512 c, float r0, float phases, __m512i *p, __m512i *q, __m512 *f)
{
    const __m512 l = _mm512_sub_ps(c, _mm512_set1_ps(r0));
    *p = iceil16(l);
    const __m512 s = _mm512_mul_ps(_mm512_sub_ps(_mm512_cvtepi32_ps(*p), l), _mm512_set1_ps(phases));
    *q = _mm512_min_epi32(_mm512_cvttps_epi32(s), _mm512_set1_epi32((int)phases - 1));
    *f = _mm512_sub_ps(s, _mm512_cvtepi32_ps(*q));
}

/* o[k] = t0[k] + f (t1[k] - t0[k]), k < n, t1 = t0 + n (block.c's lerp);
 * m: the mask of a row's last (or only) 16 floats, made once a call */
static inline void lerp16(float *o, const float *t0, int n, float f, __mmask16 m)
{
    const __m512 fv = _mm512_set1_ps(f);
    int k = 0;
    for (; n - k > 16; k += 16) {
        const __m512 a = _mm512_loadu_ps(t0 + k), b = _mm512_loadu_ps(t0 + n + k);
        _mm512_storeu_ps(o + k, _mm512_add_ps(a, _mm512_mul_ps(fv, _mm512_sub_ps(b, a))));
    }
    const __m512 a = _mm512_maskz_loadu_ps(m, t0 + k), b = _mm512_maskz_loadu_ps(m, t0 + n + k);
    _mm512_mask_storeu_ps(o + k, m, _mm512_add_ps(a, _mm512_mul_ps(fv, _mm512_sub_ps(b, a))));
}
static inline __mmask16 tail16(int n) { return (__mmask16)(0xffffu >> (15 - (n - 1) % 16)); }

unsigned vs_place_voxels_avx512(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out)
{
    const __mmask16 all = n >= 16 ? (__mmask16)0xffff : (__mmask16)((1u << n) - 1u);
    const __m512i idx = _mm512_mullo_epi32(_mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15),
                                           _mm512_set1_epi32(stride));
    const __m512 x = _mm512_mask_i32gather_ps(_mm512_setzero_ps(), all, idx, xyz, 4);
    const __m512 y = _mm512_mask_i32gather_ps(_mm512_setzero_ps(), all, idx, xyz + 1, 4);
    const __m512 z = _mm512_mask_i32gather_ps(_mm512_setzero_ps(), all, idx, xyz + 2, 4);
    __mmask16 live = all;
    if (P->sat) {
        const __m512 px = _mm512_set1_ps(P->pad_x), py = _mm512_set1_ps(P->pad_y);
        const __m512i one = _mm512_set1_epi32(1), zero = _mm512_setzero_si512();
        const __m512i xa = _mm512_max_epi32(_mm512_sub_epi32(ifloor16(_mm512_sub_ps(x, px)), _mm512_set1_epi32(P->tx0)), zero);
        const __m512i ya = _mm512_max_epi32(_mm512_sub_epi32(ifloor16(_mm512_sub_ps(y, py)), _mm512_set1_epi32(P->ty0)), zero);
        const __m512i xb = _mm512_min_epi32(_mm512_sub_epi32(iceil16(_mm512_add_ps(x, px)), _mm512_set1_epi32(P->tx0)),
                                            _mm512_set1_epi32(P->tw - 1));
        const __m512i yb = _mm512_min_epi32(_mm512_sub_epi32(iceil16(_mm512_add_ps(y, py)), _mm512_set1_epi32(P->ty0)),
                                            _mm512_set1_epi32(P->th - 1));
        const __mmask16 some = _mm512_mask_cmple_epi32_mask(_mm512_cmple_epi32_mask(xa, xb) & all, ya, yb);
        const __m512i w = _mm512_set1_epi32(P->tw + 1);
        const __m512i r0 = _mm512_mullo_epi32(ya, w), r1 = _mm512_mullo_epi32(_mm512_add_epi32(yb, one), w);
        const __m512i c1 = _mm512_add_epi32(xb, one);
        const __m512i s11 = _mm512_mask_i32gather_epi32(zero, some, _mm512_add_epi32(r1, c1), P->sat, 4);
        const __m512i s01 = _mm512_mask_i32gather_epi32(zero, some, _mm512_add_epi32(r0, c1), P->sat, 4);
        const __m512i s10 = _mm512_mask_i32gather_epi32(zero, some, _mm512_add_epi32(r1, xa), P->sat, 4);
        const __m512i s00 = _mm512_mask_i32gather_epi32(zero, some, _mm512_add_epi32(r0, xa), P->sat, 4);
        const __m512i sum = _mm512_add_epi32(_mm512_sub_epi32(_mm512_sub_epi32(s11, s01), s10), s00);
        const __m512i area = _mm512_mullo_epi32(_mm512_add_epi32(_mm512_sub_epi32(xb, xa), one),
                                                _mm512_add_epi32(_mm512_sub_epi32(yb, ya), one));
        live = some & _mm512_mask_cmpneq_epi32_mask(some, sum, area);
    }
    if (!live) return 0;
    __m512i bx, by, qx, qy;
    __m512 fx, fy;
    place16(x, P->rx0, P->phases, &bx, &qx, &fx);
    place16(y, P->ry0, P->phases, &by, &qy, &fy);
    _mm512_storeu_si512(out->bx, _mm512_sub_epi32(bx, _mm512_set1_epi32(P->ox)));
    _mm512_storeu_si512(out->by, _mm512_sub_epi32(by, _mm512_set1_epi32(P->oy)));
    _mm512_storeu_si512(out->qx, qx);
    _mm512_storeu_si512(out->qy, qy);
    _mm512_storeu_ps(out->fx, fx);
    _mm512_storeu_ps(out->fy, fy);
    /* the slab tables' rows and fractions (vs_place_slab_x), then a row
     * pair a live voxel */
    const __m512 sxv = _mm512_min_ps(
        _mm512_max_ps(_mm512_mul_ps(_mm512_sub_ps(z, _mm512_set1_ps((float)P->opening * P->slab + P->rz)),
                                    _mm512_set1_ps(P->sscale)),
                      _mm512_setzero_ps()),
        _mm512_set1_ps((float)P->sn));
    const __m512i srv = _mm512_min_epi32(_mm512_cvttps_epi32(sxv), _mm512_set1_epi32(P->sn - 1));
    int sr[16];
    float sf[16];
    _mm512_storeu_si512(sr, srv);
    _mm512_storeu_ps(sf, _mm512_sub_ps(sxv, _mm512_cvtepi32_ps(srv)));
    const __mmask16 md = tail16(P->sw), mc = P->colw ? tail16(P->bx) : 0, mr = P->colw ? tail16(P->ny) : 0;
    for (unsigned m = live; m; m &= m - 1) {
        const int i = __builtin_ctz(m);
        const size_t row = (size_t)sr[i] * P->sw;
        lerp16(out->D[i], P->sd + row, P->sw, sf[i], md);
        if (P->with_e) lerp16(out->E[i], P->se + row, P->sw, sf[i], md);
        if (!P->colw) continue;
        lerp16(out->cw[i], P->colw + (size_t)out->qx[i] * P->bx, P->bx, out->fx[i], mc);
        _mm256_storeu_ps(out->cw[i] + P->bx, _mm256_setzero_ps());
        lerp16(out->rw[i], P->roww + (size_t)out->qy[i] * P->ny, P->ny, out->fy[i], mr);
    }
    return live;
}
