/* Relevant voxels (paper §2, §4.3): voxels whose value can be classified as
 * non-transparent, plus the seam layer of neighbours within `seam` voxels
 * (without the seam, post-shaded objects shrink and alias).  Built once per
 * classification and kept in the context across frames. */
#ifndef VS_RELEVANT_H
#define VS_RELEVANT_H

#include "internal.h"

typedef struct vs_voxel {
    uint16_t i, j, k, pad; /* grid position                         */
    float value;           /* raw density                           */
} vs_voxel;

/* Voxels are stored brick by brick (VS_BRICK^3 grid cells) so a frame can
 * project, bin and cull whole bricks before touching their voxels. */
#define VS_BRICK 8
typedef struct vs_brick {
    uint32_t start, count;  /* range in the voxel list                     */
    uint16_t i0, j0, k0;    /* lowest grid position of the brick's voxels   */
    uint16_t i1, j1, k1;    /* highest                                      */
} vs_brick;

typedef struct vs_relevant_cache {
    /* key: what the list was built from */
    const struct vs_volume *vol;
    uint64_t serial;       /* vol->serial when built: a new volume at the same
                              address, or rewritten data, does not match */
    int dims[3];
    double vmin, vmax;
    double alpha_lo, alpha_hi;
    int seam;
    int with_grad;
    /* the list, brick by brick (bricks in k, j, i order), and inside a
     * brick ordered by k, then j, then i */
    size_t count;
    vs_voxel *voxels;
    float *grad;           /* 3 per voxel, index units (with_grad only) */
    size_t nbricks;
    vs_brick *bricks;      /* non-empty bricks only                     */
    uint8_t *scratch;      /* 2 bytes per grid voxel, kept for rebuilds */
    double build_ms;
} vs_relevant_cache;

/* Returns the cached list if still valid, else rebuilds it.  *rebuilt tells
 * which happened.  with_grad: also store grid central-difference gradients
 * (pre-shaded pipelines shade voxels). */
struct vs_pool;
/* The rebuild runs on `pool` (NULL: on the calling thread); the list is the
 * same for any thread count. */
vs_status vs_relevant_get(vs_context *ctx, struct vs_pool *pool, const struct vs_volume *vol, const vs_classify *c,
                          int seam, int with_grad, const vs_relevant_cache **out, int *rebuilt);
void vs_relevant_cache_free(vs_relevant_cache *rc);
/* Does the classification give value 0 (empty space) a non-zero opacity?
 * Then every voxel is relevant and sheets are clipped to the volume. */
int vs_classify_zero_visible(const vs_classify *c);

#endif
