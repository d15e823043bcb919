/* Levels of detail that keep what the classification shows (lod_keep.c).
 *
 * A level holds plain filtered values, classified afterwards: a structure
 * thinner than a level voxel (a CT headrest one voxel thick) averages below
 * the iso-value and leaves the level.  Per classification, the voxels of a
 * level where that happened -- the level's reconstruction transparent all
 * around a voxel while the finer level's, classified and filtered down,
 * is not -- are raised until the level's reconstructed opacity there is
 * the finer level's average (lowered, for a dark structure averaged above
 * an iso-range with an upper end).  Nothing else changes, so smooth
 * surfaces (a visible voxel next door) keep the plain level exactly. */
#ifndef VS_LOD_KEEP_H
#define VS_LOD_KEEP_H

#include "classify.h"
#include "lod.h"

struct vs_pool;
/* Level `level` (>= 1, built by vs_lod_get) of vol as classified by c:
 * the plain level, or its patched copy (made once per classification and
 * kept in the cache, with the finer levels' it depends on).  *ms: the time
 * spent patching (0 when kept). */
vs_status vs_lod_keep(vs_context *ctx, struct vs_pool *pool, vs_lod_cache *cache, const struct vs_volume *vol,
                      int level, const vs_classify *c, const struct vs_volume **out, double *ms);
/* Forget the patched copies (a new classification, or new levels). */
void vs_lod_keep_clear(vs_lod_cache *cache);

#endif
