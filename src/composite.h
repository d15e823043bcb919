/* The compositing stage (composite.c): a sheet's shaded pixels into the
 * tile's front-to-back accumulation, which is also its occlusion map, and
 * the tile's final pixels. */
#ifndef VS_COMPOSITE_H
#define VS_COMPOSITE_H

#include "tile.h"

/* Composite the spans of sb into acc; returns how many pixels crossed the
 * occlusion threshold thr, and lowers *first_row to the first own row
 * where one did. */
int vs_composite_sheet(const tile_ctx *t, const spans *sp, float *acc, shade_buf sb, float thr, int *first_row);
/* The tile's accumulated pixels over the background into the image. */
void vs_composite_finish(const tile_ctx *t, const float *acc);

#endif
