/* The occlusion map of a tile (its accumulated opacity) and what it saves:
 * culling voxels and bricks whose footprints can only land on opaque
 * pixels (a summed-area table of the tile's opaque pixels answers that in
 * O(1)), and shading only the pixels still open. */
#ifndef VS_OCCLUSION_H
#define VS_OCCLUSION_H

#include "tile.h"

/* Is every tile pixel that a footprint centred in [x0,x1] x [y0,y1] and
 * scaled by at most sc (plus the central-difference seam) can reach already
 * opaque? */
static inline int box_occluded_pad(const tile_ctx *t, const int *sat, float x0, float x1, float y0, float y1,
                                   float px, float py)
{
    int xa = vs_ifloor(x0 - px) - t->x0, xb = vs_iceil(x1 + px) - t->x0;
    int ya = vs_ifloor(y0 - py) - t->y0, yb = vs_iceil(y1 + py) - t->y0;
    if (xa < 0) xa = 0;
    if (ya < 0) ya = 0;
    if (xb > t->tw - 1) xb = t->tw - 1;
    if (yb > t->th - 1) yb = t->th - 1;
    if (xa > xb || ya > yb) return 1; /* touches no pixel of this tile */
    int w = t->tw + 1;
    int sum = sat[(yb + 1) * w + xb + 1] - sat[ya * w + xb + 1] - sat[(yb + 1) * w + xa] + sat[ya * w + xa];
    return sum == (xb - xa + 1) * (yb - ya + 1);
}

/* The same with the frame's footprint reach scaled by sc. */
static inline int box_occluded(const tile_ctx *t, const int *sat, float x0, float x1, float y0, float y1, float sc)
{
    float px, py;
    vs_frame_reach(t->F, sc, &px, &py);
    return box_occluded_pad(t, sat, x0, x1, y0, y1, px, py);
}


/* Rebuild the summed-area table from tile row `from` on (rows above keep
 * their sums). */
void vs_build_sat(const tile_ctx *t, const float *acc, float thr, int *sat, int from);
/* Clear the opacity of span pixels already fully opaque; returns how many
 * span pixels keep an opacity (the work count of shading). */
uint64_t vs_skip_opaque(const tile_ctx *t, const spans *r, const float *acc, float *alpha);
/* The same count without occlusion. */
uint64_t vs_count_visible(const tile_ctx *t, const spans *r, const float *alpha);
/* The part of the touched rectangle r to classify, shade and composite. */
void vs_shaded_spans(const rect *r, const int *live0, const int *live1, int seam, spans *sp);
/* Shrink own row y's live columns past pixels that became opaque. */
void vs_shrink_live(const tile_ctx *t, const float *acc, int y, int *live0, int *live1);

#endif
