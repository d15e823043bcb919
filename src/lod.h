/* Levels of detail: a volume seen small is splatted from a coarser copy of
 * itself, so that a frame's cost follows the pixels it covers rather than
 * the voxels behind them.  Each level is the one before low-pass filtered
 * and decimated by 2 along its finer axes (lod.c says which); its voxels are splatted with the same
 * kernel in level units, i.e. a Gaussian as much wider in the volume's,
 * which is the reconstruction of the filtered signal at the coarser scale.
 * The levels are built on first use and kept in the context, keyed on the
 * volume's data serial (a new range re-ranges them, a new transform
 * re-places them). */
#ifndef VS_LOD_H
#define VS_LOD_H

#include "camera.h"
#include "volume.h"

#define VS_LOD_MAX 12
#define VS_LOD_MIN_DIM 8

typedef struct vs_lod_cache {
    vs_volume_stamp from; /* the full-resolution volume, when built, ranged, placed */
    struct vs_volume *level[VS_LOD_MAX + 1]; /* [0] unused: the volume itself */
    /* each level's relevant voxels (full resolution's are the context's):
     * a view that moves between levels does not rebuild them */
    struct vs_relevant_cache *relevant[VS_LOD_MAX + 1];
    /* lod_keep.c: per level, the copy patched for the classification
     * below (NULL: the plain level shows it), whether it was worked out,
     * and the level's serial then; the classification's opacity table and
     * domain; the min-max per brick of the volume (level 1's source) */
    struct vs_volume *kept[VS_LOD_MAX + 1];
    int kept_done[VS_LOD_MAX + 1];
    uint64_t kept_serial[VS_LOD_MAX + 1];
    float *kept_alpha;
    double kept_vmin, kept_scale;
    float *minmax[VS_LOD_MAX + 1]; /* [0]: the volume */
} vs_lod_cache;

struct vs_pool;
/* The coarsest level whose voxels lie at most s->lod_pixels apart on the
 * image (at the volume's nearest point under perspective: lod_depth.h
 * splits such a view by depth), measured along
 * the volume's finest axis; 0 when lod_pixels is 0, a crop box is set, or
 * the volume is too small to decimate. */
int vs_lod_choose(const struct vs_volume *vol, const vs_settings *s, const vs_camera *cam);
/* The same where the image is `scale` times the size at depth 0
 * (vs_camera_scale): what a depth band of a perspective view needs. */
int vs_lod_choose_at(const struct vs_volume *vol, const vs_settings *s, const vs_camera *cam, double scale);
/* Level `level` (>= 1) of vol, built (with the levels before it) on `pool`
 * if the cache does not hold it; *ms the time spent building (0 if none). */
vs_status vs_lod_get(vs_context *ctx, struct vs_pool *pool, vs_lod_cache **cache, const struct vs_volume *vol,
                     int level, const struct vs_volume **out, double *ms);
/* The settings that frame `lv` (a level of vol) exactly as `s` frames vol:
 * the same image scale and centre, sheets one level voxel apart. */
void vs_lod_settings(const struct vs_volume *vol, const struct vs_volume *lv, const vs_settings *s,
                     vs_settings *out);
void vs_lod_cache_free(vs_lod_cache *c);

#endif
