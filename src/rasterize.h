/* Kernel sections into sheet buffers: where a voxel's kernel, integrated
 * over one slab, lands on a sheet (make_section), and the rasterizers that
 * add it: an exponential per pixel for general footprints, one skewed block
 * from the footprint tables, or the fused kernels for footprints whose rows
 * share one column phase.  Which voxels reach which sheet is activate.c's. */
#ifndef VS_RASTERIZE_H
#define VS_RASTERIZE_H

#include "tile.h"

#include <math.h>

/* What every section on sheet k shares: its skewed tables (NULL: an
 * exponential per pixel) and, with perspective, its scale about the image
 * centre and the scale's inverse (1 when orthographic). */
typedef struct sheet_geom {
    const vs_block_geom *g;
    float sk, isk;
} sheet_geom;

/* The tables and scale of sheet k's sections. */
sheet_geom vs_sheet_geom(const vs_frame *F, int k);

/* The slab section of a voxel on a sheet from its depth integrals D and E
 * over the slab (E: of the depth derivative, exp at the slab's ends;
 * c0 <= c1: the slab's ends from the voxel's centre, clamped to the
 * kernel's depth radius, for a sheared footprint's centroid).  (x, y) is
 * the voxel's image position, with perspective its depth-0 one: the
 * section on the sheet's plane is centred on the same world point, which
 * appears scaled by the sheet's scale about the image centre. */
static inline void place_section(const tile_ctx *t, const sheet_geom *sh, float x, float y, float D, float E,
                                 float c0, float c1, section *sec)
{
    const vs_footprint *fp = t->fp;
    sec->D = D;
    sec->E = E;
    sec->cx = x;
    sec->cy = y;
    sec->sc = sh->sk;
    sec->is = sh->isk;
    sec->g = sh->g;
    if (t->F->cam.persp) {
        const float cx = (float)t->F->cam.cx, cy = (float)t->F->cam.cy;
        sec->cx = cx + (x - cx) * sh->sk;
        sec->cy = cy + (y - cy) * sh->sk;
    }
    if (fp->sheared) { /* centroid of the depth term within the slab */
        float zbar = -E / (2.0f * (float)fp->kappa * D);
        /* a centroid lies inside its slab; in a kernel's tail D and -E
         * are both tiny and their tabulated ratio can run away, which would
         * throw the footprint outside the tiles it was binned to */
        if (!(zbar >= c0)) zbar = c0;
        if (zbar > c1) zbar = c1;
        sec->cx += fp->sx * zbar * sec->sc;
        sec->cy += fp->sy * zbar * sec->sc;
    }
}

/* The slab's ends from a voxel's centre at depth z, sheet k, clamped to
 * the kernel's depth radius (c0, c1); returns the near end unclamped. */
static inline float section_ends(const vs_footprint *fp, float z, int k, float *c0, float *c1)
{
    const float slab = (float)fp->slab, rz = (float)fp->rz;
    const float a = (float)k * slab - z, b = a + slab;
    *c0 = a < -rz ? -rz : (a > rz ? rz : a);
    *c1 = b < -rz ? -rz : (b > rz ? rz : b);
    return a;
}

/* Compute the slab section of voxel at depth z for sheet k; 0 if empty. */
static inline int make_section(const tile_ctx *t, const sheet_geom *sh, float x, float y, float z, int k,
                               section *sec)
{
    const vs_footprint *fp = t->fp;
    float c0, c1;
    const float z0 = section_ends(fp, z, k, &c0, &c1);
    float D = vs_fp_depth(fp, z0 + (float)fp->slab) - vs_fp_depth(fp, z0);
    if (!(D > 0.0f)) return 0;
    float rz = (float)fp->rz, kap = (float)fp->kappa;
    float e0 = 0.0f, e1 = 0.0f;
    /* the depth derivative's integral: for gradient splats and the
     * centroid of a sheared footprint only */
    if (fp->sheared || t->F->stages->gradient_splats) {
        e0 = vs_fp_exp(fp, kap * c0 * c0);
        e1 = vs_fp_exp(fp, kap * c1 * c1);
        if (fabsf(c0) >= rz) e0 = 0.0f;
        if (fabsf(c1) >= rz) e1 = 0.0f;
    }
    place_section(t, sh, x, y, D, e1 - e0, c0, c1, sec);
    return 1;
}

/* A sheared footprint whose rows all share one column phase (no skew:
 * row_shift 0, e.g. anisotropic voxels seen with an axis in the image
 * plane, or perspective sheets of isotropic ones) is a column times a row
 * weight, like a separable one: the fused voxel kernels build its rows in
 * registers and add them, with the products and threshold of
 * vs_block_build_skewed's uniform case, so the sheet gets the same floats
 * as from the block.  The columns (placement, the vectors inside the
 * buffer, their factors) and the rows are set apart, so that the sections
 * of a voxel whose centre moves only down the image share the columns. */
typedef struct unskewed_cols {
    const vs_block_geom *g; /* the tables and centre they were placed for */
    float cx;
    int bx;     /* buffer column of block pixel 0 */
    int v0, v1; /* the block's vectors inside the buffer (none: v0 >= v1) */
    float cw[VS_VOXEL1_MAX + 8];
    float dx[VS_VOXEL1_MAX + 8]; /* post-gs: the columns' offsets from cx */
} unskewed_cols;

/* Sheet at a time, general footprints without tables (the pipeline
 * table's `raster`): density (post-cd), density and gradient splats
 * (post-gs), four weighted channels (pre, post-alpha). */
void vs_raster1(const tile_ctx *t, const section *sec, const float w4[4], float *q, rect *bb);
void vs_raster_gs(const tile_ctx *t, const section *sec, const float w4[4], float *buf, rect *bb);
void vs_raster4(const tile_ctx *t, const section *sec, const float w4[4], float *buf, rect *bb);
/* A section from skewed tables (sec->g), ch channels; uc: the columns of an
 * earlier section of the same voxel to reuse, or NULL. */
void vs_raster_skewed(const tile_ctx *t, const section *sec, const float w4[4], int ch, float *dst, rect *bb,
                      unskewed_cols *uc);

#endif
