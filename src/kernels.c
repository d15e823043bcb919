/* Scalar reference kernels: the definition every SIMD kernel is tested
 * against (tests/test_simd.c). */
#include "kernels.h"

void vs_splat_row1_scalar(float *row, const float *ex, float w, int n)
{
    for (int i = 0; i < n; i++) row[i] += w * ex[i];
}

void vs_splat_row4_scalar(float *row4, const float *ex, const float w[4], int n)
{
    for (int i = 0; i < n; i++) {
        float h = ex[i];
        float *p = row4 + 4 * i;
        p[0] += w[0] * h;
        p[1] += w[1] * h;
        p[2] += w[2] * h;
        p[3] += w[3] * h;
    }
}

void vs_splat_row_gs_scalar(float *row4, const float *ex, const float *exd, const float c[4], int n)
{
    for (int i = 0; i < n; i++) {
        float h = ex[i];
        float *p = row4 + 4 * i;
        p[0] += c[0] * h;
        p[1] += c[1] * exd[i];
        p[2] += c[2] * h;
        p[3] += c[3] * h;
    }
}

int vs_composite_scalar(float *acc, const float *alpha, const float *rgb, int n, float thr)
{
    int crossed = 0;
    for (int i = 0; i < n; i++) {
        float a = alpha[i];
        if (!(a > 0.0f)) continue;
        float *p = acc + 4 * i;
        float before = p[3];
        float w = (1.0f - before) * a;
        p[0] += w * rgb[3 * i];
        p[1] += w * rgb[3 * i + 1];
        p[2] += w * rgb[3 * i + 2];
        float after = before + w;
        p[3] = after > 1.0f ? 1.0f : after;
        crossed += before < thr && p[3] >= thr;
    }
    return crossed;
}

void vs_splat_block_scalar(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                           const float w8[8])
{
    for (int r = 0; r < rows; r++) {
        float *d = dst + r * ds;
        const float *b = blk + r * bs;
        for (int i = 0; i < 8 * nvec; i++) d[i] += w8[i % 8] * b[i];
    }
}
