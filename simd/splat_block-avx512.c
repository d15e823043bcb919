/* Footprint blocks into a sheet, AVX-512F: two block vectors per register,
 * an odd last one in a 256-bit register; multiply then add exactly as the
 * scalar reference (scalar.c; no FMA, see kernels.h).  A one-vector
 * row stays in a 256-bit register. */
#include "kernels.h"

#include <immintrin.h>

void vs_splat_block_avx512(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                           const float w8[8])
{
    const __m256 w = _mm256_loadu_ps(w8);
    if (nvec == 1) { /* the common 8-pixel density footprint: one ymm a row */
        for (int r = 0; r < rows; r++) {
            float *d = dst + r * ds;
            _mm256_storeu_ps(d, _mm256_add_ps(_mm256_loadu_ps(d), _mm256_mul_ps(w, _mm256_loadu_ps(blk + r * bs))));
        }
        return;
    }
    const __m512 w2 = _mm512_insertf32x8(_mm512_castps256_ps512(w), w, 1);
    for (int r = 0; r < rows; r++) {
        float *d = dst + r * ds;
        const float *b = blk + r * bs;
        int v = 0;
        for (; v + 2 <= nvec; v += 2)
            _mm512_storeu_ps(d + 8 * v,
                             _mm512_add_ps(_mm512_loadu_ps(d + 8 * v), _mm512_mul_ps(w2, _mm512_loadu_ps(b + 8 * v))));
        if (v < nvec)
            _mm256_storeu_ps(d + 8 * v,
                             _mm256_add_ps(_mm256_loadu_ps(d + 8 * v), _mm256_mul_ps(w, _mm256_loadu_ps(b + 8 * v))));
    }
}
