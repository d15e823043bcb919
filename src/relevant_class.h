/* What the two builds of the relevant-voxel list share (relevant.c, the
 * whole grid at once; relevant_bricks.c, brick by brick): the class of a
 * value against the opacity range, buffer reuse and the list's arrays. */
#ifndef VS_RELEVANT_CLASS_H
#define VS_RELEVANT_CLASS_H

#include "classify.h"
#include "context.h"
#include "relevant.h"

#include <math.h>
#include <stdlib.h>

static inline int vs_relevant_in_range(const vs_classify *c, double v)
{
    /* opacity is non-zero strictly inside (alpha_lo, alpha_hi) for ramps and
     * on the closed range for hard thresholds */
    if (!isfinite(v)) return 0;
    if (c->ramp > 0 || c->use_points) return v > c->alpha_lo && v < c->alpha_hi;
    return v >= c->alpha_lo && v <= c->alpha_hi;
}

/* A voxel's class: below the range, inside it, above it, or non-finite (0). */
enum { VS_REL_BELOW = 1, VS_REL_INSIDE = 2, VS_REL_ABOVE = 4 };
static inline uint8_t vs_relevant_class(const vs_classify *c, double v)
{
    if (vs_relevant_in_range(c, v)) return VS_REL_INSIDE;
    if (!isfinite(v)) return 0;
    return v <= c->alpha_lo ? VS_REL_BELOW : VS_REL_ABOVE;
}

/* Buffers of the previous list are reused (realloc) so that changing the
 * iso-range does not pay for fresh, page-faulting allocations each time. */
static inline void *vs_relevant_take(void **old, size_t bytes)
{
    void *p = realloc(*old, bytes ? bytes : 1);
    if (p) *old = NULL;
    return p;
}

/* A brick whose every voxel is relevant (all VS_BRICK^3 of them, the
 * interior of a large object) holds no voxels of its own: it points at one
 * block of all positions in k, j, i order at the list's start, so an
 * opaque interior costs neither the build's writes nor 1 KB a brick. */
#define VS_BRICK_VOXELS (VS_BRICK * VS_BRICK * VS_BRICK)
static inline void vs_relevant_whole_block(vs_voxel *v)
{
    for (int i = 0; i < VS_BRICK_VOXELS; i++) v[i] = (vs_voxel)i;
}

/* The list's arrays for count stored voxels in nonempty bricks (the voxels in
 * old's array when there is one): VS_OK, or the error set and both NULL
 * when the count passes 2^32 - 1 or memory runs out. */
static inline vs_status vs_relevant_lists(vs_context *ctx, vs_relevant_cache *old, size_t count, size_t nonempty,
                                          vs_voxel **vox, vs_brick **bricks)
{
    *vox = NULL;
    *bricks = NULL;
    if (count > UINT32_MAX)
        return vs_set_error(ctx, VS_ERR_TOO_LARGE, "relevant voxels: %zu voxels exceed the limit", count);
    vs_voxel *v = old ? vs_relevant_take((void **)&old->voxels, count * sizeof *v) : malloc((count ? count : 1) * sizeof *v);
    vs_brick *b = malloc((nonempty ? nonempty : 1) * sizeof *b);
    if (!v || !b) {
        free(v);
        free(b);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "relevant voxels: cannot hold %zu voxels", count);
    }
    *vox = v;
    *bricks = b;
    return VS_OK;
}

/* The grid of VS_BRICK^3 bricks over dims d: nb per axis; returns them all. */
static inline size_t vs_relevant_grid(const int d[3], int nb[3])
{
    for (int a = 0; a < 3; a++) nb[a] = (d[a] + VS_BRICK - 1) / VS_BRICK;
    return (size_t)nb[0] * nb[1] * nb[2];
}

/* Brick (bi, bj, bk) of a grid of dims d, holding count voxels from slot
 * start of the list. */
static inline vs_brick vs_relevant_brick(const int d[3], int bi, int bj, int bk, uint32_t start, uint32_t count)
{
    vs_brick br;
    br.start = start;
    br.count = count;
    br.i0 = (uint16_t)(bi * VS_BRICK);
    br.j0 = (uint16_t)(bj * VS_BRICK);
    br.k0 = (uint16_t)(bk * VS_BRICK);
    br.i1 = (uint16_t)((bi + 1) * VS_BRICK > d[0] ? d[0] - 1 : (bi + 1) * VS_BRICK - 1);
    br.j1 = (uint16_t)((bj + 1) * VS_BRICK > d[1] ? d[1] - 1 : (bj + 1) * VS_BRICK - 1);
    br.k1 = (uint16_t)((bk + 1) * VS_BRICK > d[2] ? d[2] - 1 : (bk + 1) * VS_BRICK - 1);
    return br;
}

#endif
