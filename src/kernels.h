/* The inner loops that SIMD code may replace, as a table of function
 * pointers chosen per frame (libjpeg-turbo style): filled with the scalar
 * reference in src/kernels.c first, then upgraded best ISA first by
 * simd/dispatch.c, capped by the settings and VSPLAT_ISA.
 *
 * Every kernel does one multiply and one add per element in the same order
 * as the scalar reference (no fused multiply-add), so each ISA gives
 * bit-identical results: images never depend on the machine, and a row's
 * split into vector body and tail (which depends on the tile) cannot change
 * a pixel. */
#ifndef VS_KERNELS_H
#define VS_KERNELS_H

#include "vsplat.h"

#include <stddef.h>

typedef struct vs_kernels {
    vs_isa isa; /* the ISA cap in force (what the stats report) */
    /* row[i] += w * ex[i], i in [0, n) */
    void (*splat_row1)(float *row, const float *ex, float w, int n);
    /* row4[4i + c] += w[c] * ex[i]: four interleaved channels */
    void (*splat_row4)(float *row4, const float *ex, const float w[4], int n);
    /* gradient splats: row4[4i] += c[0] ex[i], [4i+1] += c[1] exd[i],
     * [4i+2] += c[2] ex[i], [4i+3] += c[3] ex[i] */
    void (*splat_row_gs)(float *row4, const float *ex, const float *exd, const float c[4], int n);
    /* front-to-back over one span: for alpha[i] > 0,
     *   w = (1 - acc[4i+3]) * alpha[i]; acc[4i+c] += w * rgb[3i+c]; acc[4i+3] += w (<= 1);
     * returns how many pixels crossed the opacity threshold thr */
    int (*composite)(float *acc, const float *alpha, const float *rgb, int n, float thr);
    /* a footprint block (src/block.h) into a sheet:
     *   dst[r ds + i] += w8[i % 8] * blk[r bs + i], r < rows, i < 8 nvec */
    void (*splat_block)(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                        const float w8[8]);
} vs_kernels;

/* Scalar reference kernels (src/kernels.c). */
void vs_splat_row1_scalar(float *row, const float *ex, float w, int n);
void vs_splat_row4_scalar(float *row4, const float *ex, const float w[4], int n);
void vs_splat_row_gs_scalar(float *row4, const float *ex, const float *exd, const float c[4], int n);
int vs_composite_scalar(float *acc, const float *alpha, const float *rgb, int n, float thr);
void vs_splat_block_scalar(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                           const float w8[8]);

/* The per-ISA versions in simd/ (declared once here for the dispatch, the
 * tests and the kernel benchmark; call them only where the CPU has the ISA). */
void vs_splat_row4_sse4(float *row4, const float *ex, const float w[4], int n);
void vs_splat_row_gs_sse4(float *row4, const float *ex, const float *exd, const float c[4], int n);
void vs_splat_row4_avx2(float *row4, const float *ex, const float w[4], int n);
void vs_splat_row_gs_avx2(float *row4, const float *ex, const float *exd, const float c[4], int n);
void vs_splat_row4_avx512(float *row4, const float *ex, const float w[4], int n);
typedef void (*vs_splat_block_fn)(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                                  const float w8[8]);
void vs_splat_block_sse4(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                         const float w8[8]);
void vs_splat_block_avx2(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                         const float w8[8]);
void vs_splat_block_avx512(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                           const float w8[8]);

/* Fill the table: scalar, then the best ISA <= cap this CPU supports
 * (simd/dispatch.c). */
void vs_kernels_init(vs_kernels *k, vs_isa cap);
/* The ISA cap from VSPLAT_ISA (VS_ISA_AUTO if unset or unknown). */
vs_isa vs_isa_from_env(void);

#endif
