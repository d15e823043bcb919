/* Footprint blocks into a sheet, AVX2: one block vector per register,
 * multiply then add exactly as the scalar reference (src/kernels.c; no FMA,
 * see src/kernels.h).  A one-vector row (the common 8-pixel density
 * footprint) is the unrolled special case. */
#include "kernels.h"

#include <immintrin.h>

void vs_splat_block_avx2(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                         const float w8[8])
{
    const __m256 w = _mm256_loadu_ps(w8);
    if (nvec == 1) {
        for (int r = 0; r < rows; r++) {
            float *d = dst + r * ds;
            _mm256_storeu_ps(d, _mm256_add_ps(_mm256_loadu_ps(d), _mm256_mul_ps(w, _mm256_loadu_ps(blk + r * bs))));
        }
        return;
    }
    for (int r = 0; r < rows; r++) {
        float *d = dst + r * ds;
        const float *b = blk + r * bs;
        for (int v = 0; v < nvec; v++)
            _mm256_storeu_ps(d + 8 * v,
                             _mm256_add_ps(_mm256_loadu_ps(d + 8 * v), _mm256_mul_ps(w, _mm256_loadu_ps(b + 8 * v))));
    }
}
