/* The classification stage (sheet_classify.c): a sheet's opacities and,
 * post-shaded, gradients; one function per pipeline, chosen by pipeline.c.
 * The transfer-function tables they read are classify.c's. */
#ifndef VS_SHEET_CLASSIFY_H
#define VS_SHEET_CLASSIFY_H

#include "tile.h"

/* Perspective, post-cd: sheet k's central differences p (x, y per pixel of
 * that sheet, z across sheets along the pixel's ray) to x, y per depth-0
 * pixel and z along view z, for the pixel (u, v) from the image centre;
 * sk the sheet's scale, cz = px_per_mm / (focal_px z_per_mm)
 * (sheet_classify.c explains it).  Classification and pre-integrated
 * shading share it, so that both give sheet k + 1 the same gradient. */
static inline void vs_perspective_gradient(float *p, float sk, float u, float v, float cz)
{
    p[0] *= sk;
    p[1] *= sk;
    p[2] -= (p[0] * u + p[1] * v) * cz;
}

/* Each returns how many span pixels keep an opacity. */
uint64_t vs_classify_post_cd(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
uint64_t vs_classify_post_gs(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
uint64_t vs_classify_pre(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
uint64_t vs_classify_post_alpha(const tile_ctx *t, const sheet_view *sv, shade_buf sb);

#endif
