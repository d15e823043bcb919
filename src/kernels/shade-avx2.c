/* AVX2 versions of the post-shaded per-sheet kernels (kernels.h),
 * 8 pixels a step, bit-identical to scalar.c: the table coordinate in
 * double as the reference, truncation by cvtt, lrintf as cvtps (round to
 * nearest), one multiply and one add per element, IEEE division.  Tails go
 * to the scalar reference (pixels are independent). */
#include "kernels.h"

#include <float.h>
#include <immintrin.h>

/* x = max((float)((v - vmin) * scale), 0), NaN -> 0 */
static inline __m256 tab_coord8(__m256 v, __m256d vmin, __m256d scale)
{
    __m256d lo = _mm256_cvtps_pd(_mm256_castps256_ps128(v));
    __m256d hi = _mm256_cvtps_pd(_mm256_extractf128_ps(v, 1));
    lo = _mm256_mul_pd(_mm256_sub_pd(lo, vmin), scale);
    hi = _mm256_mul_pd(_mm256_sub_pd(hi, vmin), scale);
    __m256 x = _mm256_set_m128(_mm256_cvtpd_ps(hi), _mm256_cvtpd_ps(lo));
    return _mm256_and_ps(x, _mm256_cmp_ps(x, _mm256_setzero_ps(), _CMP_GT_OQ));
}

/* (x, y, z) per lane -> x0 y0 z0 x1 ... z7 in three vectors */
static inline void store3(float *p, __m256 x, __m256 y, __m256 z)
{
    const __m256i i0 = _mm256_setr_epi32(0, 0, 0, 1, 1, 1, 2, 2);
    const __m256i i1 = _mm256_setr_epi32(2, 3, 3, 3, 4, 4, 4, 5);
    const __m256i i2 = _mm256_setr_epi32(5, 5, 6, 6, 6, 7, 7, 7);
    __m256 o0 = _mm256_blend_ps(_mm256_blend_ps(_mm256_permutevar8x32_ps(x, i0), _mm256_permutevar8x32_ps(y, i0), 0x92),
                                _mm256_permutevar8x32_ps(z, i0), 0x24);
    __m256 o1 = _mm256_blend_ps(_mm256_blend_ps(_mm256_permutevar8x32_ps(x, i1), _mm256_permutevar8x32_ps(y, i1), 0x24),
                                _mm256_permutevar8x32_ps(z, i1), 0x49);
    __m256 o2 = _mm256_blend_ps(_mm256_blend_ps(_mm256_permutevar8x32_ps(x, i2), _mm256_permutevar8x32_ps(y, i2), 0x49),
                                _mm256_permutevar8x32_ps(z, i2), 0x92);
    _mm256_storeu_ps(p, o0);
    _mm256_storeu_ps(p + 8, o1);
    _mm256_storeu_ps(p + 16, o2);
}

/* the inverse of store3 */
static inline void load3(const float *p, __m256 *x, __m256 *y, __m256 *z)
{
    __m256 o0 = _mm256_loadu_ps(p), o1 = _mm256_loadu_ps(p + 8), o2 = _mm256_loadu_ps(p + 16);
    __m256 bx = _mm256_blend_ps(_mm256_blend_ps(o0, o1, 0x92), o2, 0x24);
    __m256 by = _mm256_blend_ps(_mm256_blend_ps(o0, o1, 0x24), o2, 0x49);
    __m256 bz = _mm256_blend_ps(_mm256_blend_ps(o0, o1, 0x49), o2, 0x92);
    *x = _mm256_permutevar8x32_ps(bx, _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
    *y = _mm256_permutevar8x32_ps(by, _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6));
    *z = _mm256_permutevar8x32_ps(bz, _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7));
}

/* the opacity table at v (as lookup_alpha in scalar.c) */
static inline __m256 lookup_alpha8(const vs_shade_tabs *T, __m256 v)
{
    const __m256 top_x = _mm256_set1_ps((float)(VS_KTAB - 1));
    __m256 x = tab_coord8(v, _mm256_set1_pd(T->vmin), _mm256_set1_pd(T->scale));
    __m256 top = _mm256_cmp_ps(x, top_x, _CMP_GE_OQ);
    x = _mm256_andnot_ps(top, x); /* index 0 where the table's end is used */
    __m256i j = _mm256_cvttps_epi32(x);
    __m256 f = _mm256_sub_ps(x, _mm256_cvtepi32_ps(j));
    __m256 t0 = _mm256_i32gather_ps(T->alpha, j, 4), t1 = _mm256_i32gather_ps(T->alpha + 1, j, 4);
    return _mm256_blendv_ps(_mm256_add_ps(t0, _mm256_mul_ps(f, _mm256_sub_ps(t1, t0))),
                            _mm256_set1_ps(T->alpha[VS_KTAB - 1]), top);
}

/* lanes [0, k) set */
static inline __m256i prefix8(int k)
{
    return _mm256_cmpgt_epi32(_mm256_set1_epi32(k), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}

/* 8 pixels, or the first m of them (masked loads and stores: no access
 * past the span) */
static inline void classify8(float *alpha, float *g, const float *q, const float *qp, const float *qn, ptrdiff_t stride,
                             int m, const vs_shade_tabs *T)
{
    const __m256 half = _mm256_set1_ps(0.5f), two_slab = _mm256_set1_ps(T->two_slab);
    const __m256i in = prefix8(m);
#define LD(p) (m == 8 ? _mm256_loadu_ps(p) : _mm256_maskload_ps(p, in))
    __m256 a = lookup_alpha8(T, LD(q));
    __m256 gx = _mm256_mul_ps(half, _mm256_sub_ps(LD(q + 1), LD(q - 1)));
    __m256 gy = _mm256_mul_ps(half, _mm256_sub_ps(LD(q + stride), LD(q - stride)));
    __m256 gz = _mm256_div_ps(_mm256_sub_ps(LD(qn), LD(qp)), two_slab);
#undef LD
    if (m == 8) {
        _mm256_storeu_ps(alpha, a);
        store3(g, gx, gy, gz);
    } else {
        float tmp[24];
        _mm256_maskstore_ps(alpha, in, a);
        store3(tmp, gx, gy, gz);
        for (int k = 0; k < 3; k++) _mm256_maskstore_ps(g + 8 * k, prefix8(3 * m - 8 * k), _mm256_loadu_ps(tmp + 8 * k));
    }
}

void vs_classify_cd_avx2(float *alpha, float *g, const float *q, const float *qp, const float *qn, ptrdiff_t stride,
                         int n, const vs_shade_tabs *T)
{
    int i = 0;
    for (; i + 8 <= n; i += 8) classify8(alpha + i, g + 3 * i, q + i, qp + i, qn + i, stride, 8, T);
    if (i < n) classify8(alpha + i, g + 3 * i, q + i, qp + i, qn + i, stride, n - i, T);
}

/* Three passes over up to 64 pixels (8 vectors): each table look-up
 * depends on the one before (gradient -> lambda bin and radius -> phi bin
 * -> diffuse, specular), and a gather waits for its loads; split into
 * passes, the gathers of different vectors are independent and overlap. */
enum { BLK = 64 };

/* post-gs: (density, gx, gy, gz) per pixel, transposed to one vector per
 * channel (pixel order 0 2 4 6 1 3 5 7, put back by one permute each) */
void vs_classify_gs_avx2(float *alpha, float *g, const float *q4, int n, const vs_shade_tabs *T)
{
    const __m256i back = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
    const __m256 slab = _mm256_set1_ps(T->slab);
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        const float *p = q4 + 4 * i;
        __m256 r0 = _mm256_loadu_ps(p), r1 = _mm256_loadu_ps(p + 8), r2 = _mm256_loadu_ps(p + 16),
               r3 = _mm256_loadu_ps(p + 24);
        __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
        __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
        __m256 d = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(t0, t2, 0x44), back);
        __m256 gx = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(t0, t2, 0xee), back);
        __m256 gy = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(t1, t3, 0x44), back);
        __m256 gz = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(t1, t3, 0xee), back);
        _mm256_storeu_ps(alpha + i, lookup_alpha8(T, d));
        store3(g + 3 * i, _mm256_div_ps(gx, slab), _mm256_div_ps(gy, slab), _mm256_div_ps(gz, slab));
    }
    if (i < n) vs_classify_gs_scalar(alpha + i, g + 3 * i, q4 + 4 * i, n - i, T);
}

void vs_shade_lut_avx2(float *g, const float *alpha, const float *v, int vstride, int n, const vs_shade_tabs *T)
{
    const __m256 ppm = _mm256_set1_ps(T->ppm), zpm = _mm256_set1_ps(T->zpm), zero = _mm256_setzero_ps();
    const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    const __m256 fmax = _mm256_set1_ps(FLT_MAX), tiny = _mm256_set1_ps(1e-30f), k127 = _mm256_set1_ps(127.0f);
    const __m256i zi = _mm256_setzero_si256(), m127 = _mm256_set1_epi32(-127);
    const __m256i off_lr = _mm256_set1_epi32(127 * 255 + 127), off_p = _mm256_set1_epi32(127 * 181);
    const __m256i c255 = _mm256_set1_epi32(255), c181 = _mm256_set1_epi32(181), cnl = _mm256_set1_epi32(T->nl);
    const __m256i lo16 = _mm256_set1_epi32(0xffff), lo8 = _mm256_set1_epi32(0xff);
    const __m256d vmin = _mm256_set1_pd(T->vmin), scale = _mm256_set1_pd(T->scale);
    const __m256 top_x = _mm256_set1_ps((float)(VS_KTAB - 1));
    const __m256i vidx = _mm256_mullo_epi32(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), _mm256_set1_epi32(vstride));
    const float *col = T->color;
    _Alignas(32) int32_t ia[BLK], ib[BLK];
    int i0 = 0;
    for (; i0 + 8 <= n; i0 += BLK) {
        const int nv = (n - i0 < BLK ? n - i0 : BLK) / 8;
        int live[BLK / 8];
        /* pass 1: quantised gradient -> lambda bin (ia) and phi index (ib) */
        for (int c = 0; c < nv; c++) {
            const int i = i0 + 8 * c;
            live[c] = _mm256_movemask_ps(_mm256_cmp_ps(_mm256_loadu_ps(alpha + i), zero, _CMP_GT_OQ));
            if (!live[c]) continue;
            __m256 g0x, g0y, g0z;
            load3(g + 3 * i, &g0x, &g0y, &g0z);
            __m256 gx = _mm256_mul_ps(g0x, ppm), gy = _mm256_mul_ps(g0y, ppm), gz = _mm256_mul_ps(g0z, zpm);
            __m256 ax = _mm256_and_ps(gx, absmask), ay = _mm256_and_ps(gy, absmask), az = _mm256_and_ps(gz, absmask);
            __m256 m = _mm256_max_ps(_mm256_max_ps(ax, ay), az); /* NaN lanes are cleared below */
            __m256 ok = _mm256_and_ps(
                _mm256_and_ps(_mm256_cmp_ps(ax, fmax, _CMP_LE_OQ), _mm256_cmp_ps(ay, fmax, _CMP_LE_OQ)),
                _mm256_and_ps(_mm256_cmp_ps(az, fmax, _CMP_LE_OQ), _mm256_cmp_ps(m, tiny, _CMP_GE_OQ)));
            __m256 k = _mm256_div_ps(k127, _mm256_blendv_ps(k127, m, ok)); /* no division by 0 or NaN */
            __m256i oki = _mm256_castps_si256(ok);
            __m256i ix = _mm256_and_si256(_mm256_cvtps_epi32(_mm256_mul_ps(gx, k)), oki);
            __m256i iy = _mm256_and_si256(_mm256_cvtps_epi32(_mm256_mul_ps(gy, k)), oki);
            __m256i iz = _mm256_and_si256(_mm256_cvtps_epi32(_mm256_mul_ps(gz, k)), oki);
            __m256i allz = _mm256_cmpeq_epi32(_mm256_or_si256(_mm256_or_si256(ix, iy), iz), zi);
            iz = _mm256_blendv_epi8(iz, m127, allz); /* zero gradient: faces the eye */
            __m256i lr = _mm256_add_epi32(_mm256_mullo_epi32(iy, c255), _mm256_add_epi32(ix, off_lr));
            __m256i li = _mm256_and_si256(_mm256_i32gather_epi32((const int *)(const void *)T->lambda_bin, lr, 2), lo16);
            __m256i r = _mm256_and_si256(_mm256_i32gather_epi32((const int *)(const void *)T->radius, lr, 1), lo8);
            _mm256_store_si256((__m256i *)(void *)(ia + 8 * c), li);
            _mm256_store_si256((__m256i *)(void *)(ib + 8 * c),
                               _mm256_add_epi32(_mm256_mullo_epi32(iz, c181), _mm256_add_epi32(r, off_p)));
        }
        /* pass 2: phi bin -> shading table index (ia) */
        for (int c = 0; c < nv; c++) {
            if (!live[c]) continue;
            __m256i pidx = _mm256_load_si256((const __m256i *)(const void *)(ib + 8 * c));
            __m256i pi = _mm256_and_si256(_mm256_i32gather_epi32((const int *)(const void *)T->phi_bin, pidx, 2), lo16);
            __m256i li = _mm256_load_si256((const __m256i *)(const void *)(ia + 8 * c));
            _mm256_store_si256((__m256i *)(void *)(ia + 8 * c), _mm256_add_epi32(_mm256_mullo_epi32(pi, cnl), li));
        }
        /* pass 3, per visible pixel (a quarter of the pixels on the head):
         * diffuse, specular, and the colour table as one 4-float vector
         * (r, g, b, -) from two unaligned loads, instead of eight gathers */
        for (int c = 0; c < nv; c++) {
            if (!live[c]) continue;
            const int i = i0 + 8 * c;
            __m256 val = vstride == 1 ? _mm256_loadu_ps(v + i) : _mm256_i32gather_ps(v + (ptrdiff_t)i * vstride, vidx, 4);
            __m256 x = _mm256_min_ps(tab_coord8(val, vmin, scale), top_x);
            __m256i j = _mm256_cvttps_epi32(x);
            __m256 f = _mm256_sub_ps(x, _mm256_cvtepi32_ps(j));
            /* the table's end: f = 0 at entry 4094 would not give entry 4095
             * exactly, so such pixels take c0 = c1 = the last entry (j3 = -1 marks them) */
            __m256i top = _mm256_castps_si256(_mm256_cmp_ps(x, top_x, _CMP_GE_OQ));
            __m256i j3 = _mm256_or_si256(_mm256_mullo_epi32(j, _mm256_set1_epi32(3)), top);
            _Alignas(32) float fs[8];
            _Alignas(32) int32_t js[8];
            _mm256_store_ps(fs, f);
            _mm256_store_si256((__m256i *)(void *)js, j3);
            for (unsigned lv = (unsigned)live[c]; lv; lv &= lv - 1) {
                const int l = __builtin_ctz(lv);
                __m128 rgb;
                if (js[l] >= 0) {
                    /* c1 from col + 2 and shifted: no read past the table's end */
                    __m128 c0 = _mm_loadu_ps(col + js[l]), c1 = _mm_loadu_ps(col + js[l] + 2);
                    c1 = _mm_shuffle_ps(c1, c1, _MM_SHUFFLE(3, 3, 2, 1));
                    rgb = _mm_add_ps(c0, _mm_mul_ps(_mm_set1_ps(fs[l]), _mm_sub_ps(c1, c0)));
                } else {
                    rgb = _mm_setr_ps(col[3 * (VS_KTAB - 1)], col[3 * (VS_KTAB - 1) + 1], col[3 * (VS_KTAB - 1) + 2], 0.0f);
                }
                const int di = ia[8 * c + l];
                __m128 o = _mm_add_ps(_mm_mul_ps(rgb, _mm_set1_ps(T->diffuse[di])), _mm_set1_ps(T->specular[di]));
                float *dst = g + 3 * (i + l);
                _mm_storel_pi((__m64 *)(void *)dst, o); /* 3 floats: the next pixel's stay */
                _mm_store_ss(dst + 2, _mm_movehl_ps(o, o));
            }
        }
        if (nv * 8 < BLK) {
            i0 += nv * 8;
            break;
        }
    }
    if (i0 < n) vs_shade_lut_scalar(g + 3 * i0, alpha + i0, v + (ptrdiff_t)i0 * vstride, vstride, n - i0, T);
}
