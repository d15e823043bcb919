/* Relevant voxels (paper §2, §4.3): voxels whose value can be classified as
 * non-transparent, plus the seam layer of neighbours within `seam` voxels
 * (without the seam, post-shaded objects shrink and alias).  Built once per
 * classification and kept in the context across frames. */
#ifndef VS_RELEVANT_H
#define VS_RELEVANT_H

#include "classify.h"
#include "volume.h"

/* Voxels are stored brick by brick (VS_BRICK^3 grid cells) so a frame can
 * project, bin and cull whole bricks before touching their voxels.  A voxel
 * is only its position in the brick, di | dj << 3 | dk << 6 (2 bytes, not
 * the 12 of position plus value): a frame reads the value, and the
 * pre-shaded pipelines the gradient, from the volume, and only for the
 * voxels that survive culling. */
#define VS_RELEVANT_KEEP_SCRATCH ((size_t)256 << 20)
#define VS_BRICK_BITS 3
#define VS_BRICK (1 << VS_BRICK_BITS)
typedef uint16_t vs_voxel;
#define VS_VOXEL_DI(v) ((v) & (VS_BRICK - 1))
#define VS_VOXEL_DJ(v) (((v) >> VS_BRICK_BITS) & (VS_BRICK - 1))
#define VS_VOXEL_DK(v) ((v) >> (2 * VS_BRICK_BITS))
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
    /* the list, brick by brick (bricks in k, j, i order), and inside a
     * brick ordered by k, then j, then i; a brick with every voxel
     * relevant points at the block of all positions at slot 0
     * (vs_relevant_whole_block), so `stored` can be far below `count` */
    size_t count, stored;
    vs_voxel *voxels;
    size_t nbricks;
    vs_brick *bricks;      /* non-empty bricks only                     */
    uint8_t *scratch;      /* 2 bytes per grid voxel, kept for rebuilds up
                              to VS_RELEVANT_KEEP_SCRATCH bytes */
    /* per brick of the grid, the least and greatest finite value (an empty
     * brick: +inf, -inf), built once per data (data_serial) and handed from
     * list to list: a rebuild then visits only the bricks the
     * classification can reach */
    float *minmax;
    uint64_t minmax_serial;
    int sparse;            /* this list was built brick by brick             */
    double build_ms;
} vs_relevant_cache;

/* Returns the list cached in *slot if still valid, else rebuilds it there
 * (the context's slot for full resolution, one a level of detail).
 * *rebuilt tells which happened. */
struct vs_pool;
/* The rebuild runs on `pool` (NULL: on the calling thread); the list is the
 * same for any thread count. */
vs_status vs_relevant_get(vs_context *ctx, vs_relevant_cache **slot, struct vs_pool *pool,
                          const struct vs_volume *vol, const vs_classify *c, int seam, const vs_relevant_cache **out,
                          int *rebuilt);
/* How a rebuild finds the voxels: VS_RELEVANT_AUTO (vs_relevant_get's
 * choice: brick by brick when the volume is large and the bricks the
 * classification can reach are few), or forced, for tests: both give the
 * same list. */
enum { VS_RELEVANT_AUTO, VS_RELEVANT_DENSE, VS_RELEVANT_SPARSE };
vs_status vs_relevant_get_mode(vs_context *ctx, vs_relevant_cache **slot, struct vs_pool *pool,
                               const struct vs_volume *vol, const vs_classify *c, int seam, int mode,
                               const vs_relevant_cache **out, int *rebuilt);
void vs_relevant_cache_free(vs_relevant_cache *rc);
/* Are the volume's faces cut, each sheet divided near them by the voxels'
 * share (face_cover.h), for a volume reading base outside and reaching up
 * to vmax?  When base is visible (then every voxel is relevant too), and
 * when values lie above an upper end of the range: there the fall-off from
 * them to base at a face passes through the range and would draw a wall on
 * every face they touch (a soft-tissue window on a body cut by the scan). */
int vs_classify_faces(const vs_classify *c, double base, double vmax);

#endif
