/* The shading stage (shade.c, shade_preint.c): splat weights of voxels, and per sheet the
 * colours of the classified pixels; one function per pipeline, chosen by
 * pipeline.c. */
#ifndef VS_SHADE_H
#define VS_SHADE_H

#include "tile.h"

/* Splat weights (the pipeline table's `weights`). */
void vs_weights_density(const vs_frame *F, const pend *p, unsigned live, float w[][4]);
void vs_weights_pre(const vs_frame *F, const pend *p, unsigned live, float w[][4]);
void vs_weights_post_alpha(const vs_frame *F, const pend *p, unsigned live, float w[][4]);

/* Per sheet (the pipeline table's `shade`). */
void vs_shade_post_lut(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
void vs_shade_post_exact(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
void vs_shade_post_preint(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
void vs_shade_pre(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
void vs_shade_post_alpha(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
void vs_shade_post_alpha_preint(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
/* After any of them, with perspective: each pixel's opacity for the
 * length of its ray through the slab. */
void vs_perspective_opacity(const tile_ctx *t, const spans *r, float *alpha);

#endif
