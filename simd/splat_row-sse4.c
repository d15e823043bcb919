/* Footprint row accumulation for interleaved channels, SSE4.1: one RGBA (or
 * density + gradient) pixel per vector, one multiply and one add per element
 * exactly as the scalar reference (see kernels.h).  Single-channel rows
 * and compositing have no SSE version: GCC auto-vectorizes the scalar row
 * loop as well, and a per-pixel SSE composite measured slower (docs/PERFORMANCE.md). */
#include "kernels.h"

#include <smmintrin.h>

void vs_splat_row4_sse4(float *row4, const float *ex, const float w[4], int n)
{
    __m128 vw = _mm_loadu_ps(w);
    for (int i = 0; i < n; i++) {
        __m128 h = _mm_set1_ps(ex[i]);
        _mm_storeu_ps(row4 + 4 * i, _mm_add_ps(_mm_loadu_ps(row4 + 4 * i), _mm_mul_ps(vw, h)));
    }
}
