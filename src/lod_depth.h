/* Levels of detail by depth: a perspective view whose far part is seen
 * smaller than its near part is split into depth bands, each splatted
 * from the level its nearest depth needs, nearest first.  Each band's
 * sheets are reconstructed from one level only; the band shades and
 * composites its own sheets and splats the ones
 * before it no further than its gradients need (frame.h, show0/show1),
 * compositing behind the picture of the bands in front, whose opaque
 * pixels cull its voxels (frame.h, under). */
#ifndef VS_LOD_DEPTH_H
#define VS_LOD_DEPTH_H

#include "camera.h"
#include "lod.h"
#include "volume.h"

/* A band: the level splatted and its depths in mm from the camera's z = 0
 * plane, [z0, z1) (the first from -inf, the last to +inf). */
typedef struct vs_lod_band {
    int level;
    double z0, z1;
} vs_lod_band;

/* The bands of a view of vol (nearest first): one, the level vs_lod_choose
 * gives, unless the view is perspective and its far corners allow a
 * coarser level than its nearest; then a band from each depth where the
 * level vs_lod_choose_at allows grows.  Returns how many. */
int vs_lod_bands(const struct vs_volume *vol, const vs_settings *s, const vs_camera *cam,
                 vs_lod_band band[VS_LOD_MAX + 1]);
/* The sheets [*show0, *show1) of slab thickness `slab` (view units,
 * z_per_mm of them a mm) whose slabs fill the band. */
void vs_lod_band_sheets(const vs_lod_band *b, double z_per_mm, double slab, int *show0, int *show1);
/* Straight RGBA over the background (vs_settings.background), as a frame
 * finishes its pixels. */
void vs_image_background(float *img, size_t npix, const float bg[4]);
/* The counters and times of b added to sum (a band's frame to the view's). */
void vs_stats_add(vs_stats *sum, const vs_stats *b);

#endif
