/* The classification stage (sheet_classify.c): a sheet's opacities and,
 * post-shaded, gradients; one function per pipeline, chosen by pipeline.c.
 * The transfer-function tables they read are classify.c's. */
#ifndef VS_SHEET_CLASSIFY_H
#define VS_SHEET_CLASSIFY_H

#include "tile.h"

/* Each returns how many span pixels keep an opacity. */
uint64_t vs_classify_post_cd(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
uint64_t vs_classify_post_gs(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
uint64_t vs_classify_pre(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
uint64_t vs_classify_post_alpha(const tile_ctx *t, const sheet_view *sv, shade_buf sb);

#endif
