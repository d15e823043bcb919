/* Footprint blocks: the fast path for separable footprints (isotropic
 * voxels from any view, anisotropic ones seen along an axis).
 *
 * A separable footprint exp(-A dx^2 - C dy^2) is a column weight times a
 * row weight.  Both depend only on the voxel centre's sub-pixel phase, so
 * they are tabulated once per frame at VS_BLOCK_PHASES + 1 phases per pixel
 * and interpolated linearly between them.  (Rounding the phase to the
 * nearest entry instead is not enough: a pixel sums some 50 voxels whose
 * weights each err in proportion to the voxel's value, not to the field's
 * gradient, and central differences of a smooth field then tilt normals by
 * several degrees — tests/test_splat.c's ramp.)  A voxel builds one block of
 * weights, `ny` rows of `nvec` 8-float vectors (weights outside the kernel's
 * radius are exactly 0), and every sheet its kernel reaches adds the block
 * times a per-sheet weight pattern with one kernel call
 * (vs_kernels.splat_block) — no per-row set-up, no per-pixel look-ups.
 *
 * The pattern repeats every `ch` floats: ch = 1 for density (post-cd),
 * ch = 4 for interleaved RGBA (pre, post-alpha) or density + gradient
 * (post-gs, where the block holds h, h dx, h dy, h per pixel). */
#ifndef VS_BLOCK_H
#define VS_BLOCK_H

#include "footprint.h"

typedef struct vs_block_geom {
    int ch;          /* floats per pixel: 1 or 4                              */
    int grad;        /* block holds h, h dx, h dy, h (gradient splats)        */
    int nx, ny;      /* pixels a footprint spans at most, across and down     */
    int nvec;        /* 8-float vectors per block row: ceil(nx ch / 8)        */
    int bx;          /* pixels per block row: 8 nvec / ch (>= nx)             */
    float rx0, ry0;  /* footprint half-extents (pixels)                        */
    float thr;       /* exp(-emax): a product below it lies outside the radius */
    float *colw;     /* (PHASES + 1) x bx: exp(-A dx^2), 0 past the radius     */
    float *roww;     /* (PHASES + 1) x ny: exp(-C dy^2), 0 past the radius     */
} vs_block_geom;

#define VS_BLOCK_PHASES 256

/* 8-float vectors a skewed block row needs at most for ch floats a pixel:
 * the widest row plus the drift of the row centres over the rows. */
int vs_block_skewed_nvec(const vs_block_geom *g, float row_shift, int ch);
/* The block of a general footprint (skewed tables) centred at image
 * position (cx, cy): g->ny rows, each placed at its own column phase, laid
 * into one rectangle of ch-float pixels (zeros where a row does not reach;
 * ch = 4 repeats the weight h in every channel, or with grad holds h,
 * h dx, h dy, h, the offsets from the centre in pixels), rows 8 maxvec
 * floats apart.  Out: image column x and row y of the rectangle's first
 * pixel and its vectors per row (<= maxvec). */
void vs_block_build_skewed(const vs_block_geom *g, float row_shift, float cx, float cy, int ch, int grad, int maxvec,
                           float *blk, int *x, int *y, int *nvec);

/* Where one voxel's block lands: image column/row of its first pixel and
 * its phase-table rows. */
typedef struct vs_block_place {
    int x, y;        /* image coordinates of block pixel (0, 0)            */
    float ux, uy;    /* phase: block pixel (0, 0) lies u past the
                        footprint's left (top) edge, u in [0, 1)           */
    int qx, qy;      /* table rows below the phases ...                     */
    float fx, fy;    /* ... and the interpolation weights of the next rows */
} vs_block_place;

/* Tables for a separable footprint; returns 0 when out of memory or too
 * large (VS_BLOCK_MAX_SPAN). */
int vs_block_setup(vs_block_geom *g, const vs_footprint *fp, int ch, int grad);
/* Skewed tables for any footprint (rotated or sheared ellipses): written as
 * exp(-A (dx - row_shift dy)^2) exp(-row_k dy^2), a footprint is a row
 * weight (roww, with row_k) times column weights (colw, with A) about a
 * centre that moves by row_shift per row, so each row takes its own column
 * phase.  rx0 is then the half-width of the widest row.  For a separable
 * footprint the tables equal vs_block_setup's.  Returns 0 like it. */
int vs_block_setup_skewed(vs_block_geom *g, const vs_footprint *fp);
void vs_block_free(vs_block_geom *g);

/* How far the block's first pixel `first` (the ceiling of c - r0) lies
 * past the block's left (top) edge c - r0: vs_block_place_at's ux (uy). */
static inline float vs_block_phase(float c, float r0, int first)
{
    return (float)first - (c - r0);
}

/* The block of a voxel centred at image position (cx, cy). */
static inline void vs_block_place_at(const vs_block_geom *g, float cx, float cy, vs_block_place *p)
{
    p->x = vs_iceil(cx - g->rx0);
    p->y = vs_iceil(cy - g->ry0);
    p->ux = vs_block_phase(cx, g->rx0, p->x);
    p->uy = vs_block_phase(cy, g->ry0, p->y);
    float sx = p->ux * (float)VS_BLOCK_PHASES, sy = p->uy * (float)VS_BLOCK_PHASES;
    p->qx = (int)sx;
    p->qy = (int)sy;
    if (p->qx > VS_BLOCK_PHASES - 1) p->qx = VS_BLOCK_PHASES - 1;
    if (p->qy > VS_BLOCK_PHASES - 1) p->qy = VS_BLOCK_PHASES - 1;
    p->fx = sx - (float)p->qx;
    p->fy = sy - (float)p->qy;
}

/* Fill rows [j0, j1) and vectors [v0, v1) of the block (row stride
 * 8 nvec floats). */
void vs_block_build(const vs_block_geom *g, const vs_block_place *p, int j0, int j1, int v0, int v1, float *blk);

/* The factors of rows [j0, j1) and vectors [v0, v1) of the block of a
 * one-channel (density) footprint: pixel i of row j is cw[i - 8 v0] *
 * rw[j - j0], kept where > g->thr (vs_kernels.splat_voxel1 builds the
 * rows from them in registers, vs_block_build into memory). */
void vs_block_factors(const vs_block_geom *g, const vs_block_place *p, int j0, int j1, int v0, int v1, float *cw,
                      float *rw);
/* The two halves of vs_block_factors_ch: column factors of pixels
 * [i0, i1) into cw[0 ..), row factors of rows [j0, j1) into rw[0 ..). */
void vs_block_col_factors(const vs_block_geom *g, const vs_block_place *p, int i0, int i1, float *cw);
void vs_block_row_factors(const vs_block_geom *g, const vs_block_place *p, int j0, int j1, float *rw);
/* vs_block_factors for vectors of ch floats a pixel whatever g's own layout
 * (the skewed tables serve one- and four-channel sheets). */
void vs_block_factors_ch(const vs_block_geom *g, const vs_block_place *p, int ch, int j0, int j1, int v0, int v1,
                         float *cw, float *rw);

/* Most pixels a block row or column may span (vs_block_setup refuses more). */
#define VS_BLOCK_MAX_SPAN 4096

#endif
