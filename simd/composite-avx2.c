/* AVX2 front-to-back compositing (kernels.h `composite`), 8 pixels a
 * step, bit-identical to the scalar reference: the accumulators (4 floats a
 * pixel) are transposed to one vector per channel, the colours (3 a pixel)
 * de-interleaved, and pixels with alpha <= 0 (or NaN) keep their
 * accumulators bit for bit. Vectors without a visible pixel are skipped
 * without touching the accumulators. */
#include "kernels.h"

#include <immintrin.h>

int vs_composite_avx2(float *acc, const float *alpha, const float *rgb, int n, float thr)
{
    /* the transposes leave pixels in the order 0 2 4 6 1 3 5 7 */
    const __m256i ord = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
    const __m256 one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps(), vthr = _mm256_set1_ps(thr);
    int crossed = 0, i = 0;
    for (; i + 8 <= n; i += 8) {
        __m256 a = _mm256_loadu_ps(alpha + i);
        __m256 live = _mm256_cmp_ps(a, zero, _CMP_GT_OQ);
        if (_mm256_movemask_ps(live) == 0) continue;
        a = _mm256_permutevar8x32_ps(a, ord);
        live = _mm256_permutevar8x32_ps(live, ord);
        float *p = acc + 4 * i;
        __m256 r0 = _mm256_loadu_ps(p), r1 = _mm256_loadu_ps(p + 8), r2 = _mm256_loadu_ps(p + 16),
               r3 = _mm256_loadu_ps(p + 24);
        __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
        __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
        __m256 R = _mm256_shuffle_ps(t0, t2, 0x44), G = _mm256_shuffle_ps(t0, t2, 0xee);
        __m256 B = _mm256_shuffle_ps(t1, t3, 0x44), A = _mm256_shuffle_ps(t1, t3, 0xee);
        /* colours, de-interleaved straight into the same pixel order */
        const float *c = rgb + 3 * i;
        __m256 o0 = _mm256_loadu_ps(c), o1 = _mm256_loadu_ps(c + 8), o2 = _mm256_loadu_ps(c + 16);
        __m256 cr = _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(o0, o1, 0x92), o2, 0x24),
                                             _mm256_setr_epi32(0, 6, 4, 2, 3, 1, 7, 5));
        __m256 cg = _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(o0, o1, 0x24), o2, 0x49),
                                             _mm256_setr_epi32(1, 7, 5, 3, 4, 2, 0, 6));
        __m256 cb = _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(o0, o1, 0x49), o2, 0x92),
                                             _mm256_setr_epi32(2, 0, 6, 4, 5, 3, 1, 7));
        __m256 w = _mm256_mul_ps(_mm256_sub_ps(one, A), a);
        __m256 nR = _mm256_add_ps(R, _mm256_mul_ps(w, cr));
        __m256 nG = _mm256_add_ps(G, _mm256_mul_ps(w, cg));
        __m256 nB = _mm256_add_ps(B, _mm256_mul_ps(w, cb));
        __m256 nA = _mm256_min_ps(one, _mm256_add_ps(A, w)); /* after > 1 ? 1 : after, NaN stays */
        __m256 cross = _mm256_and_ps(live, _mm256_and_ps(_mm256_cmp_ps(A, vthr, _CMP_LT_OQ),
                                                         _mm256_cmp_ps(nA, vthr, _CMP_GE_OQ)));
        crossed += __builtin_popcount((unsigned)_mm256_movemask_ps(cross));
        R = _mm256_blendv_ps(R, nR, live);
        G = _mm256_blendv_ps(G, nG, live);
        B = _mm256_blendv_ps(B, nB, live);
        A = _mm256_blendv_ps(A, nA, live);
        t0 = _mm256_unpacklo_ps(R, G);
        t1 = _mm256_unpackhi_ps(R, G);
        t2 = _mm256_unpacklo_ps(B, A);
        t3 = _mm256_unpackhi_ps(B, A);
        _mm256_storeu_ps(p, _mm256_shuffle_ps(t0, t2, 0x44));
        _mm256_storeu_ps(p + 8, _mm256_shuffle_ps(t0, t2, 0xee));
        _mm256_storeu_ps(p + 16, _mm256_shuffle_ps(t1, t3, 0x44));
        _mm256_storeu_ps(p + 24, _mm256_shuffle_ps(t1, t3, 0xee));
    }
    if (i < n) crossed += vs_composite_scalar(acc + 4 * i, alpha + i, rgb + 3 * i, n - i, thr);
    return crossed;
}
