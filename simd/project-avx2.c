/* Voxel transform and binning, AVX2: eight voxels a step, multiply then add
 * in the scalar reference's order (scalar.c; no FMA, kernels.h),
 * the kept lanes written out in order from the comparison mask. */
#include "kernels.h"

#include <immintrin.h>

int vs_project_brick_avx2(const uint16_t *vox, int n, const vs_project_in *P, uint16_t *keep, float *xyz)
{
    __m256 m[3][3], b[3];
    for (int r = 0; r < 3; r++) {
        b[r] = _mm256_set1_ps(P->base[r]);
        for (int a = 0; a < 3; a++) m[r][a] = _mm256_set1_ps(P->m[r][a]);
    }
    const __m256 px = _mm256_set1_ps(P->px), py = _mm256_set1_ps(P->py);
    const __m256 bx0 = _mm256_set1_ps(P->bx0), bx1 = _mm256_set1_ps(P->bx1);
    const __m256 by0 = _mm256_set1_ps(P->by0), by1 = _mm256_set1_ps(P->by1);
    const __m256i seven = _mm256_set1_epi32(7);
    int q = 0, i = 0;
    for (; i + 8 <= n; i += 8) {
        const __m256i v = _mm256_cvtepu16_epi32(_mm_loadu_si128((const __m128i *)(vox + i)));
        const __m256 di = _mm256_cvtepi32_ps(_mm256_and_si256(v, seven));
        const __m256 dj = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(v, 3), seven));
        const __m256 dk = _mm256_cvtepi32_ps(_mm256_srli_epi32(v, 6));
        __m256 c[3];
        for (int r = 0; r < 3; r++)
            c[r] = _mm256_add_ps(
                _mm256_add_ps(_mm256_add_ps(b[r], _mm256_mul_ps(m[r][0], di)), _mm256_mul_ps(m[r][1], dj)),
                _mm256_mul_ps(m[r][2], dk));
        /* dropped where any of the four reference comparisons holds (ordered:
         * like C's <, false for NaN) */
        __m256 drop = _mm256_cmp_ps(_mm256_add_ps(c[0], px), bx0, _CMP_LT_OQ);
        drop = _mm256_or_ps(drop, _mm256_cmp_ps(_mm256_sub_ps(c[0], px), bx1, _CMP_GT_OQ));
        drop = _mm256_or_ps(drop, _mm256_cmp_ps(_mm256_add_ps(c[1], py), by0, _CMP_LT_OQ));
        drop = _mm256_or_ps(drop, _mm256_cmp_ps(_mm256_sub_ps(c[1], py), by1, _CMP_GT_OQ));
        unsigned kept = ~(unsigned)_mm256_movemask_ps(drop) & 0xffu;
        if (!kept) continue;
        float t[3][8];
        for (int r = 0; r < 3; r++) _mm256_storeu_ps(t[r], c[r]);
        while (kept) {
            const int l = __builtin_ctz(kept);
            kept &= kept - 1;
            keep[q] = (uint16_t)(i + l);
            xyz[3 * q] = t[0][l];
            xyz[3 * q + 1] = t[1][l];
            xyz[3 * q + 2] = t[2][l];
            q++;
        }
    }
    if (i < n) { /* the tail: the reference, its indices made absolute */
        const int t = vs_project_brick_scalar(vox + i, n - i, P, keep + q, xyz + 3 * q);
        for (int k = q; k < q + t; k++) keep[k] = (uint16_t)(keep[k] + i);
        q += t;
    }
    return q;
}
