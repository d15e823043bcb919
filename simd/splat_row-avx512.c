/* Footprint row accumulation for interleaved channels, AVX-512F: four RGBA
 * pixels per vector, multiply then add as the scalar reference.  Not run on
 * the project's machines (no AVX-512): tests skip it there. */
#include "kernels.h"

#include <immintrin.h>

void vs_splat_row4_avx512(float *row4, const float *ex, const float w[4], int n)
{
    __m512 vw = _mm512_broadcast_f32x4(_mm_loadu_ps(w));
    const __m512i spread = _mm512_set_epi32(3, 3, 3, 3, 2, 2, 2, 2, 1, 1, 1, 1, 0, 0, 0, 0);
    int i = 0;
    for (; i + 4 <= n; i += 4) {
        __m512 h = _mm512_permutexvar_ps(spread, _mm512_castps128_ps512(_mm_loadu_ps(ex + i)));
        _mm512_storeu_ps(row4 + 4 * i, _mm512_add_ps(_mm512_loadu_ps(row4 + 4 * i), _mm512_mul_ps(vw, h)));
    }
    for (; i < n; i++) {
        __m128 h = _mm_set1_ps(ex[i]);
        _mm_storeu_ps(row4 + 4 * i, _mm_add_ps(_mm_loadu_ps(row4 + 4 * i), _mm_mul_ps(_mm_loadu_ps(w), h)));
    }
}
