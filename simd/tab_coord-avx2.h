/* The table coordinate of eight values as the scalar reference's
 * tab_coord (scalar.c) computes it, in double: shared by the AVX2
 * classification and shading kernels (include only from -avx2 files). */
#ifndef VS_TAB_COORD_AVX2_H
#define VS_TAB_COORD_AVX2_H

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

#endif
