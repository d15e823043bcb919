/* Footprint row accumulation for interleaved channels, AVX2: two pixels per
 * vector, multiply then add as the scalar reference (no FMA: see
 * kernels.h). */
#include "kernels.h"

#include <immintrin.h>

void vs_splat_row4_avx2(float *row4, const float *ex, const float w[4], int n)
{
    __m256 vw = _mm256_broadcast_ps((const __m128 *)w);
    int i = 0;
    for (; i + 2 <= n; i += 2) {
        __m256 h = _mm256_set_m128(_mm_set1_ps(ex[i + 1]), _mm_set1_ps(ex[i]));
        _mm256_storeu_ps(row4 + 4 * i, _mm256_add_ps(_mm256_loadu_ps(row4 + 4 * i), _mm256_mul_ps(vw, h)));
    }
    for (; i < n; i++) {
        __m128 h = _mm_set1_ps(ex[i]);
        _mm_storeu_ps(row4 + 4 * i, _mm_add_ps(_mm_loadu_ps(row4 + 4 * i), _mm_mul_ps(_mm_loadu_ps(w), h)));
    }
}
