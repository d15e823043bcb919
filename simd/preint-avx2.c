/* AVX2 pre-integrated opacity (kernels.h preint_alpha), 8 segments a
 * step, bit-identical to scalar.c: the cells as vs_preint_cell (clamped
 * with max and min, so NaN and infinity take the table's ends), the four
 * corners of each half by gathers, the same multiplies and adds in the
 * same order; eight segments below the table's transparent block
 * (vs_preint_tabs.zero_x) are 0 without look-ups.  The tail goes to the
 * scalar reference. */
#include "kernels.h"

#include <immintrin.h>

/* One end of 8 segments: its table coordinate x = (v - vmin) scale, and
 * vs_preint_cell's cell and fraction (clamped with max and min: max
 * returns its second operand when the first is NaN, 0 as the reference's
 * !(x > 0)).  Each end is found once, the middle serving both halves; the
 * cells only once the segments are known not to be transparent. */
typedef struct end8 {
    __m256 x, frac;
    __m256i cell;
} end8;

static inline end8 end_at(const vs_preint_tabs *P, __m256 v)
{
    end8 e = {_mm256_mul_ps(_mm256_sub_ps(v, _mm256_set1_ps(P->vmin)), _mm256_set1_ps(P->scale)),
              _mm256_setzero_ps(), _mm256_setzero_si256()};
    return e;
}

static inline void end_cell(const vs_preint_tabs *P, end8 *e)
{
    const float topf = (float)(P->n - 2);
    const __m256 x = _mm256_max_ps(e->x, _mm256_setzero_ps());
    e->cell = _mm256_cvttps_epi32(_mm256_min_ps(x, _mm256_set1_ps(topf)));
    const __m256 in = _mm256_cmp_ps(x, _mm256_set1_ps(topf + 1.0f), _CMP_LT_OQ);
    e->frac = _mm256_blendv_ps(_mm256_set1_ps(1.0f), _mm256_sub_ps(x, _mm256_cvtepi32_ps(e->cell)), in);
}

/* the table's opacity between ends f and b */
static inline __m256 alpha8(const vs_preint_tabs *P, const end8 *f, const end8 *b)
{
    /* entry (i, j)'s opacity: tab[4 (i n + j)] */
    const __m256i ij = _mm256_add_epi32(_mm256_mullo_epi32(f->cell, _mm256_set1_epi32(P->n)), b->cell);
    const __m256i e = _mm256_slli_epi32(ij, 2);
    const float *t = P->tab;
    const __m256 fx = f->frac, fy = b->frac;
    const __m256 e00 = _mm256_i32gather_ps(t, e, 4), e01 = _mm256_i32gather_ps(t + 4, e, 4);
    const __m256 e10 = _mm256_i32gather_ps(t + 4 * P->n, e, 4), e11 = _mm256_i32gather_ps(t + 4 * P->n + 4, e, 4);
    const __m256 u = _mm256_add_ps(e00, _mm256_mul_ps(fy, _mm256_sub_ps(e01, e00)));
    const __m256 v = _mm256_add_ps(e10, _mm256_mul_ps(fy, _mm256_sub_ps(e11, e10)));
    return _mm256_add_ps(u, _mm256_mul_ps(fx, _mm256_sub_ps(v, u)));
}

void vs_preint_alpha_avx2(float *alpha, const float *f, const float *m, const float *b, int n,
                          const vs_preint_tabs *P)
{
    const __m256 one = _mm256_set1_ps(1.0f), zx = _mm256_set1_ps(P->zero_x);
    const int block = P->zero_x > 0.0f; /* else values below the table read entry 0, not 0 */
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        end8 ef = end_at(P, _mm256_loadu_ps(f + i)), em = end_at(P, _mm256_loadu_ps(m + i)),
             eb = end_at(P, _mm256_loadu_ps(b + i));
        /* all three ends below the transparent block: every corner the
         * reference reads is 0, and so is its result (NaN lanes fail the
         * test and take the look-ups) */
        const __m256 below = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(ef.x, zx, _CMP_LT_OQ),
                                                         _mm256_cmp_ps(em.x, zx, _CMP_LT_OQ)),
                                           _mm256_cmp_ps(eb.x, zx, _CMP_LT_OQ));
        if (block && _mm256_movemask_ps(below) == 0xff) {
            _mm256_storeu_ps(alpha + i, _mm256_setzero_ps());
            continue;
        }
        end_cell(P, &ef);
        end_cell(P, &em);
        end_cell(P, &eb);
        const __m256 a1 = alpha8(P, &ef, &em), a2 = alpha8(P, &em, &eb);
        _mm256_storeu_ps(alpha + i, _mm256_add_ps(a1, _mm256_mul_ps(_mm256_sub_ps(one, a1), a2)));
    }
    if (i < n) vs_preint_alpha_scalar(alpha + i, f + i, m + i, b + i, n - i, P);
}
