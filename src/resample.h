/* Anisotropic grids splatted as cubic ones.  A kernel on voxels thicker
 * along one axis is an ellipsoid; seen obliquely its sections move across
 * the image from sheet to sheet, so each section is placed on its own
 * (several times the cost of a shared footprint: the CT head's 1.5 mm
 * slices cost 3x a frame).  Instead, a frame of such a volume splats a
 * copy on cubic voxels of the finest spacing, or a level of detail made
 * from it; the copy is built once and kept in the context.  The copy keeps the reconstruction: the grid's
 * Gaussian of width sigma s_a along a thick axis is the cubic grid's
 * Gaussian (sigma s_min) convolved with one of width sigma sqrt(s_a^2 -
 * s_min^2), so each new voxel is that narrower Gaussian of the old ones
 * along the axis, normalised (resample.c).  It is framed as the volume by
 * vs_camera_settings_for_copy: same centre, same finest spacing, so the
 * sheets stay where they were. */
#ifndef VS_RESAMPLE_H
#define VS_RESAMPLE_H

#include "volume.h"

struct vs_relevant_cache;
typedef struct vs_resample_cache {
    vs_volume_stamp from;            /* the volume, when copied, ranged, placed */
    struct vs_volume *cubic;         /* the copy on cubic voxels */
    struct vs_relevant_cache *relevant; /* the copy's relevant voxels */
} vs_resample_cache;

/* Spacing ratios (thickest over finest) below this are splatted as they
 * are: the Gaussian between the grids would be narrower than about half a
 * new voxel, and sampling it would alias (resample.c). */
#define VS_RESAMPLE_MIN_RATIO 1.25

/* Whether a frame of vol with settings s splats the cubic copy or a level
 * of it: a splatting pipeline without a crop box, resample != 0, orthogonal
 * grid axes, a spacing ratio of at least VS_RESAMPLE_MIN_RATIO, and (auto,
 * resample < 0) a copy no larger than the volume plus 64 MB. */
int vs_resample_wanted(const struct vs_volume *vol, const vs_settings *s);
/* The copy of vol on cubic voxels, built on `pool` if the cache does not
 * hold it; *ms the time spent building (0 if none). */
struct vs_pool;
vs_status vs_resample_get(vs_context *ctx, struct vs_pool *pool, vs_resample_cache **cache,
                          const struct vs_volume *vol, const struct vs_volume **out, double *ms);
void vs_resample_cache_free(vs_resample_cache *c);

#endif
