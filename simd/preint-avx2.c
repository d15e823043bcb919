/* AVX2 pre-integrated opacity (kernels.h preint_alpha), 8 segments a
 * step, bit-identical to scalar.c: the cells as vs_preint_cell (clamped
 * with max and min, so NaN and infinity take the table's ends), the four
 * corners of each half by gathers, the same multiplies and adds in the
 * same order; eight segments below the table's transparent block
 * (vs_preint_tabs.zero_x) are 0 without look-ups.  The tail goes to the
 * scalar reference. */
#include "kernels.h"

#include <immintrin.h>

/* vs_preint_cell for 8 values: the cell, and the fraction in *frac */
static inline __m256i cell8(__m256 v, __m256 vmin, __m256 scale, __m256 top, __m256 top1, __m256 *frac)
{
    /* max returns its second operand when the first is NaN: 0, as the
     * reference's !(x > 0) */
    const __m256 x = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(v, vmin), scale), _mm256_setzero_ps());
    const __m256i i = _mm256_cvttps_epi32(_mm256_min_ps(x, top));
    const __m256 in = _mm256_cmp_ps(x, top1, _CMP_LT_OQ);
    *frac = _mm256_blendv_ps(_mm256_set1_ps(1.0f), _mm256_sub_ps(x, _mm256_cvtepi32_ps(i)), in);
    return i;
}

/* the table's opacity between f and b */
static inline __m256 alpha8(const vs_preint_tabs *P, __m256 f, __m256 b)
{
    const __m256 vmin = _mm256_set1_ps(P->vmin), scale = _mm256_set1_ps(P->scale);
    const float topf = (float)(P->n - 2);
    const __m256 top = _mm256_set1_ps(topf), top1 = _mm256_set1_ps(topf + 1.0f);
    __m256 fx, fy;
    const __m256i i = cell8(f, vmin, scale, top, top1, &fx), j = cell8(b, vmin, scale, top, top1, &fy);
    /* entry (i, j)'s opacity: tab[4 (i n + j)] */
    const __m256i e = _mm256_slli_epi32(_mm256_add_epi32(_mm256_mullo_epi32(i, _mm256_set1_epi32(P->n)), j), 2);
    const float *t = P->tab;
    const __m256 e00 = _mm256_i32gather_ps(t, e, 4), e01 = _mm256_i32gather_ps(t + 4, e, 4);
    const __m256 e10 = _mm256_i32gather_ps(t + 4 * P->n, e, 4), e11 = _mm256_i32gather_ps(t + 4 * P->n + 4, e, 4);
    const __m256 u = _mm256_add_ps(e00, _mm256_mul_ps(fy, _mm256_sub_ps(e01, e00)));
    const __m256 v = _mm256_add_ps(e10, _mm256_mul_ps(fy, _mm256_sub_ps(e11, e10)));
    return _mm256_add_ps(u, _mm256_mul_ps(fx, _mm256_sub_ps(v, u)));
}

void vs_preint_alpha_avx2(float *alpha, const float *f, const float *m, const float *b, int n,
                          const vs_preint_tabs *P)
{
    const __m256 one = _mm256_set1_ps(1.0f), vmin = _mm256_set1_ps(P->vmin), scale = _mm256_set1_ps(P->scale);
    const __m256 zx = _mm256_set1_ps(P->zero_x);
    const int skip = P->zero_x > 0.0f;
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        const __m256 mv = _mm256_loadu_ps(m + i);
        if (skip) {
            /* all three ends below the transparent block: every corner the
             * reference reads is 0, and so is its result (NaN lanes fail
             * the test and take the look-ups) */
#define BELOW(v) _mm256_cmp_ps(_mm256_mul_ps(_mm256_sub_ps((v), vmin), scale), zx, _CMP_LT_OQ)
            const __m256 in = _mm256_and_ps(_mm256_and_ps(BELOW(_mm256_loadu_ps(f + i)), BELOW(mv)),
                                            BELOW(_mm256_loadu_ps(b + i)));
#undef BELOW
            if (_mm256_movemask_ps(in) == 0xff) {
                _mm256_storeu_ps(alpha + i, _mm256_setzero_ps());
                continue;
            }
        }
        const __m256 a1 = alpha8(P, _mm256_loadu_ps(f + i), mv), a2 = alpha8(P, mv, _mm256_loadu_ps(b + i));
        _mm256_storeu_ps(alpha + i, _mm256_add_ps(a1, _mm256_mul_ps(_mm256_sub_ps(one, a1), a2)));
    }
    if (i < n) vs_preint_alpha_scalar(alpha + i, f + i, m + i, b + i, n - i, P);
}
