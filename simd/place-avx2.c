/* Voxel activation (occlusion test, block placement, depth integrals),
 * AVX2: eight voxels a step, the scalar reference's operations in its
 * order (scalar.c), table and summed-area look-ups by masked gathers
 * (masked so that a culled or empty lane reads nothing). */
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

/* table[i] + f (table[i + 1] - table[i]) in the lanes of m, else 0, f the
 * fraction of x >= 0.  Entries i and i + 1 come as one 8-byte gather
 * element (half the elements of two float gathers), then split. */
static inline __m256 lerp_table8(const float *table, __m256 m, __m256 x)
{
    const __m256i i = _mm256_cvttps_epi32(x);
    const __m256 f = _mm256_sub_ps(x, _mm256_cvtepi32_ps(i));
    const __m256i mi = _mm256_castps_si256(m);
    const __m256 lo = _mm256_castsi256_ps(_mm256_mask_i32gather_epi64(
        _mm256_setzero_si256(), (const long long *)(const void *)table, _mm256_castsi256_si128(i),
        _mm256_cvtepi32_epi64(_mm256_castsi256_si128(mi)), 4));
    const __m256 hi = _mm256_castsi256_ps(_mm256_mask_i32gather_epi64(
        _mm256_setzero_si256(), (const long long *)(const void *)table, _mm256_extracti128_si256(i, 1),
        _mm256_cvtepi32_epi64(_mm256_extracti128_si256(mi, 1)), 4));
    /* shuffle_ps gives lanes 0 1 4 5 2 3 6 7; the 64-bit permute orders them */
    const __m256 t0 = _mm256_castpd_ps(_mm256_permute4x64_pd(
        _mm256_castps_pd(_mm256_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0))), _MM_SHUFFLE(3, 1, 2, 0)));
    const __m256 t1 = _mm256_castpd_ps(_mm256_permute4x64_pd(
        _mm256_castps_pd(_mm256_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 1, 3, 1))), _MM_SHUFFLE(3, 1, 2, 0)));
    return _mm256_and_ps(m, _mm256_add_ps(t0, _mm256_mul_ps(f, _mm256_sub_ps(t1, t0))));
}

/* G(z) in the lanes of m (vs_fp_depth) */
static inline __m256 depth8(const vs_place_in *P, __m256 m, __m256 z)
{
    const __m256 x = _mm256_mul_ps(_mm256_add_ps(z, _mm256_set1_ps(P->rz)), _mm256_set1_ps(P->depth_scale));
    const __m256 pos = _mm256_and_ps(m, _mm256_cmp_ps(x, _mm256_setzero_ps(), _CMP_GT_OQ));
    const __m256 top = _mm256_and_ps(pos, _mm256_cmp_ps(x, _mm256_set1_ps((float)(P->depth_n - 1)), _CMP_GE_OQ));
    const __m256 g = lerp_table8(P->depth, _mm256_andnot_ps(top, pos), x);
    return _mm256_blendv_ps(g, _mm256_set1_ps(P->depth[P->depth_n - 1]), top);
}

/* exp(-kappa b^2) for |b| < rz in the lanes of m, else 0 (the scalar
 * reference's exp_at) */
static inline __m256 exp8(const vs_place_in *P, __m256 m, __m256 b)
{
    const __m256 ab = _mm256_andnot_ps(_mm256_set1_ps(-0.0f), b);
    const __m256 in = _mm256_and_ps(m, _mm256_cmp_ps(ab, _mm256_set1_ps(P->rz), _CMP_LT_OQ));
    const __m256 x = _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(P->kappa), b), b),
                                   _mm256_set1_ps(P->exp_scale));
    const __m256 ok = _mm256_and_ps(in, _mm256_cmp_ps(x, _mm256_set1_ps((float)(P->exp_n - 1)), _CMP_LT_OQ));
    return lerp_table8(P->exp_table, ok, x);
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
static unsigned place_half(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out, int h)
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
    __m256 g0 = depth8(P, live, _mm256_sub_ps(_mm256_set1_ps((float)P->opening * P->slab), z));
    for (int j = 0; j < P->nd; j++) {
        const __m256 g1 = depth8(P, live, _mm256_sub_ps(_mm256_set1_ps((float)(P->opening + j + 1) * P->slab), z));
        _mm256_storeu_ps(out->D[j] + h, _mm256_sub_ps(g1, g0));
        g0 = g1;
    }
    if (P->with_e) {
        __m256 e0 = exp8(P, live, _mm256_sub_ps(_mm256_set1_ps((float)P->opening * P->slab), z));
        for (int j = 0; j < P->nd; j++) {
            const __m256 e1 = exp8(P, live, _mm256_sub_ps(_mm256_set1_ps((float)(P->opening + j + 1) * P->slab), z));
            _mm256_storeu_ps(out->E[j] + h, _mm256_sub_ps(e1, e0));
            e0 = e1;
        }
    }
    return bits << h;
}

unsigned vs_place_voxels_avx2(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out)
{
    unsigned live = place_half(xyz, stride, n, P, out, 0);
    if (n > 8) live |= place_half(xyz, stride, n, P, out, 8);
    if (P->colw)
        for (unsigned m = live; m; m &= m - 1) {
            const int i = __builtin_ctz(m);
            lerp8(out->cw[i], P->colw + (size_t)out->qx[i] * P->bx, P->bx, out->fx[i]);
            _mm256_storeu_ps(out->cw[i] + P->bx, _mm256_setzero_ps());
            lerp8(out->rw[i], P->roww + (size_t)out->qy[i] * P->ny, P->ny, out->fy[i]);
        }
    return live;
}
