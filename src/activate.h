/* Voxel activation (activate.c): bricks opened and binned into the tile's
 * buckets, and each sheet's voxels into the sheet buffers. */
#ifndef VS_ACTIVATE_H
#define VS_ACTIVATE_H

#include "tile.h"

/* Open brick b at sheet `opening`: cull it whole, or bucket its voxels
 * that reach this tile by first sheet. */
void vs_expand_brick(tile_state *ts, uint32_t b, int opening);
/* Sheet at a time (general footprints): sheet k from the voxels
 * overlapping it. */
void vs_rasterize_sheet(tile_state *ts, int k, float *dst, rect *bb);
/* Voxel at a time: the voxels starting at sheet `opening` into every
 * sheet of the ring (R slots, sheet k in slot (k - kbase) mod R) they
 * reach, with the pipeline's fused kernel (the table's `activate`):
 * density, four channels, density with gradient splats. */
void vs_activate_density(tile_state *ts, int opening, float *const *ring, rect *bbs, int R, int kbase);
void vs_activate_rgba(tile_state *ts, int opening, float *const *ring, rect *bbs, int R, int kbase);
void vs_activate_gradient(tile_state *ts, int opening, float *const *ring, rect *bbs, int R, int kbase);

#endif
