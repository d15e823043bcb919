/* The inner loops that SIMD code may replace, as a table of function
 * pointers chosen per frame (libjpeg-turbo style): filled with the scalar
 * reference (scalar.c) first, then upgraded best ISA first by dispatch.c,
 * capped by the settings and VSPLAT_ISA.  Each family has one file per ISA,
 * FAMILY-ISA.c, built with that ISA's flags (cmake/SimdFlags.cmake).
 *
 * Every kernel does one multiply and one add per element in the same order
 * as the scalar reference (no fused multiply-add), so each ISA gives
 * bit-identical results: images never depend on the machine, and a row's
 * split into vector body and tail (which depends on the tile) cannot change
 * a pixel. */
#ifndef VS_KERNELS_H
#define VS_KERNELS_H

#include "vsplat.h"

#include <stddef.h>
#include <stdint.h>

/* Tables of the post-shaded classification and LUT shading (src/shade_lut.h),
 * gathered per sheet from the frame so the kernels need no internal
 * headers.  The 8- and 16-bit tables have 4 bytes of padding at the end:
 * SIMD versions read them with 32-bit gathers and mask. */
typedef struct vs_shade_tabs {
    double vmin, scale;     /* table coordinate x = (float)((v - vmin) * scale) */
    const float *alpha;     /* [VS_KTAB]: opacity corrected for the slab, or
                               NULL: classify the gradients only           */
    float alpha_zero_x;     /* the opacity table reads 0 below this x
                               (vs_alpha_zero_x)                           */
    const float *color;     /* [VS_KTAB][3]                                   */
    float slab, two_slab;   /* slab thickness (post-gs gradients), and twice it
                               (divisor of the z central difference)        */
    float cd_wide;          /* post-cd's in-sheet differences: 0, the two-
                               point 0.5 (q[i+1] - q[i-1]); else w > 0 mixes
                               in the four-point stencil, (0.5 + 2w)
                               (q[i+1] - q[i-1]) - w (q[i+2] - q[i-2]), which
                               reads two pixels each side (w = 1/12: the
                               four-point stencil itself)                   */
    float cd_wide_z;        /* the same across sheets: 0, (qn - qp) / two_slab;
                               else w > 0, ((0.5 + 2w) (qn - qp) - w (qn2 -
                               qp2)) / slab                                 */
    float ppm, zpm;         /* gradient: view space -> eye frame per mm       */
    int nl;                 /* longitude bins                                 */
    const uint16_t *lambda_bin;
    const uint8_t *radius;
    const uint16_t *phi_bin;
    const float *diffuse, *specular;
} vs_shade_tabs;
/* The pre-integration table (src/preintegrate.h) as the kernels see it:
 * [n][n] entries over (front, back) of (opacity, premultiplied r g b). */
typedef struct vs_preint_tabs {
    const float *tab;
    float vmin, scale; /* coordinate x = (v - vmin) * scale, in [0, n - 1] */
    int n;
    /* entries (i, j) with i, j <= zero_x have opacity 0: a segment whose
     * three coordinates lie below zero_x is transparent, and a kernel may
     * skip its look-ups (0: none known) */
    float zero_x;
} vs_preint_tabs;

/* The cell of value v along one axis of that table and the fraction
 * within it: the reference every version follows (NaN and values below
 * the table take its first entry, values past it the last). */
static inline int vs_preint_cell(const vs_preint_tabs *P, float v, float *frac)
{
    float x = (v - P->vmin) * P->scale;
    const float top = (float)(P->n - 2);
    if (!(x > 0.0f)) x = 0.0f;
    const int i = x < top ? (int)x : P->n - 2;
    *frac = x < top + 1.0f ? x - (float)i : 1.0f;
    return i;
}

/* Channel c of the table at entry idx = i n + j, bilinear with the
 * fractions (fx along front, fy along back): the one formula every
 * look-up follows. */
static inline float vs_preint_bilerp(const vs_preint_tabs *P, size_t idx, float fx, float fy, int c)
{
    const float *e00 = P->tab + 4 * idx + c, *e10 = e00 + 4 * (size_t)P->n;
    const float u = e00[0] + fy * (e00[4] - e00[0]);
    const float v = e10[0] + fy * (e10[4] - e10[0]);
    return u + fx * (v - u);
}

/* Entries of the classification tables (VS_TF_TABLE in classify.h). */
#define VS_KTAB 4096

/* The table coordinate below which the linearly interpolated opacity
 * table t[VS_KTAB] reads exactly 0: x < i - 1 interpolates two zero
 * entries when t[0..i-1] are 0.  Classification skips its look-ups there. */
static inline float vs_alpha_zero_x(const float *t)
{
    int i = 0;
    while (i < VS_KTAB && t[i] == 0.0f) i++;
    return i == VS_KTAB ? (float)VS_KTAB : (float)(i - 1);
}

/* What project_brick needs: the view position of a brick's corner voxel,
 * the view matrix, and the box a voxel centre must reach to be kept (a
 * tile's buffer widened by the footprint: +-INFINITY keeps every voxel). */
typedef struct vs_project_in {
    float base[3];
    float m[3][3];
    float px, py;          /* footprint half-extent (pixels)              */
    float bx0, bx1, by0, by1; /* the buffer's first and last pixel centres */
} vs_project_in;
/* Widest row splat_voxel1 takes (floats); wider footprints use blocks in
 * memory (splat_block). */
#define VS_VOXEL1_MAX 64
/* Most sheets one voxel kernel may reach (the splat_voxel kernels). */
#define VS_MAX_SHEETS_VOXEL 64
/* Most voxels one brick holds (VS_BRICK^3, src/relevant.h). */
#define VS_PROJECT_MAX 512

/* Voxels one place_voxels call takes at most. */
#define VS_PLACE_BATCH 16
/* What place_voxels needs: the tile's occlusion map, the footprint block's
 * geometry and the slab tables of the depth integrals (src/activate.c,
 * src/block.h, src/footprint.h). */
typedef struct vs_place_in {
    const int *sat;         /* summed-area table of the tile's opaque pixels,
                               tw + 1 ints a row; NULL: no occlusion test    */
    int tx0, ty0, tw, th;   /* the tile's own pixels (image coordinates)     */
    float pad_x, pad_y;     /* the footprint's reach plus the seam (pixels)  */
    float rx0, ry0;         /* block half-extents (vs_block_geom)            */
    float phases;           /* VS_BLOCK_PHASES                               */
    int ox, oy;             /* image coordinates of buffer pixel (0, 0)      */
    float slab, rz;         /* slab thickness, kernel depth radius           */
    /* The depth integrals over the slabs opening .. opening + nd - 1 of a
     * voxel at depth z depend only on phi = z - (opening slab + rz), where
     * its kernel starts inside the first slab: rows of sw floats at
     * phi = r / sscale, r = 0..sn, interpolated linearly (vs_footprint
     * slab_d, slab_e); with_e: also the integrals of the depth derivative
     * (post-gs) */
    const float *sd, *se;
    float sscale;
    int sn, sw;
    int with_e;
    int opening, nd;        /* first sheet, and how many slabs from it       */
    /* the block's column and row factors (vs_block_factors): phase tables
     * of bx and ny entries a row (vs_block_geom colw, roww), or colw NULL
     * for none; bx, ny <= VS_VOXEL1_MAX */
    const float *colw, *roww;
    int bx, ny;
} vs_place_in;
/* Per voxel lane: its block's placement (vs_block_place_at, relative to
 * the buffer) and the depth integrals over slabs opening .. opening+nd-1
 * (sw floats a lane written, the ones past nd 0). */
typedef struct vs_placed {
    int bx[VS_PLACE_BATCH], by[VS_PLACE_BATCH]; /* block pixel (0,0) in the buffer */
    int qx[VS_PLACE_BATCH], qy[VS_PLACE_BATCH]; /* phase-table rows                */
    float fx[VS_PLACE_BATCH], fy[VS_PLACE_BATCH];
    float D[VS_PLACE_BATCH][VS_MAX_SHEETS_VOXEL];
    float E[VS_PLACE_BATCH][VS_MAX_SHEETS_VOXEL]; /* with_e only */
    /* with colw: the whole block's factors, columns (then 8 zeros, which
     * splat_voxel4 may read) and rows, as vs_block_factors computes them */
    float cw[VS_PLACE_BATCH][VS_VOXEL1_MAX + 8];
    float rw[VS_PLACE_BATCH][VS_VOXEL1_MAX];
} vs_placed;

/* A voxel's slab-table coordinate (vs_place_in): sscale (z - (opening slab
 * + rz)) within [0, sn], the row below it and the fraction past that row;
 * every ISA computes these floats with the same operations. */
static inline float vs_place_slab_x(const vs_place_in *P, float z)
{
    float x = (z - ((float)P->opening * P->slab + P->rz)) * P->sscale;
    x = x > 0.0f ? x : 0.0f;
    return x < (float)P->sn ? x : (float)P->sn;
}

/* Post-gs: the kernel's lattice ripple along one row of a sheet
 * (src/gs_ripple.h).  The row is taken in blocks of 8 pixels anchored at
 * absolute image x (block b: x = 8 b .. 8 b + 7), so that a pixel's term
 * is a function of the pixel alone, not of where its span starts (which
 * the tile decides).  Pixel i of a span is lane l = (m + i) & 7 of block
 * c = (m + i) >> 3, counted from the block of its first pixel, and gets
 *   v_j = (m[0][j] A_0 + m[1][j] A_1) + m[2][j] A_2,  A_a = P_a cl[a][l] + Q_a sl[a][l],
 * with P, Q of block c from vs_ripple_block: the row's phase (C, S) at
 * x = 0 turned by the block's xr[c] (cos, sin of each axis's phase at its
 * first pixel), then the terms ca, cb.  All but C, S, xr and m are the
 * same for every row of a frame (orthographic) or of a sheet. */
typedef struct vs_ripple_lanes {
    float ca[3], cb[3];
    float cl[3][8], sl[3][8];
    float m[3][3];
} vs_ripple_lanes;
typedef struct vs_ripple_row {
    float C[3], S[3];
    const float (*xr)[6]; /* block c's turn: cos of axis a at [c][a], sin at [c][3 + a] */
    int m;                /* the span's first pixel's lane in its block */
    const vs_ripple_lanes *L;
} vs_ripple_row;

/* P and Q (above) of block c: the one formula every kernel follows. */
static inline void vs_ripple_block(const vs_ripple_row *R, int c, float P[3], float Q[3])
{
    const vs_ripple_lanes *L = R->L;
    for (int a = 0; a < 3; a++) {
        const float xc = R->xr[c][a], xs = R->xr[c][3 + a];
        const float C = R->C[a] * xc - R->S[a] * xs, S = R->S[a] * xc + R->C[a] * xs;
        P[a] = L->ca[a] * C + L->cb[a] * S;
        Q[a] = L->cb[a] * C - L->ca[a] * S;
    }
}

typedef struct vs_kernels {
    vs_isa isa; /* the ISA cap in force (what the stats report) */
    /* row[i] += w * ex[i], i in [0, n) */
    void (*splat_row1)(float *row, const float *ex, float w, int n);
    /* row4[4i + c] += w[c] * ex[i]: four interleaved channels */
    void (*splat_row4)(float *row4, const float *ex, const float w[4], int n);
    /* front-to-back over one span: for alpha[i] > 0,
     *   w = (1 - acc[4i+3]) * alpha[i]; acc[4i+c] += w * rgb[3i+c]; acc[4i+3] += w (<= 1);
     * returns how many pixels crossed the opacity threshold thr */
    int (*composite)(float *acc, const float *alpha, const float *rgb, int n, float thr);
    /* a footprint block (src/block.h) into a sheet:
     *   dst[r ds + i] += w8[i % 8] * blk[r bs + i], r < rows, i < 8 nvec */
    void (*splat_block)(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                        const float w8[8]);
    /* a gradient-splat block (4 floats a pixel: h, h dx, h dy, h) into a
     * 4-channel sheet, mixing channels with m (4 rows of 3):
     *   dst[r ds + 4p + c] += (m[3c] h + m[3c+1] hdx) + m[3c+2] hdy,
     * r < rows, p < 2 nvec */
    void (*splat_block_mix)(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                            const float m[12]);
    /* post-cd step 1 over one span of a density sheet q (neighbour rows at
     * +-stride, sheets before/after qp, qn, and two before/after qp2, qn2):
     * alpha[i] = opacity table at q[i] (linear interpolation), and the
     * central-difference gradient
     *   g[3i..3i+2] = 0.5 (q[i+1] - q[i-1]), 0.5 (q[i+s] - q[i-s]), (qn[i] - qp[i]) / two_slab
     * (with T->cd_wide, the x and y differences as vs_shade_tabs says; with
     * T->cd_wide_z, the depth difference, which then reads qp2 and qn2)
     * at least where alpha[i] > 0: a kernel may leave g alone on a run of
     * pixels that are all transparent.  With T->alpha NULL (pre-integration
     * classifies the segment instead), alpha is left alone and g is written
     * for every i. */
    void (*classify_cd)(float *alpha, float *g, const float *q, const float *qp, const float *qn, const float *qp2,
                        const float *qn2, ptrdiff_t stride, int n, const vs_shade_tabs *T);
    /* post-gs step 1 over one span of a sheet of (density, three gradient
     * splats) per pixel: alpha[i] = opacity table at q4[4i], and
     * g[3i + c] = q4[4i + 1 + c] / slab - q4[4i] v_c(i) (v of R, vs_ripple_row;
     * R NULL: no such term) where classify_cd writes it */
    void (*classify_gs)(float *alpha, float *g, const float *q4, int n, const vs_shade_tabs *T,
                        const vs_ripple_row *R);
    /* step 2 (post-cd, post-gs) where alpha[i] > 0: the gradient g[3i..]
     * shaded through the normal LUT (vs_shade_lut_eval) times the colour
     * table at v[i * vstride], plus specular, replaces g[3i..]; other
     * pixels are left alone */
    void (*shade_lut)(float *g, const float *alpha, const float *v, int vstride, int n, const vs_shade_tabs *T);
    /* the Phong terms alone, for every i < n: d[i], s[i] = diffuse and
     * specular of the gradient g[3i..] through the normal LUT (pre-
     * integrated shading mixes them with the table's colours) */
    void (*shade_terms)(float *d, float *s, const float *g, int n, const vs_shade_tabs *T);
    /* pre-integrated opacity of n segments taken as two halves, f[i] to
     * m[i] and m[i] to b[i]: alpha[i] = a1 + (1 - a1) a2, each the table's
     * opacity interpolated bilinearly at its cells (vs_preint_cell):
     * u = e00 + fy (e01 - e00), v = e10 + fy (e11 - e10), u + fx (v - u) */
    void (*preint_alpha)(float *alpha, const float *f, const float *m, const float *b, int n,
                         const vs_preint_tabs *P);
    /* voxel transform and binning: for the n (<= VS_PROJECT_MAX) voxels of a
     * brick, vox[i] = di | dj << 3 | dk << 6, the view position
     *   x = ((base[0] + m[0][0] di) + m[0][1] dj) + m[0][2] dk   (y, z alike)
     * and, for those with !(x + px < bx0 || x - px > bx1 || y + py < by0 ||
     * y - py > by1), in order: keep[q] = i, xyz[3q..3q+2] = x, y, z.
     * Returns how many were kept. */
    int (*project_brick)(const uint16_t *vox, int n, const vs_project_in *P, uint16_t *keep, float *xyz);
    /* one density voxel into every sheet it reaches (post-cd; a footprint
     * block built in registers and added at once, src/block.h): row r of
     * the block is h[i] = cw[i] rw[r], 0 where not > thr, i < 8 nvec, and
     *   dst[s][r ds + i] += w[s] h[i],  s < ns, r < rows */
    void (*splat_voxel1)(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                         int rows, int nvec, float thr);
    /* the same for four channels (pre, post-alpha: the block holds h in
     * each channel of a pixel): pixel p of row r has h = cw[p] rw[r] (0
     * where not > thr), p < 2 nvec, and
     *   dst[s][r ds + 4p + c] += w[4s + c] h,  c < 4, s < ns, r < rows
     * cw must be readable (any values) up to a multiple of 8 floats */
    void (*splat_voxel4)(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                         int rows, int nvec, float thr);
    /* gradient splats of one voxel (post-gs, separable footprints): pixel p
     * of row r has h = cw[p] rw[r] (0 where not > thr) and the block layout
     * (h, h dx[p], h dy[r], h) of src/block.c, p < 2 nvec, and
     *   dst[s][r ds + 4p + c] += w[4s + c] layout[c],  c < 4, s < ns, r < rows
     * (vs_block_build and one splat_block a sheet, without the block in
     * memory); cw and dx must be readable up to a multiple of 8 floats */
    void (*splat_voxel_gs)(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                           const float *dx, const float *dy, int rows, int nvec, float thr);
    /* one gradient-splat section of a sheared footprint whose rows share
     * one column phase (post-gs; splat_block_mix on the block that
     * vs_block_build_skewed builds, without the block in memory): pixel p
     * of row r has h = cw[p] rw[r] (0 where not > thr), hx = h dx[p],
     * hy = h dy[r], and
     *   dst[r ds + 4p + c] += (m[3c] h + m[3c+1] hx) + m[3c+2] hy,  c < 4, p < 2 nvec
     * cw and dx must be readable up to a multiple of 8 floats */
    void (*splat_rows_mix)(float *dst, ptrdiff_t ds, const float *cw, const float *rw, const float *dx,
                           const float *dy, int rows, int nvec, float thr, const float m[12]);
    /* activation of n (<= VS_PLACE_BATCH) voxels whose centres x, y, z lie
     * at xyz[i stride ..]: bit i of the result is set unless voxel i is
     * occluded (P->sat: every tile pixel within pad of its centre opaque,
     * or none at all), and for those set, out's lane i holds the block
     * placement and the nd slab integrals
     *   D[j] = G((opening + j + 1) slab - z) - G((opening + j) slab - z)
     * and (with P->colw) the block's factors, exactly as src/activate.c and
     * src/block.h compute them one by one */
    unsigned (*place_voxels)(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out);
} vs_kernels;

/* Kernel types, for the tests and the kernel benchmark, which call the
 * versions directly. */
typedef void (*vs_splat_block_fn)(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                                  const float w8[8]);
typedef void (*vs_splat_rows_mix_fn)(float *dst, ptrdiff_t ds, const float *cw, const float *rw, const float *dx,
                                     const float *dy, int rows, int nvec, float thr, const float m[12]);
typedef void (*vs_splat_voxel1_fn)(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw,
                                   const float *rw, int rows, int nvec, float thr);
typedef void (*vs_splat_voxel_gs_fn)(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw,
                                     const float *rw, const float *dx, const float *dy, int rows, int nvec, float thr);
typedef unsigned (*vs_place_voxels_fn)(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out);
typedef int (*vs_project_brick_fn)(const uint16_t *vox, int n, const vs_project_in *P, uint16_t *keep, float *xyz);
typedef void (*vs_classify_cd_fn)(float *alpha, float *g, const float *q, const float *qp, const float *qn,
                                  const float *qp2, const float *qn2, ptrdiff_t stride, int n, const vs_shade_tabs *T);
typedef void (*vs_classify_gs_fn)(float *alpha, float *g, const float *q4, int n, const vs_shade_tabs *T,
                                  const vs_ripple_row *R);
typedef void (*vs_shade_lut_fn)(float *g, const float *alpha, const float *v, int vstride, int n,
                                const vs_shade_tabs *T);
typedef void (*vs_shade_terms_fn)(float *d, float *s, const float *g, int n, const vs_shade_tabs *T);
typedef void (*vs_preint_alpha_fn)(float *alpha, const float *f, const float *m, const float *b, int n,
                                   const vs_preint_tabs *P);
typedef int (*vs_composite_fn)(float *acc, const float *alpha, const float *rgb, int n, float thr);

/* The versions, by family: the scalar reference of every kernel is in
 * scalar.c, the SIMD ones in FAMILY-ISA.c (declared once here for the
 * dispatch, the tests and the kernel benchmark; call them only where the
 * CPU has the ISA).  A kernel without a version for an ISA takes the one
 * below it: where a version measured no faster it was not kept (the
 * post-shaded sheet kernels have no AVX-512 version, docs/PERFORMANCE.md). */

/* splat_row: splat_row1 (scalar only), splat_row4 */
void vs_splat_row1_scalar(float *row, const float *ex, float w, int n);
void vs_splat_row4_scalar(float *row4, const float *ex, const float w[4], int n);
void vs_splat_row4_sse4(float *row4, const float *ex, const float w[4], int n);
void vs_splat_row4_avx2(float *row4, const float *ex, const float w[4], int n);
void vs_splat_row4_avx512(float *row4, const float *ex, const float w[4], int n);

/* splat_block: splat_block, splat_block_mix, splat_rows_mix */
void vs_splat_block_scalar(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                           const float w8[8]);
void vs_splat_block_sse4(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                         const float w8[8]);
void vs_splat_block_avx2(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                         const float w8[8]);
void vs_splat_block_avx512(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                           const float w8[8]);
void vs_splat_block_mix_scalar(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                               const float m[12]);
void vs_splat_block_mix_sse4(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                             const float m[12]);
void vs_splat_block_mix_avx2(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                             const float m[12]);
void vs_splat_rows_mix_scalar(float *dst, ptrdiff_t ds, const float *cw, const float *rw, const float *dx,
                              const float *dy, int rows, int nvec, float thr, const float m[12]);
void vs_splat_rows_mix_avx2(float *dst, ptrdiff_t ds, const float *cw, const float *rw, const float *dx,
                            const float *dy, int rows, int nvec, float thr, const float m[12]);

/* splat_voxel: splat_voxel1, splat_voxel4, splat_voxel_gs */
void vs_splat_voxel1_scalar(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                            int rows, int nvec, float thr);
void vs_splat_voxel1_avx2(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                          int rows, int nvec, float thr);
void vs_splat_voxel1_avx512(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                            int rows, int nvec, float thr);
void vs_splat_voxel4_scalar(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                            int rows, int nvec, float thr);
void vs_splat_voxel4_avx2(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                          int rows, int nvec, float thr);
void vs_splat_voxel_gs_scalar(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw,
                              const float *rw, const float *dx, const float *dy, int rows, int nvec, float thr);
void vs_splat_voxel_gs_avx2(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                            const float *dx, const float *dy, int rows, int nvec, float thr);

/* place: place_voxels */
unsigned vs_place_voxels_scalar(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out);
unsigned vs_place_voxels_avx2(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out);
unsigned vs_place_voxels_avx512(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out);

/* project: project_brick */
int vs_project_brick_scalar(const uint16_t *vox, int n, const vs_project_in *P, uint16_t *keep, float *xyz);
int vs_project_brick_avx2(const uint16_t *vox, int n, const vs_project_in *P, uint16_t *keep, float *xyz);
int vs_project_brick_avx512(const uint16_t *vox, int n, const vs_project_in *P, uint16_t *keep, float *xyz);

/* classify: classify_cd, classify_gs */
void vs_classify_cd_scalar(float *alpha, float *g, const float *q, const float *qp, const float *qn,
                           const float *qp2, const float *qn2, ptrdiff_t stride, int n, const vs_shade_tabs *T);
void vs_classify_cd_avx2(float *alpha, float *g, const float *q, const float *qp, const float *qn, const float *qp2,
                         const float *qn2, ptrdiff_t stride, int n, const vs_shade_tabs *T);
void vs_classify_gs_scalar(float *alpha, float *g, const float *q4, int n, const vs_shade_tabs *T,
                           const vs_ripple_row *R);
void vs_classify_gs_avx2(float *alpha, float *g, const float *q4, int n, const vs_shade_tabs *T,
                         const vs_ripple_row *R);

/* shade: shade_lut, shade_terms */
void vs_shade_lut_scalar(float *g, const float *alpha, const float *v, int vstride, int n, const vs_shade_tabs *T);
void vs_shade_lut_avx2(float *g, const float *alpha, const float *v, int vstride, int n, const vs_shade_tabs *T);
void vs_shade_terms_scalar(float *d, float *s, const float *g, int n, const vs_shade_tabs *T);
void vs_shade_terms_avx2(float *d, float *s, const float *g, int n, const vs_shade_tabs *T);
void vs_preint_alpha_scalar(float *alpha, const float *f, const float *m, const float *b, int n,
                            const vs_preint_tabs *P);
void vs_preint_alpha_avx2(float *alpha, const float *f, const float *m, const float *b, int n,
                          const vs_preint_tabs *P);

/* composite */
int vs_composite_scalar(float *acc, const float *alpha, const float *rgb, int n, float thr);
int vs_composite_avx2(float *acc, const float *alpha, const float *rgb, int n, float thr);

/* Fill the table: scalar, then the best ISA <= cap this CPU supports
 * (dispatch.c). */
void vs_kernels_init(vs_kernels *k, vs_isa cap);
/* The ISA cap from VSPLAT_ISA (VS_ISA_AUTO if unset or unknown). */
vs_isa vs_isa_from_env(void);

#endif
