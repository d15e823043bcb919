/* AVX-512 versions of the post-shaded per-sheet kernels (src/kernels.h),
 * 16 pixels a step; same arithmetic as simd/shade-avx2.c and therefore
 * bit-identical to the scalar reference in src/kernels.c. */
#include "kernels.h"

#include <float.h>
#include <immintrin.h>
#include <string.h>

/* lanes of component c in interleaved vector k are M[(c - k + 3) % 3] */
#define M0 0x9249
#define M1 0x2492
#define M2 0x4924

static inline __m512 tab_coord16(__m512 v, __m512d vmin, __m512d scale)
{
    __m512d lo = _mm512_cvtps_pd(_mm512_castps512_ps256(v));
    __m512d hi = _mm512_cvtps_pd(_mm512_extractf32x8_ps(v, 1));
    lo = _mm512_mul_pd(_mm512_sub_pd(lo, vmin), scale);
    hi = _mm512_mul_pd(_mm512_sub_pd(hi, vmin), scale);
    __m512 x = _mm512_insertf32x8(_mm512_castps256_ps512(_mm512_cvtpd_ps(lo)), _mm512_cvtpd_ps(hi), 1);
    return _mm512_maskz_mov_ps(_mm512_cmp_ps_mask(x, _mm512_setzero_ps(), _CMP_GT_OQ), x); /* NaN -> 0 */
}

static inline void store3(float *p, __m512 x, __m512 y, __m512 z)
{
    const __m512i i0 = _mm512_setr_epi32(0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3, 4, 4, 4, 5);
    const __m512i i1 = _mm512_setr_epi32(5, 5, 6, 6, 6, 7, 7, 7, 8, 8, 8, 9, 9, 9, 10, 10);
    const __m512i i2 = _mm512_setr_epi32(10, 11, 11, 11, 12, 12, 12, 13, 13, 13, 14, 14, 14, 15, 15, 15);
    __m512 o0 = _mm512_permutexvar_ps(i0, x);
    o0 = _mm512_mask_permutexvar_ps(o0, M1, i0, y);
    o0 = _mm512_mask_permutexvar_ps(o0, M2, i0, z);
    __m512 o1 = _mm512_permutexvar_ps(i1, x);
    o1 = _mm512_mask_permutexvar_ps(o1, M0, i1, y);
    o1 = _mm512_mask_permutexvar_ps(o1, M1, i1, z);
    __m512 o2 = _mm512_permutexvar_ps(i2, x);
    o2 = _mm512_mask_permutexvar_ps(o2, M2, i2, y);
    o2 = _mm512_mask_permutexvar_ps(o2, M0, i2, z);
    _mm512_storeu_ps(p, o0);
    _mm512_storeu_ps(p + 16, o1);
    _mm512_storeu_ps(p + 32, o2);
}

static inline void load3(const float *p, __m512 *x, __m512 *y, __m512 *z)
{
    __m512 o0 = _mm512_loadu_ps(p), o1 = _mm512_loadu_ps(p + 16), o2 = _mm512_loadu_ps(p + 32);
    __m512 bx = _mm512_mask_mov_ps(_mm512_mask_mov_ps(o0, M2, o1), M1, o2);
    __m512 by = _mm512_mask_mov_ps(_mm512_mask_mov_ps(o0, M0, o1), M2, o2);
    __m512 bz = _mm512_mask_mov_ps(_mm512_mask_mov_ps(o0, M1, o1), M0, o2);
    *x = _mm512_permutexvar_ps(_mm512_setr_epi32(0, 3, 6, 9, 12, 15, 2, 5, 8, 11, 14, 1, 4, 7, 10, 13), bx);
    *y = _mm512_permutexvar_ps(_mm512_setr_epi32(1, 4, 7, 10, 13, 0, 3, 6, 9, 12, 15, 2, 5, 8, 11, 14), by);
    *z = _mm512_permutexvar_ps(_mm512_setr_epi32(2, 5, 8, 11, 14, 1, 4, 7, 10, 13, 0, 3, 6, 9, 12, 15), bz);
}

/* 16 pixels, or the first `in` lanes of them (loads and stores masked:
 * no access past the span) */
static inline void classify16(float *alpha, float *g, const float *q, const float *qp, const float *qn,
                              ptrdiff_t stride, __mmask16 in, const vs_shade_tabs *T)
{
    const __m512d vmin = _mm512_set1_pd(T->vmin), scale = _mm512_set1_pd(T->scale);
    const __m512 top_x = _mm512_set1_ps((float)(VS_KTAB - 1)), top_a = _mm512_set1_ps(T->alpha[VS_KTAB - 1]);
    const __m512 half = _mm512_set1_ps(0.5f), two_slab = _mm512_set1_ps(T->two_slab);
    const float *tab = T->alpha;
    __m512 x = tab_coord16(_mm512_maskz_loadu_ps(in, q), vmin, scale);
    __mmask16 top = _mm512_cmp_ps_mask(x, top_x, _CMP_GE_OQ);
    x = _mm512_maskz_mov_ps((__mmask16)~top, x); /* index 0 where the table's end is used */
    __m512i j = _mm512_cvttps_epi32(x);
    __m512 f = _mm512_sub_ps(x, _mm512_cvtepi32_ps(j));
    __m512 t0 = _mm512_i32gather_ps(j, tab, 4), t1 = _mm512_i32gather_ps(j, tab + 1, 4);
    __m512 a = _mm512_add_ps(t0, _mm512_mul_ps(f, _mm512_sub_ps(t1, t0)));
    _mm512_mask_storeu_ps(alpha, in, _mm512_mask_mov_ps(a, top, top_a));
    __m512 gx = _mm512_mul_ps(half, _mm512_sub_ps(_mm512_maskz_loadu_ps(in, q + 1), _mm512_maskz_loadu_ps(in, q - 1)));
    __m512 gy = _mm512_mul_ps(half, _mm512_sub_ps(_mm512_maskz_loadu_ps(in, q + stride),
                                                  _mm512_maskz_loadu_ps(in, q - stride)));
    __m512 gz = _mm512_div_ps(_mm512_sub_ps(_mm512_maskz_loadu_ps(in, qn), _mm512_maskz_loadu_ps(in, qp)), two_slab);
    if (in == 0xffff) {
        store3(g, gx, gy, gz);
    } else {
        int nf = 3 * __builtin_popcount(in); /* in is a prefix mask */
        float tmp[48];
        store3(tmp, gx, gy, gz);
        __mmask16 m0 = (__mmask16)(nf >= 16 ? 0xffff : (1u << nf) - 1);
        __mmask16 m1 = (__mmask16)(nf >= 32 ? 0xffff : nf <= 16 ? 0 : (1u << (nf - 16)) - 1);
        __mmask16 m2 = (__mmask16)(nf <= 32 ? 0 : (1u << (nf - 32)) - 1);
        _mm512_mask_storeu_ps(g, m0, _mm512_loadu_ps(tmp));
        _mm512_mask_storeu_ps(g + 16, m1, _mm512_loadu_ps(tmp + 16));
        _mm512_mask_storeu_ps(g + 32, m2, _mm512_loadu_ps(tmp + 32));
    }
}

void vs_classify_cd_avx512(float *alpha, float *g, const float *q, const float *qp, const float *qn,
                           ptrdiff_t stride, int n, const vs_shade_tabs *T)
{
    int i = 0;
    for (; i + 16 <= n; i += 16) classify16(alpha + i, g + 3 * i, q + i, qp + i, qn + i, stride, 0xffff, T);
    if (i < n)
        classify16(alpha + i, g + 3 * i, q + i, qp + i, qn + i, stride, (__mmask16)((1u << (n - i)) - 1), T);
}

/* Shading of 16 pixels: gradients (x, y, z) and densities in, colours out
 * (vs_shade_lut_eval and the colour table, as the scalar reference). */
typedef struct shade_consts {
    __m512 ppm, zpm;
    __m512i cnl;
    __m512d vmin, scale;
    const vs_shade_tabs *T;
} shade_consts;

static inline void shade16(const shade_consts *K, __mmask16 lm, __m512 g0x, __m512 g0y, __m512 g0z, __m512 val,
                           __m512 out[3])
{
    const vs_shade_tabs *T = K->T;
    const __m512 fmax = _mm512_set1_ps(FLT_MAX), tiny = _mm512_set1_ps(1e-30f), k127 = _mm512_set1_ps(127.0f);
    const __m512i lo16 = _mm512_set1_epi32(0xffff), lo8 = _mm512_set1_epi32(0xff);
    const __m512 top_x = _mm512_set1_ps((float)(VS_KTAB - 1));
    __m512 gx = _mm512_mul_ps(g0x, K->ppm), gy = _mm512_mul_ps(g0y, K->ppm), gz = _mm512_mul_ps(g0z, K->zpm);
    __m512 ax = _mm512_abs_ps(gx), ay = _mm512_abs_ps(gy), az = _mm512_abs_ps(gz);
    __m512 m = _mm512_max_ps(_mm512_max_ps(ax, ay), az); /* NaN lanes are cleared below */
    __mmask16 ok = _mm512_cmp_ps_mask(ax, fmax, _CMP_LE_OQ) & _mm512_cmp_ps_mask(ay, fmax, _CMP_LE_OQ) &
                   _mm512_cmp_ps_mask(az, fmax, _CMP_LE_OQ) & _mm512_cmp_ps_mask(m, tiny, _CMP_GE_OQ);
    __m512 k = _mm512_div_ps(k127, _mm512_mask_mov_ps(k127, ok, m));
    __m512i ix = _mm512_maskz_cvtps_epi32(ok, _mm512_mul_ps(gx, k));
    __m512i iy = _mm512_maskz_cvtps_epi32(ok, _mm512_mul_ps(gy, k));
    __m512i iz = _mm512_maskz_cvtps_epi32(ok, _mm512_mul_ps(gz, k));
    __mmask16 allz = _mm512_testn_epi32_mask(_mm512_or_si512(_mm512_or_si512(ix, iy), iz), _mm512_set1_epi32(-1));
    iz = _mm512_mask_mov_epi32(iz, allz, _mm512_set1_epi32(-127)); /* zero gradient: faces the eye */
    __m512i lr = _mm512_add_epi32(_mm512_mullo_epi32(iy, _mm512_set1_epi32(255)),
                                  _mm512_add_epi32(ix, _mm512_set1_epi32(127 * 255 + 127)));
    /* masked-off lanes load nothing (their indices are valid all the same) */
    const __m512i zi = _mm512_setzero_si512();
    __m512i li = _mm512_and_si512(_mm512_mask_i32gather_epi32(zi, lm, lr, T->lambda_bin, 2), lo16);
    __m512i r = _mm512_and_si512(_mm512_mask_i32gather_epi32(zi, lm, lr, T->radius, 1), lo8);
    __m512i pidx = _mm512_add_epi32(_mm512_mullo_epi32(iz, _mm512_set1_epi32(181)),
                                    _mm512_add_epi32(r, _mm512_set1_epi32(127 * 181)));
    __m512i pi = _mm512_and_si512(_mm512_mask_i32gather_epi32(zi, lm, pidx, T->phi_bin, 2), lo16);
    __m512i di = _mm512_add_epi32(_mm512_mullo_epi32(pi, K->cnl), li);
    const __m512 zf = _mm512_setzero_ps();
    __m512 d = _mm512_mask_i32gather_ps(zf, lm, di, T->diffuse, 4);
    __m512 sp = _mm512_mask_i32gather_ps(zf, lm, di, T->specular, 4);
    __m512 x = _mm512_min_ps(tab_coord16(val, K->vmin, K->scale), top_x);
    __m512i j = _mm512_cvttps_epi32(x);
    __mmask16 top = _mm512_cmp_ps_mask(x, top_x, _CMP_GE_OQ);
    __m512 f = _mm512_sub_ps(x, _mm512_cvtepi32_ps(j));
    __m512i j3 = _mm512_mullo_epi32(_mm512_min_epi32(j, _mm512_set1_epi32(VS_KTAB - 2)), _mm512_set1_epi32(3));
    const float *col = T->color;
    for (int ch = 0; ch < 3; ch++) {
        __m512 c0 = _mm512_mask_i32gather_ps(zf, lm, j3, col + ch, 4);
        __m512 c1 = _mm512_mask_i32gather_ps(zf, lm, j3, col + 3 + ch, 4);
        __m512 rgb = _mm512_add_ps(c0, _mm512_mul_ps(f, _mm512_sub_ps(c1, c0)));
        rgb = _mm512_mask_mov_ps(rgb, top, _mm512_set1_ps(col[3 * (VS_KTAB - 1) + ch]));
        out[ch] = _mm512_add_ps(_mm512_mul_ps(rgb, d), sp);
    }
}

/* Pixels listed in idx[0..cnt), cnt <= 16: gathered, shaded, scattered. */
static inline void shade_list(const shade_consts *K, float *g, const float *v, int vstride, const int *idx, int cnt)
{
    __mmask16 lm = (__mmask16)(cnt >= 16 ? 0xffff : (1u << cnt) - 1);
    __m512i p = _mm512_maskz_loadu_epi32(lm, idx);
    __m512i p3 = _mm512_add_epi32(p, _mm512_add_epi32(p, p));
    const __m512 zf = _mm512_setzero_ps();
    __m512 g0x = _mm512_mask_i32gather_ps(zf, lm, p3, g, 4);
    __m512 g0y = _mm512_mask_i32gather_ps(zf, lm, p3, g + 1, 4);
    __m512 g0z = _mm512_mask_i32gather_ps(zf, lm, p3, g + 2, 4);
    __m512i pv = vstride == 1 ? p : _mm512_mullo_epi32(p, _mm512_set1_epi32(vstride));
    __m512 val = _mm512_mask_i32gather_ps(zf, lm, pv, v, 4);
    __m512 out[3];
    shade16(K, lm, g0x, g0y, g0z, val, out);
    _mm512_mask_i32scatter_ps(g, lm, p3, out[0], 4);
    _mm512_mask_i32scatter_ps(g + 1, lm, p3, out[1], 4);
    _mm512_mask_i32scatter_ps(g + 2, lm, p3, out[2], 4);
}

/* Runs of 16 visible pixels are shaded in place; the visible pixels of
 * other runs are compacted into a list (vpcompressd) and shaded 16 at a
 * time, so gathers are spent on visible pixels only (about a quarter of a
 * span on the head). */
void vs_shade_lut_avx512(float *g, const float *alpha, const float *v, int vstride, int n, const vs_shade_tabs *T)
{
    const shade_consts K = {_mm512_set1_ps(T->ppm), _mm512_set1_ps(T->zpm), _mm512_set1_epi32(T->nl),
                            _mm512_set1_pd(T->vmin), _mm512_set1_pd(T->scale), T};
    const __m512 zero = _mm512_setzero_ps();
    const __m512i iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    const __m512i vidx = _mm512_mullo_epi32(iota, _mm512_set1_epi32(vstride));
    int idx[32], cnt = 0;
    for (int i = 0; i < n; i += 16) {
        __mmask16 in = (__mmask16)(n - i >= 16 ? 0xffff : (1u << (n - i)) - 1);
        __mmask16 live = _mm512_mask_cmp_ps_mask(in, _mm512_maskz_loadu_ps(in, alpha + i), zero, _CMP_GT_OQ);
        if (live == 0xffff) {
            __m512 g0x, g0y, g0z, out[3];
            load3(g + 3 * i, &g0x, &g0y, &g0z);
            __m512 val = vstride == 1 ? _mm512_loadu_ps(v + i) : _mm512_i32gather_ps(vidx, v + (ptrdiff_t)i * vstride, 4);
            shade16(&K, 0xffff, g0x, g0y, g0z, val, out);
            store3(g + 3 * i, out[0], out[1], out[2]);
            continue;
        }
        if (!live) continue;
        _mm512_mask_compressstoreu_epi32(idx + cnt, live, _mm512_add_epi32(iota, _mm512_set1_epi32(i)));
        cnt += __builtin_popcount(live);
        if (cnt >= 16) {
            shade_list(&K, g, v, vstride, idx, 16);
            cnt -= 16;
            memcpy(idx, idx + 16, (size_t)cnt * sizeof *idx);
        }
    }
    if (cnt > 0) shade_list(&K, g, v, vstride, idx, cnt);
}
