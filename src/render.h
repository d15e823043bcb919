/* The frame around the tiles (render.c: set-up, relevant voxels, binning,
 * the tiles on the pool), and vs_render's choice of what it splats
 * (render_entry.c: the cubic copy of an anisotropic grid, the level of
 * detail, depth bands of levels under perspective). */
#ifndef VS_RENDER_H
#define VS_RENDER_H

#include "classify.h"
#include "lod_depth.h"
#include "relevant.h"

/* vol is what is splatted: the volume `full` or one of its levels of
 * detail; cls, the full volume's classification, becomes the frame's (and
 * is freed with it, whatever happens); band, when not NULL, the depths
 * whose sheets are shown (lod_depth.h), and under, when not NULL, the
 * picture of the bands in front (straight RGBA on no background, the
 * frame's size), which the frame composites behind; lod_span, when not
 * NULL, is when that level was built, just before. */
vs_status vs_render_splat(vs_context *ctx, const struct vs_volume *vol, const struct vs_volume *full,
                          vs_classify *cls, struct vs_relevant_cache **rel_slot, const vs_settings *s,
                          const vs_lod_band *band, const float *under, vs_image *out, vs_stats *st,
                          const double *lod_span);

#endif
