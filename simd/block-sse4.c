/* Footprint blocks into a sheet, SSE4.1: each 8-float block vector as two
 * 4-float halves, multiply then add exactly as the scalar reference
 * (src/kernels.c; no FMA, see src/kernels.h). */
#include "kernels.h"

#include <smmintrin.h>

void vs_splat_block_sse4(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                         const float w8[8])
{
    const __m128 wa = _mm_loadu_ps(w8), wb = _mm_loadu_ps(w8 + 4);
    for (int r = 0; r < rows; r++) {
        float *d = dst + r * ds;
        const float *b = blk + r * bs;
        for (int v = 0; v < nvec; v++) {
            _mm_storeu_ps(d + 8 * v, _mm_add_ps(_mm_loadu_ps(d + 8 * v), _mm_mul_ps(wa, _mm_loadu_ps(b + 8 * v))));
            _mm_storeu_ps(d + 8 * v + 4,
                          _mm_add_ps(_mm_loadu_ps(d + 8 * v + 4), _mm_mul_ps(wb, _mm_loadu_ps(b + 8 * v + 4))));
        }
    }
}
