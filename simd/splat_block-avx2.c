/* Footprint blocks into a sheet, AVX2: splat_block, splat_block_mix, and
 * splat_rows_mix (the mix of splat_block_mix on rows built in registers
 * instead of a block in memory).  One block vector per register, multiply
 * then add exactly as the scalar reference (scalar.c; no FMA, see
 * kernels.h).  A one-vector row (the common 8-pixel density footprint) is
 * the unrolled special case of splat_block. */
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

/* Two pixels a register: each 128-bit lane is one pixel, so in-lane
 * shuffles broadcast its h, h dx, h dy; products and sums in the scalar
 * reference's order. */
void vs_splat_block_mix_avx2(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                             const float m[12])
{
    const __m256 m0 = _mm256_setr_ps(m[0], m[3], m[6], m[9], m[0], m[3], m[6], m[9]);
    const __m256 m1 = _mm256_setr_ps(m[1], m[4], m[7], m[10], m[1], m[4], m[7], m[10]);
    const __m256 m2 = _mm256_setr_ps(m[2], m[5], m[8], m[11], m[2], m[5], m[8], m[11]);
    for (int r = 0; r < rows; r++) {
        float *d = dst + r * ds;
        const float *b = blk + r * bs;
        for (int v = 0; v < nvec; v++) {
            const __m256 x = _mm256_loadu_ps(b + 8 * v);
            const __m256 h = _mm256_shuffle_ps(x, x, 0x00), hx = _mm256_shuffle_ps(x, x, 0x55),
                         hy = _mm256_shuffle_ps(x, x, 0xAA);
            const __m256 t = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(m0, h), _mm256_mul_ps(m1, hx)),
                                           _mm256_mul_ps(m2, hy));
            _mm256_storeu_ps(d + 8 * v, _mm256_add_ps(_mm256_loadu_ps(d + 8 * v), t));
        }
    }
}

/* A gradient-splat section's rows built in registers and mixed as
 * splat_block_mix above mixes a block's: per 8-float vector of two pixels,
 * h, hx and hy spread over each pixel's four channels. */
void vs_splat_rows_mix_avx2(float *dst, ptrdiff_t ds, const float *cw, const float *rw, const float *dx,
                            const float *dy, int rows, int nvec, float thr, const float m[12])
{
    const __m256 t = _mm256_set1_ps(thr);
    const __m256 m0 = _mm256_setr_ps(m[0], m[3], m[6], m[9], m[0], m[3], m[6], m[9]);
    const __m256 m1 = _mm256_setr_ps(m[1], m[4], m[7], m[10], m[1], m[4], m[7], m[10]);
    const __m256 m2 = _mm256_setr_ps(m[2], m[5], m[8], m[11], m[2], m[5], m[8], m[11]);
    const __m256i spread[4] = {_mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1), _mm256_setr_epi32(2, 2, 2, 2, 3, 3, 3, 3),
                               _mm256_setr_epi32(4, 4, 4, 4, 5, 5, 5, 5), _mm256_setr_epi32(6, 6, 6, 6, 7, 7, 7, 7)};
    for (int r = 0; r < rows; r++) {
        const __m256 ry = _mm256_set1_ps(rw[r]), y8 = _mm256_set1_ps(dy[r]);
        float *d = dst + r * ds;
        for (int v = 0; v < nvec; v += 4) {
            __m256 h8 = _mm256_mul_ps(_mm256_loadu_ps(cw + 2 * v), ry);
            h8 = _mm256_and_ps(h8, _mm256_cmp_ps(h8, t, _CMP_GT_OQ));
            const __m256 x8 = _mm256_loadu_ps(dx + 2 * v);
            const int nq = nvec - v < 4 ? nvec - v : 4;
            for (int q = 0; q < nq; q++) {
                const __m256 h = _mm256_permutevar8x32_ps(h8, spread[q]);
                const __m256 hx = _mm256_mul_ps(h, _mm256_permutevar8x32_ps(x8, spread[q]));
                const __m256 hy = _mm256_mul_ps(h, y8);
                const __m256 a = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(m0, h), _mm256_mul_ps(m1, hx)),
                                               _mm256_mul_ps(m2, hy));
                float *p = d + 8 * (v + q);
                _mm256_storeu_ps(p, _mm256_add_ps(_mm256_loadu_ps(p), a));
            }
        }
    }
}
