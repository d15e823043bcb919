/* AVX2 shading of a sheet's visible pixels through the normal and colour
 * tables (kernels.h shade_lut, shade_terms), bit-identical to scalar.c: the colour
 * table's coordinate in double as the reference, lrintf as cvtps (round to
 * nearest), one multiply and one add per element.  Tails go to the scalar
 * reference (pixels are independent). */
#include "kernels.h"
#include "tab_coord-avx2.h"

#include <float.h>
#include <immintrin.h>

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

/* Three passes over up to 64 pixels (8 vectors): each table look-up
 * depends on the one before (gradient -> lambda bin and radius -> phi bin
 * -> diffuse, specular), and a gather waits for its loads; split into
 * passes, the gathers of different vectors are independent and overlap. */
enum { BLK = 64 };

/* Passes 1 and 2 over nv vectors of gradients g (3 floats a pixel): the
 * shading table's index of each pixel into ia; live[c], vector c's pixels
 * with alpha > 0 (alpha NULL: all), vectors without any are skipped. */
static inline void lut_bins(const float *g, const float *alpha, int nv, int live[BLK / 8], int32_t ia[BLK],
                            const vs_shade_tabs *T)
{
    const __m256 ppm = _mm256_set1_ps(T->ppm), zpm = _mm256_set1_ps(T->zpm), zero = _mm256_setzero_ps();
    const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    const __m256 fmax = _mm256_set1_ps(FLT_MAX), tiny = _mm256_set1_ps(1e-30f), k127 = _mm256_set1_ps(127.0f);
    const __m256i zi = _mm256_setzero_si256(), m127 = _mm256_set1_epi32(-127);
    const __m256i off_lr = _mm256_set1_epi32(127 * 255 + 127), off_p = _mm256_set1_epi32(127 * 181);
    const __m256i c255 = _mm256_set1_epi32(255), c181 = _mm256_set1_epi32(181), cnl = _mm256_set1_epi32(T->nl);
    const __m256i lo16 = _mm256_set1_epi32(0xffff), lo8 = _mm256_set1_epi32(0xff);
    _Alignas(32) int32_t ib[BLK];
    /* pass 1: quantised gradient -> lambda bin (ia) and phi index (ib) */
    for (int c = 0; c < nv; c++) {
        live[c] = alpha ? _mm256_movemask_ps(_mm256_cmp_ps(_mm256_loadu_ps(alpha + 8 * c), zero, _CMP_GT_OQ)) : 0xff;
        if (!live[c]) continue;
        __m256 g0x, g0y, g0z;
        load3(g + 24 * c, &g0x, &g0y, &g0z);
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
}

void vs_shade_lut_avx2(float *g, const float *alpha, const float *v, int vstride, int n, const vs_shade_tabs *T)
{
    const __m256d vmin = _mm256_set1_pd(T->vmin), scale = _mm256_set1_pd(T->scale);
    const __m256 top_x = _mm256_set1_ps((float)(VS_KTAB - 1));
    const __m256i vidx = _mm256_mullo_epi32(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), _mm256_set1_epi32(vstride));
    const float *col = T->color;
    _Alignas(32) int32_t ia[BLK];
    int i0 = 0;
    for (; i0 + 8 <= n; i0 += BLK) {
        const int nv = (n - i0 < BLK ? n - i0 : BLK) / 8;
        int live[BLK / 8];
        lut_bins(g + 3 * i0, alpha + i0, nv, live, ia, T);
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

void vs_shade_terms_avx2(float *d, float *s, const float *g, int n, const vs_shade_tabs *T)
{
    _Alignas(32) int32_t ia[BLK];
    int i0 = 0;
    for (; i0 + 8 <= n; i0 += BLK) {
        const int nv = (n - i0 < BLK ? n - i0 : BLK) / 8;
        int live[BLK / 8];
        lut_bins(g + 3 * i0, NULL, nv, live, ia, T);
        for (int c = 0; c < nv; c++) {
            const __m256i di = _mm256_load_si256((const __m256i *)(const void *)(ia + 8 * c));
            _mm256_storeu_ps(d + i0 + 8 * c, _mm256_i32gather_ps(T->diffuse, di, 4));
            _mm256_storeu_ps(s + i0 + 8 * c, _mm256_i32gather_ps(T->specular, di, 4));
        }
        if (nv * 8 < BLK) {
            i0 += nv * 8;
            break;
        }
    }
    if (i0 < n) vs_shade_terms_scalar(d + i0, s + i0, g + 3 * i0, n - i0, T);
}
