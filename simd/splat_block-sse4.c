/* Footprint blocks into a sheet, SSE4.1: each 8-float block vector as two
 * 4-float halves, multiply then add exactly as the scalar reference
 * (scalar.c; no FMA, see kernels.h). */
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

/* One pixel a register (h, h dx, h dy broadcast by shuffles), in the scalar
 * reference's order. */
void vs_splat_block_mix_sse4(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                             const float m[12])
{
    const __m128 m0 = _mm_setr_ps(m[0], m[3], m[6], m[9]);
    const __m128 m1 = _mm_setr_ps(m[1], m[4], m[7], m[10]);
    const __m128 m2 = _mm_setr_ps(m[2], m[5], m[8], m[11]);
    for (int r = 0; r < rows; r++) {
        float *d = dst + r * ds;
        const float *b = blk + r * bs;
        for (int p = 0; p < 2 * nvec; p++) {
            const __m128 x = _mm_loadu_ps(b + 4 * p);
            const __m128 h = _mm_shuffle_ps(x, x, 0x00), hx = _mm_shuffle_ps(x, x, 0x55),
                         hy = _mm_shuffle_ps(x, x, 0xAA);
            const __m128 t = _mm_add_ps(_mm_add_ps(_mm_mul_ps(m0, h), _mm_mul_ps(m1, hx)), _mm_mul_ps(m2, hy));
            _mm_storeu_ps(d + 4 * p, _mm_add_ps(_mm_loadu_ps(d + 4 * p), t));
        }
    }
}
