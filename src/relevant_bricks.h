/* The relevant-voxel list brick by brick (relevant_bricks.c), for large
 * volumes: relevant.c decides when. */
#ifndef VS_RELEVANT_BRICKS_H
#define VS_RELEVANT_BRICKS_H

#include "relevant.h"

struct vs_pool;
/* Volumes from this many voxels keep a min-max per brick (for smaller ones
 * the whole grid is as fast: 33.7 M u8 voxels, 76 ms against 82). */
#define VS_RELEVANT_SPARSE_VOXELS ((size_t)1 << 26)

/* Per brick of the volume's grid (vs_relevant_grid), the least and
 * greatest finite value, 2 floats each (a brick holding a NaN: least
 * -inf); NULL when out of memory. */
float *vs_relevant_minmax(struct vs_pool *pool, const struct vs_volume *vol);
/* The list into rc from rc->minmax: VS_OK; an error status; or
 * VS_ERR_UNSUPPORTED (nothing set) when the reached bricks would cost more
 * than about two passes over the grid, unless forced.  lut: the class of
 * each integer value (NULL for f32). */
vs_status vs_relevant_build_bricks(vs_context *ctx, struct vs_pool *pool, const struct vs_volume *vol,
                                   const vs_classify *c, const uint8_t *lut, int seam, int force, vs_relevant_cache *rc,
                                   vs_relevant_cache *old);

#endif
