/* The per-tile sheet loop (paper §2 and §4): for each image-aligned sheet,
 * front to back, rasterize the kernel sections of the tile's voxels into the
 * tile's sheet buffer (which has a one-pixel seam for central differences),
 * then classify, estimate gradients, shade and composite the touched part of
 * the sheet, updating the tile's occlusion map (its accumulated opacity).
 *
 * A tile only reads shared, read-only frame data and writes its own pixels,
 * so tiles run in any order on any thread and the image is bit-identical for
 * every thread count. */
#include "finish.h"
#include "splat.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct rect {
    int x0, y0, x1, y1; /* half-open, buffer coordinates */
} rect;

static inline void rect_clear(rect *r)
{
    r->x0 = r->y0 = 1 << 30;
    r->x1 = r->y1 = -(1 << 30);
}
static inline int rect_empty(const rect *r) { return r->x0 >= r->x1 || r->y0 >= r->y1; }

/* Pixels of a sheet to shade: buffer rows [y0, y1), in row y the columns
 * [xa[y], xb[y]) (buffer coordinates; empty when xa[y] == xb[y]). */
typedef struct spans {
    int y0, y1;
    int *xa, *xb; /* indexed by buffer row */
} spans;

/* The geometry every rasterizer shares: where one kernel section lands. */
typedef struct section {
    float cx, cy;   /* centre in image coordinates (after the depth shift);
                       kept tile-independent so that every tiling computes
                       bit-identical weights */
    float D;        /* depth integral over the slab                          */
    float E;        /* exp(-k z1^2) - exp(-k z0^2), for the z gradient splat */
    float sc, is;   /* footprint scale (perspective; 1 when orthographic) and
                       its inverse: offsets in pixels times `is` are offsets
                       in the footprint's units (pixels at depth 0)          */
    const vs_block_geom *g; /* skewed tables at this scale, or NULL: an
                       exponential per pixel                                 */
} section;

typedef struct tile_ctx {
    const vs_frame *F;
    const vs_footprint *fp;
    int x0, y0, tw, th;  /* own pixels in image coordinates                 */
    int bw, bh;          /* buffer size: own pixels plus a one-pixel seam    */
    int stride;          /* pixels per buffer row: bw plus an apron of
                            VS_APRON pixels each side, which footprint
                            blocks may spill into (cleared, never shaded)   */
    float *blk;          /* scratch: one voxel's footprint block             */
    int ox, oy;          /* image coordinates of buffer pixel (0,0)          */
    float rx0;           /* footprint half-width without shift               */
    float *ex, *exd;     /* scratch: one footprint row of weights (bw each)  */
    int *rxa, *rxb;      /* scratch: per buffer row, the footprint's chord   */
    float *rey, *rdy;    /* scratch: per buffer row, its weight and offset   */
    float ry0;           /* footprint half-height without shift              */
} tile_ctx;

/* What every section on sheet k shares: its skewed tables (NULL: an
 * exponential per pixel) and, with perspective, its scale about the image
 * centre and the scale's inverse (1 when orthographic). */
typedef struct sheet_geom {
    const vs_block_geom *g;
    float sk, isk;
} sheet_geom;

static sheet_geom sheet_geom_of(const vs_frame *F, int k)
{
    sheet_geom sh = {F->use_skewed ? &F->skew : NULL, 1.0f, 1.0f};
    if (F->cam.persp) {
        const int i = k - F->sheet_k0;
        sh.g = i >= 0 && i < F->nsheet_skew && F->sheet_skew[i].ny > 0 ? &F->sheet_skew[i] : NULL;
        sh.sk = (float)vs_camera_sheet_scale(&F->cam, k, F->fp.slab);
        sh.isk = 1.0f / sh.sk;
    }
    return sh;
}

/* Compute the slab section of voxel at depth z for sheet k; 0 if empty.
 * (x, y) is the voxel's image position, with perspective its depth-0 one:
 * the section on sheet k's plane is centred on the same world point, which
 * appears scaled by the sheet's scale about the image centre. */
static inline int make_section(const tile_ctx *t, const sheet_geom *sh, float x, float y, float z, int k,
                               section *sec)
{
    const vs_footprint *fp = t->fp;
    float slab = (float)fp->slab;
    float z0 = (float)k * slab - z, z1 = z0 + slab;
    float D = vs_fp_depth(fp, z1) - vs_fp_depth(fp, z0);
    if (!(D > 0.0f)) return 0;
    float rz = (float)fp->rz;
    float c0 = z0 < -rz ? -rz : (z0 > rz ? rz : z0);
    float c1 = z1 < -rz ? -rz : (z1 > rz ? rz : z1);
    float kap = (float)fp->kappa;
    float e0 = 0.0f, e1 = 0.0f;
    /* the depth derivative's integral: for gradient splats and the
     * centroid of a sheared footprint only */
    if (fp->sheared || t->F->pipeline == VS_PIPELINE_POST_GS) {
        e0 = vs_fp_exp(fp, kap * c0 * c0);
        e1 = vs_fp_exp(fp, kap * c1 * c1);
        if (fabsf(c0) >= rz) e0 = 0.0f;
        if (fabsf(c1) >= rz) e1 = 0.0f;
    }
    sec->D = D;
    sec->E = e1 - e0;
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
        float zbar = (e0 - e1) / (2.0f * kap * D);
        /* a centroid lies inside its slab; in a kernel's tail D and e0 - e1
         * are both tiny and their tabulated ratio can run away, which would
         * throw the footprint outside the tiles it was binned to */
        if (!(zbar >= c0)) zbar = c0;
        if (zbar > c1) zbar = c1;
        sec->cx += fp->sx * zbar * sec->sc;
        sec->cy += fp->sy * zbar * sec->sc;
    }
    return 1;
}

/* Row range of a footprint inside the buffer (buffer row y is image row
 * y + oy, oy = y0 - 1). */
static inline int rows_of(const tile_ctx *t, const section *sec, int *ya, int *yb)
{
    const float ry = t->ry0 * sec->sc;
    int a = (int)ceilf(sec->cy - ry) - t->oy, b = (int)floorf(sec->cy + ry) - t->oy;
    if (a < 0) a = 0;
    if (b > t->bh - 1) b = t->bh - 1;
    *ya = a;
    *yb = b;
    return a <= b;
}

/* Column range of the footprint row dy below its centre (dy in footprint
 * units); *er is the row's exponent, *cxr its centre in pixels. */
static inline int cols_of(const tile_ctx *t, const section *sec, float dy, float *er, float *cxr,
                          int *xa, int *xb)
{
    const vs_footprint *fp = t->fp;
    float e = fp->row_k * dy * dy;
    if (e >= (float)fp->emax) return 0;
    float hw = sqrtf(((float)fp->emax - e) / fp->A) * sec->sc;
    float c = sec->cx + fp->row_shift * dy * sec->sc;
    int a = (int)ceilf(c - hw) - t->ox, b = (int)floorf(c + hw) - t->ox;
    if (a < 0) a = 0;
    if (b > t->bw - 1) b = t->bw - 1;
    *er = e;
    *cxr = c;
    *xa = a;
    *xb = b;
    return a <= b;
}

static inline void grow(rect *bb, int xa, int xb, int y)
{
    if (xa < bb->x0) bb->x0 = xa;
    if (xb + 1 > bb->x1) bb->x1 = xb + 1;
    if (y < bb->y0) bb->y0 = y;
    if (y + 1 > bb->y1) bb->y1 = y + 1;
}

static inline void merge_box(rect *bb, const rect *r)
{
    if (rect_empty(r)) return;
    if (r->x0 < bb->x0) bb->x0 = r->x0;
    if (r->y0 < bb->y0) bb->y0 = r->y0;
    if (r->x1 > bb->x1) bb->x1 = r->x1;
    if (r->y1 > bb->y1) bb->y1 = r->y1;
}

/* General (sheared or rotated-ellipse) footprints without skewed tables:
 * the weights of row y into t->ex[xa..xb] and the row's centre in pixels,
 * an exponential per pixel; 0 if the row misses the footprint. */
static int row_footprint(const tile_ctx *t, const section *sec, int y, int *xa, int *xb, float *cxr)
{
    const vs_footprint *fp = t->fp;
    float dy = ((float)(y + t->oy) - sec->cy) * sec->is, er;
    if (!cols_of(t, sec, dy, &er, cxr, xa, xb)) return 0;
    for (int x = *xa; x <= *xb; x++) {
        float dx = ((float)(x + t->ox) - *cxr) * sec->is;
        t->ex[x] = vs_fp_exp(fp, er + fp->A * dx * dx);
    }
    return 1;
}

/* Density only (post-cd): one channel. */
static void raster1(const tile_ctx *t, const section *sec, float w, float *q, rect *bb)
{
    int ya, yb, xa, xb;
    float cxr;
    if (!rows_of(t, sec, &ya, &yb)) return;
    w *= sec->D;
    for (int y = ya; y <= yb; y++) {
        if (!row_footprint(t, sec, y, &xa, &xb, &cxr)) continue;
        t->F->kern.splat_row1(q + (size_t)y * t->stride + xa, t->ex + xa, w, xb - xa + 1);
        grow(bb, xa, xb, y);
    }
}

/* Four interleaved channels with their own weights (pre, post-alpha). */
static void raster4(const tile_ctx *t, const section *sec, const float w4[4], float *buf, rect *bb)
{
    int ya, yb, xa, xb;
    float cxr;
    if (!rows_of(t, sec, &ya, &yb)) return;
    float w[4] = {w4[0] * sec->D, w4[1] * sec->D, w4[2] * sec->D, w4[3] * sec->D};
    for (int y = ya; y <= yb; y++) {
        if (!row_footprint(t, sec, y, &xa, &xb, &cxr)) continue;
        t->F->kern.splat_row4(buf + ((size_t)y * t->stride + xa) * 4, t->ex + xa, w, xb - xa + 1);
        grow(bb, xa, xb, y);
    }
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

/* 0 when the block is too wide for the fused kernels. */
static int unskewed_place_cols(const tile_ctx *t, const vs_block_geom *g, const vs_block_place *p, float cx, int ch,
                               unskewed_cols *uc)
{
    const int ppv = 8 / ch, nvec = (g->nx * ch + 7) / 8;
    const int bx = p->x - t->ox;
    uc->bx = bx;
    uc->v0 = bx < 0 ? -bx / ppv : 0;
    uc->v1 = t->bw - bx <= 0 ? 0 : (t->bw - bx + ppv - 1) / ppv;
    if (uc->v1 > nvec) uc->v1 = nvec;
    if (uc->v0 >= uc->v1) return 1;
    if ((uc->v1 - uc->v0) * ppv > VS_VOXEL1_MAX) return 0;
    const int n = (uc->v1 - uc->v0) * ppv;
    vs_block_col_factors(g, p, uc->v0 * ppv, uc->v1 * ppv, uc->cw);
    /* splat_voxel4 reads cw up to a multiple of 8 floats: defined zeros
     * past the factors (not the whole array: this runs per section) */
    if (ch == 4) memset(uc->cw + n, 0, 8 * sizeof(float));
    if (t->F->pipeline == VS_PIPELINE_POST_GS) { /* as vs_block_build_skewed's gradient layout */
        for (int i = 0; i < n; i++) uc->dx[i] = (float)(p->x + uc->v0 * ppv + i) - cx;
        memset(uc->dx + n, 0, 8 * sizeof(float));
    }
    return 1;
}

/* Post-gs: raster_gs's splats with offsets in pixels (dxs from the centre,
 * dy) turned into footprint units by `is`, as a matrix taking a pixel's
 * (h, h dxs, h dy) to its four channels; the row-centre offset is
 * dxs - row_shift dy:
 *   q += wD h,  gx += -2 wD A dx,  gy += -2 wD (B dx + k dy),
 *   gz += h wE - 2 wD (Qzx dxs + Qzy dy) */
static void gs_mix(const vs_footprint *fp, const section *sec, float w, float m[12])
{
    const float wD = w * sec->D, wE = w * sec->E, is = sec->is, rs = fp->row_shift;
    const float a = -2.0f * wD * fp->A * is, b = -2.0f * wD * fp->B * is, k = -2.0f * wD * fp->row_k * is;
    const float mm[12] = {wD, 0.0f, 0.0f,
                          0.0f, a, -a * rs,
                          0.0f, b, -b * rs + k,
                          wE, -2.0f * wD * (float)fp->Qzx * is, -2.0f * wD * (float)fp->Qzy * is};
    memcpy(m, mm, sizeof mm);
}

static void unskewed_splat_rows(const tile_ctx *t, const vs_block_geom *g, const vs_block_place *p,
                                const unskewed_cols *uc, const section *sec, const float w4[4], int ch, float *dst,
                                rect *bb)
{
    const vs_frame *F = t->F;
    const int ppv = 8 / ch, v0 = uc->v0, v1 = uc->v1, bx = uc->bx;
    const int by = p->y - t->oy;
    const int j0 = by < 0 ? -by : 0, j1 = t->bh - by < g->ny ? t->bh - by : g->ny;
    if (j0 >= j1 || v0 >= v1) return;
    const ptrdiff_t ds = (ptrdiff_t)t->stride * ch;
    float *const d = dst + (ptrdiff_t)(by + j0) * ds + (ptrdiff_t)(bx + v0 * ppv) * ch;
    float rw[VS_BLOCK_MAX_SPAN], w[4];
    const float D = sec->D;
    vs_block_row_factors(g, p, j0, j1, rw);
    if (F->pipeline == VS_PIPELINE_POST_GS) {
        float m[12], dy[VS_BLOCK_MAX_SPAN];
        gs_mix(t->fp, sec, w4[0], m);
        for (int j = j0; j < j1; j++) dy[j - j0] = (float)(p->y + j) - sec->cy;
        F->kern.splat_rows_mix(d, ds, uc->cw, rw, uc->dx, dy, j1 - j0, v1 - v0, g->thr, m);
    } else if (ch == 1) {
        w[0] = w4[0] * D;
        F->kern.splat_voxel1(&d, w, 1, ds, uc->cw, rw, j1 - j0, v1 - v0, g->thr);
    } else {
        for (int c = 0; c < 4; c++) w[c] = w4[c] * D;
        F->kern.splat_voxel4(&d, w, 1, ds, uc->cw, rw, j1 - j0, v1 - v0, g->thr);
    }
    const rect box = {bx + v0 * ppv, by + j0, bx + v1 * ppv, by + j1};
    merge_box(bb, &box);
}

/* One section through the fused kernels; 0 when the block is too wide for
 * them.  uc: the columns of an earlier section of the same voxel, reused
 * when it had the same tables and centre x (else placed anew), or NULL. */
static int raster_unskewed(const tile_ctx *t, const section *sec, const float w4[4], int ch, float *dst, rect *bb,
                           unskewed_cols *uc)
{
    const vs_block_geom *g = sec->g;
    unskewed_cols own;
    vs_block_place p;
    vs_block_place_at(g, sec->cx, sec->cy, &p);
    const int by = p.y - t->oy;
    if (by >= t->bh || by + g->ny <= 0) return 1; /* no row inside the buffer */
    if (!uc) {
        uc = &own;
        uc->g = NULL;
    }
    if (uc->g != g || !(uc->cx == sec->cx)) {
        uc->g = NULL;
        if (!unskewed_place_cols(t, g, &p, sec->cx, ch, uc)) return 0;
        uc->g = g;
        uc->cx = sec->cx;
    }
    unskewed_splat_rows(t, g, &p, uc, sec, w4, ch, dst, bb);
    return 1;
}

/* A general footprint as one skewed block (src/block.h) added by the
 * block kernel: density (post-cd, ch 1) or four channels with their own
 * weights (pre, post-alpha), or for post-gs (h, h dx, h dy, h) mixed into
 * density and gradient splats by splat_block_mix.  Only the rows inside the
 * buffer and the vectors overlapping it are added; a vector may spill into
 * the apron.  Footprints whose rows share one column phase (row_shift 0)
 * go through raster_unskewed instead unless too wide for its kernels.
 * uc: as for raster_unskewed (NULL: nothing to share). */
static void raster_skewed(const tile_ctx *t, const section *sec, const float w4[4], int ch, float *dst, rect *bb,
                          unskewed_cols *uc)
{
    const vs_frame *F = t->F;
    const vs_block_geom *g = sec->g;
    const int ppv = 8 / ch, bs = 8 * F->skew_maxvec, gs = F->pipeline == VS_PIPELINE_POST_GS;
    if (t->fp->row_shift == 0.0f && raster_unskewed(t, sec, w4, ch, dst, bb, uc)) return;
    int x, y, nvec;
    vs_block_build_skewed(g, t->fp->row_shift, sec->cx, sec->cy, ch, gs, F->skew_maxvec, t->blk, &x, &y, &nvec);
    const int by = y - t->oy, bx = x - t->ox;
    const int j0 = by < 0 ? -by : 0, j1 = t->bh - by < g->ny ? t->bh - by : g->ny;
    const int v0 = bx < 0 ? -bx / ppv : 0;
    int v1 = t->bw - bx <= 0 ? 0 : (t->bw - bx + ppv - 1) / ppv;
    if (v1 > nvec) v1 = nvec;
    if (j0 >= j1 || v0 >= v1) return;
    const ptrdiff_t ds = (ptrdiff_t)t->stride * ch;
    const ptrdiff_t off = (ptrdiff_t)(by + j0) * ds + (ptrdiff_t)(bx + v0 * ppv) * ch;
    const float *src = t->blk + (size_t)j0 * bs + 8 * v0;
    if (gs) {
        float m[12];
        gs_mix(t->fp, sec, w4[0], m);
        F->kern.splat_block_mix(dst + off, ds, src, bs, j1 - j0, v1 - v0, m);
    } else {
        float w8[8];
        for (int c = 0; c < 8; c++) w8[c] = w4[ch == 1 ? 0 : c % 4] * sec->D;
        F->kern.splat_block(dst + off, ds, src, bs, j1 - j0, v1 - v0, w8);
    }
    const rect box = {bx + v0 * ppv, by + j0, bx + v1 * ppv, by + j1};
    merge_box(bb, &box);
}

/* Density plus the three gradient splats dH/dx, dH/dy, dH/dz (FH'):
 * grad h = -2 Q v h; in-sheet (Qxx d)_x = A dx_row, (Qxx d)_y = B dx + row_k dy
 * (d relative to the shifted centre); the z part integrates exactly to
 * E - 2 D (Qzx d_x + Qzy d_y).  Layout: q, gx, gy, gz per pixel.  Offsets
 * are in footprint units, so with perspective the gradient is per pixel at
 * depth 0 for every voxel, whatever its own scale. */
static void raster_gs(const tile_ctx *t, const section *sec, float w, float *buf, rect *bb)
{
    const vs_footprint *fp = t->fp;
    int ya, yb;
    if (!rows_of(t, sec, &ya, &yb)) return;
    float wD = w * sec->D, wE = w * sec->E;
    float A = fp->A, B = fp->B, rk = fp->row_k;
    float qzx = (float)fp->Qzx, qzy = (float)fp->Qzy, rs = fp->row_shift;
    for (int y = ya; y <= yb; y++) {
        float dy = ((float)(y + t->oy) - sec->cy) * sec->is, er, cxr;
        int xa, xb;
        if (!cols_of(t, sec, dy, &er, &cxr, &xa, &xb)) continue;
        float *row = buf + (size_t)y * t->stride * 4;
        for (int x = xa; x <= xb; x++) {
            float dx = ((float)(x + t->ox) - cxr) * sec->is;
            float h = vs_fp_exp(fp, er + A * dx * dx);
            float dxs = dx + rs * dy; /* x offset from the shifted centre */
            float *p = row + 4 * x;
            p[0] += wD * h;
            p[1] += -2.0f * wD * h * (A * dx);
            p[2] += -2.0f * wD * h * (B * dx + rk * dy);
            p[3] += h * (wE - 2.0f * wD * (qzx * dxs + qzy * dy));
        }
        grow(bb, xa, xb, y);
    }
}

/* Early splat elimination.  The paper tests the occlusion map at the
 * projected voxel centre; culling a voxel whose centre is covered but whose
 * footprint still reaches open pixels removes density from their sheets and
 * bends their gradients (visible as rings on an opaque sphere).  So, as in
 * the occlusion test of Mueller et al. [22], we test the footprint's whole
 * extent (plus the one-pixel seam the central differences read): a voxel is
 * culled only if every pixel of the tile it can affect is opaque.  A
 * summed-area table of the tile's opaque pixels answers that in O(1); it is
 * rebuilt from row `from` on, the first whose opaque pixels changed. */
static void build_sat(const tile_ctx *t, const float *acc, float thr, int *sat, int from)
{
    int w = t->tw + 1;
    if (from == 0)
        for (int x = 0; x < w; x++) sat[x] = 0;
    for (int y = from; y < t->th; y++) {
        int run = 0;
        sat[(y + 1) * w] = 0;
        for (int x = 0; x < t->tw; x++) {
            run += acc[4 * (y * t->tw + x) + 3] >= thr;
            sat[(y + 1) * w + x + 1] = sat[y * w + x + 1] + run;
        }
    }
}

static void clear_rect(float *buf, int stride, int ch, const rect *r)
{
    if (rect_empty(r)) return;
    for (int y = r->y0; y < r->y1; y++)
        memset(buf + ((ptrdiff_t)y * stride + r->x0) * ch, 0, (size_t)(r->x1 - r->x0) * ch * sizeof(float));
}

/* A voxel of an expanded brick, from its first sheet to its last. */
typedef struct pend {
    float x, y, z; /* view-space centre (perspective: x, y at depth 0) */
    uint32_t v;    /* linear index in the volume                    */
    int kl;        /* last sheet (lowered when the voxel is culled) */
    float w[4];    /* splat weights before the slab's depth integral */
} pend;

/* The voxels whose first sheet is one sheet, in the order they came. */
typedef struct pend_bucket {
    pend *p;
    int n, cap;
} pend_bucket;

/* Per tile: the voxels of expanded bricks in buckets by first sheet, each
 * bucket one array (read in order when its sheet opens).  A sheet receives
 * its voxels in (first sheet, brick, voxel) order whatever the tiling or
 * thread count, so the sums are bit-identical. */
typedef struct tile_state {
    const tile_ctx *t;
    pend_bucket *bk;  /* bucket of sheet k at k - kmin                   */
    pend *spare;      /* an emptied bucket's array, for the next new one  */
    int spare_cap;
    int kmin, kmax;
    pend **active;    /* sheet-at-a-time path: voxels overlapping the sheet */
    float (*abox)[5]; /* perspective: each active voxel's voxel_box (box
                         and scale), computed once, when it is admitted */
    int nactive, cap_active;
    const float *acc; /* the tile's accumulation (occlusion map = alpha)   */
    const int *sat;   /* summed-area table of opaque pixels                */
    const int *opaque;
    vs_worker_stats *ws;
    int failed;
} tile_state;

static inline float lookup_corr(const vs_frame *F, const float *table, float v);
static inline void lookup_color(const vs_frame *F, float v, float rgb[3]);

/* Splat weights of the voxels p[lane], lane in the mask `live` (at most
 * VS_PLACE_BATCH), from their linear index in the volume: density (post),
 * or classified colour times the Phong terms of its grid gradient
 * (pre-shading: once per voxel and view).  The normal-table look-ups are a
 * chain of three dependent loads that miss the cache; each level is issued
 * for the whole batch before the next, so that the misses of different
 * voxels overlap. */
static void voxel_weights_batch(const vs_frame *F, const pend *p, unsigned live, float w[][4])
{
    const float bscale = (float)(F->fp.b / F->fp.slab);
    if (F->pipeline == VS_PIPELINE_POST_CD || F->pipeline == VS_PIPELINE_POST_GS) {
        for (unsigned m = live; m; m &= m - 1) {
            const int l = __builtin_ctz(m);
            w[l][0] = vs_volume_density(F->vol, p[l].v) * bscale;
            w[l][1] = w[l][2] = w[l][3] = 0.0f;
        }
        return;
    }
    const int *dims = F->vol->dims;
    const vs_camera *cam = &F->cam;
    const vs_shade_lut *lut = &F->lut;
    float rgb[VS_PLACE_BATCH][3], alpha[VS_PLACE_BATCH], val[VS_PLACE_BATCH], d[VS_PLACE_BATCH],
        sp[VS_PLACE_BATCH];
    int cell[VS_PLACE_BATCH], zrow[VS_PLACE_BATCH], li[VS_PLACE_BATCH], r[VS_PLACE_BATCH];
    for (unsigned m = live; m; m &= m - 1) {
        const int l = __builtin_ctz(m);
        const uint32_t v = p[l].v;
        val[l] = vs_volume_density(F->vol, v);
        alpha[l] = vs_classify_alpha(F->cls, val[l]);
        lookup_color(F, val[l], rgb[l]);
        float g[3];
        vs_volume_grid_gradient(F->vol, (int)(v % (uint32_t)dims[0]), (int)(v / (uint32_t)dims[0] % (uint32_t)dims[1]),
                                (int)(v / ((uint32_t)dims[0] * (uint32_t)dims[1])), v, g);
        double gw[3] = {g[0] / F->spacing[0], g[1] / F->spacing[1], g[2] / F->spacing[2]};
        double n[3] = {gw[0] * cam->right[0] + gw[1] * cam->right[1] + gw[2] * cam->right[2],
                       -(gw[0] * cam->up[0] + gw[1] * cam->up[1] + gw[2] * cam->up[2]),
                       gw[0] * cam->dir[0] + gw[1] * cam->dir[1] + gw[2] * cam->dir[2]};
        if (F->s->exact_normals) {
            double dd, ss;
            vs_light_eval(&F->light, n, &dd, &ss);
            d[l] = (float)dd;
            sp[l] = (float)ss;
        } else {
            cell[l] = vs_shade_lut_cell((float)n[0], (float)n[1], (float)n[2], &zrow[l]);
        }
    }
    if (!F->s->exact_normals) { /* vs_shade_lut_eval, a level at a time */
        for (unsigned m = live; m; m &= m - 1) {
            const int l = __builtin_ctz(m);
            li[l] = lut->lambda_bin[cell[l]];
            r[l] = lut->radius[cell[l]];
        }
        for (unsigned m = live; m; m &= m - 1) {
            const int l = __builtin_ctz(m);
            const int pi = lut->phi_bin[zrow[l] + r[l]];
            li[l] += pi * lut->nl;
        }
        for (unsigned m = live; m; m &= m - 1) {
            const int l = __builtin_ctz(m);
            d[l] = lut->diffuse[li[l]];
            sp[l] = lut->specular[li[l]];
        }
    }
    for (unsigned m = live; m; m &= m - 1) {
        const int l = __builtin_ctz(m);
        for (int i = 0; i < 3; i++) w[l][i] = (rgb[l][i] * d[l] + sp[l]) * alpha[l] * bscale;
        w[l][3] = (F->pipeline == VS_PIPELINE_PRE ? alpha[l] : val[l]) * bscale;
    }
}

/* The same for one voxel at linear index v. */
static void voxel_weights(const vs_frame *F, uint32_t v, float w[4])
{
    const pend one = {.v = v};
    voxel_weights_batch(F, &one, 1u, (float(*)[4])w);
}

/* Is every tile pixel that a footprint centred in [x0,x1] x [y0,y1] and
 * scaled by at most sc (plus the central-difference seam) can reach already
 * opaque? */
static inline int box_occluded_pad(const tile_ctx *t, const int *sat, float x0, float x1, float y0, float y1,
                                   float px, float py)
{
    int xa = vs_ifloor(x0 - px) - t->x0, xb = vs_iceil(x1 + px) - t->x0;
    int ya = vs_ifloor(y0 - py) - t->y0, yb = vs_iceil(y1 + py) - t->y0;
    if (xa < 0) xa = 0;
    if (ya < 0) ya = 0;
    if (xb > t->tw - 1) xb = t->tw - 1;
    if (yb > t->th - 1) yb = t->th - 1;
    if (xa > xb || ya > yb) return 1; /* touches no pixel of this tile */
    int w = t->tw + 1;
    int sum = sat[(yb + 1) * w + xb + 1] - sat[ya * w + xb + 1] - sat[(yb + 1) * w + xa] + sat[ya * w + xa];
    return sum == (xb - xa + 1) * (yb - ya + 1);
}

/* The same with the frame's footprint reach scaled by sc. */
static int box_occluded(const tile_ctx *t, const int *sat, float x0, float x1, float y0, float y1, float sc)
{
    const vs_frame *F = t->F;
    return box_occluded_pad(t, sat, x0, x1, y0, y1, (float)F->pad_x * sc, (float)F->pad_y * sc);
}

/* Perspective: the image box of a voxel's section centres over the sheets
 * its kernel reaches (their middle depths lie within half a slab of the
 * kernel's depth extent), (x, y) its depth-0 position, and the largest
 * scale. */
static void voxel_box(const vs_frame *F, float x, float y, float z, float box[4], float *sc)
{
    const double reach = F->fp.rz + 0.5 * F->fp.slab;
    const double zn = z - reach > F->cam.near_z ? z - reach : F->cam.near_z;
    double b[4];
    vs_camera_depth_box(&F->cam, x, x, y, y, zn, z + reach, b);
    for (int i = 0; i < 4; i++) box[i] = (float)b[i];
    *sc = (float)vs_camera_scale(&F->cam, zn);
}

_Static_assert(VS_MAX_VSPAN <= VS_MAX_SHEETS_VOXEL, "the splat_voxel kernels take every sheet a kernel reaches");
_Static_assert(VS_BRICK == 8 && VS_PROJECT_MAX >= VS_BRICK * VS_BRICK * VS_BRICK,
               "project_brick (src/kernels.h) decodes 3-bit brick offsets of at most 512 voxels");

/* Room for one more voxel in a bucket (a new bucket takes the spare array
 * of an emptied one); 0 when out of memory. */
static int grow_bucket(tile_state *ts, pend_bucket *bk)
{
    if (!bk->p && ts->spare) {
        bk->p = ts->spare;
        bk->cap = ts->spare_cap;
        ts->spare = NULL;
        return 1;
    }
    const int cap = bk->cap ? 2 * bk->cap : 256;
    pend *np = realloc(bk->p, (size_t)cap * sizeof *np);
    if (!np) return 0;
    bk->p = np;
    bk->cap = cap;
    return 1;
}

/* A bucket no sheet reads again gives its array to the next new one. */
static void retire_bucket(tile_state *ts, pend_bucket *bk)
{
    if (!ts->spare || ts->spare_cap < bk->cap) {
        free(ts->spare);
        ts->spare = bk->p;
        ts->spare_cap = bk->cap;
    } else {
        free(bk->p);
    }
    bk->p = NULL;
    bk->n = bk->cap = 0;
}

/* Open brick b: cull it whole if its footprints can only land on opaque
 * pixels, else project its voxels and bucket those that reach this tile. */
static void expand_brick(tile_state *ts, uint32_t b, int opening)
{
    const tile_ctx *t = ts->t;
    const vs_frame *F = t->F;
    const struct vs_brick_view *bv = &F->bview[b];
    const vs_brick *br = &F->rel->bricks[b];
    if (F->s->occlusion && *ts->opaque > 0 && box_occluded(t, ts->sat, bv->x0, bv->x1, bv->y0, bv->y1, bv->sc)) {
        ts->ws->culled += br->count;
        return;
    }
    const float slab = (float)F->fp.slab, rz = (float)F->fp.rz;
    const float px = (float)F->pad_x, py = (float)F->pad_y;
    const float bx0 = (float)t->ox, bx1 = (float)(t->ox + t->bw - 1);
    const float by0 = (float)t->oy, by1 = (float)(t->oy + t->bh - 1);
    /* voxel centres from the brick's lowest corner in float: a voxel lies
     * at most a brick from it, so this is as exact as the float result and,
     * depending on the brick alone, the same in every tile */
    float base[3], m[3][3];
    {
        const double idx0[3] = {br->i0, br->j0, br->k0};
        double p0[3];
        vs_camera_index_to_view0(&F->cam, idx0, p0);
        for (int r = 0; r < 3; r++) {
            base[r] = (float)p0[r];
            for (int a = 0; a < 3; a++) m[r][a] = (float)F->cam.M[r][a];
        }
    }
    const float near_z = (float)F->cam.near_z;
    const uint32_t row = (uint32_t)F->vol->dims[0], plane = row * (uint32_t)F->vol->dims[1];
    const uint32_t first = br->i0 + row * br->j0 + plane * br->k0; /* linear index of the brick's corner */
    /* transform and bin (a kernel); with perspective the box test follows
     * per voxel, as its footprint's size depends on its depth */
    vs_project_in P;
    memcpy(P.base, base, sizeof base);
    memcpy(P.m, m, sizeof m);
    P.px = px;
    P.py = py;
    P.bx0 = F->cam.persp ? -INFINITY : bx0;
    P.bx1 = F->cam.persp ? INFINITY : bx1;
    P.by0 = F->cam.persp ? -INFINITY : by0;
    P.by1 = F->cam.persp ? INFINITY : by1;
    uint16_t keep[VS_PROJECT_MAX];
    float xyz[3 * VS_PROJECT_MAX];
    const vs_voxel *vox = F->rel->voxels + br->start;
    const int nkeep = F->kern.project_brick(vox, (int)br->count, &P, keep, xyz);
    for (int q = 0; q < nkeep; q++) {
        const vs_voxel vx = vox[keep[q]];
        const uint32_t v = first + VS_VOXEL_DI(vx) + row * VS_VOXEL_DJ(vx) + plane * VS_VOXEL_DK(vx);
        const float x = xyz[3 * q], y = xyz[3 * q + 1], z = xyz[3 * q + 2];
        if (F->cam.persp) {
            float box[4] = {x, x, y, y}, sc = 1.0f;
            if (z - rz < near_z) continue; /* the kernel crosses the near plane */
            voxel_box(F, x, y, z, box, &sc);
            if (box[1] + px * sc < bx0 || box[0] - px * sc > bx1 || box[3] + py * sc < by0 || box[2] - py * sc > by1)
                continue; /* not this tile */
        }
        int kf = vs_ifloor((z - rz) / slab), kl = vs_ifloor((z + rz) / slab);
        if (kf < opening) kf = opening; /* rounding guard: the brick bound is conservative */
        if (kl > ts->kmax) kl = ts->kmax;
        if (kl < kf) continue;
        pend_bucket *bk = &ts->bk[kf - ts->kmin];
        if (bk->n == bk->cap && !grow_bucket(ts, bk)) {
            ts->failed = 1;
            return;
        }
        pend *e = &bk->p[bk->n++];
        e->x = x;
        e->y = y;
        e->z = z;
        e->v = v;
        e->kl = kl;
        if (!F->use_blocks) voxel_weights(F, v, e->w); /* else once it survives culling */
    }
}

/* Sheet at a time (general footprints): rasterize sheet k into `dst` from
 * the voxels overlapping it; retire those that ended, admit those that start
 * here, cull occluded ones. */
static void rasterize_sheet(tile_state *ts, int k, float *dst, rect *bb)
{
    const tile_ctx *t = ts->t;
    const vs_frame *F = t->F;
    const int persp = F->cam.persp;
    const sheet_geom sh = sheet_geom_of(F, k);
    int keep = 0;
    for (int a = 0; a < ts->nactive; a++)
        if (ts->active[a]->kl >= k) {
            if (persp) memcpy(ts->abox[keep], ts->abox[a], sizeof *ts->abox);
            ts->active[keep++] = ts->active[a];
        }
    ts->nactive = keep;
    /* bucket k is complete (bricks open no later than their first sheet),
     * so its array no longer moves and the pointers stay valid */
    const pend_bucket *bk = &ts->bk[k - ts->kmin];
    for (int i = 0; i < bk->n; i++) {
        if (ts->nactive == ts->cap_active) {
            int cap = ts->cap_active ? 2 * ts->cap_active : 1024;
            pend **na = realloc(ts->active, (size_t)cap * sizeof *na);
            if (na) ts->active = na;
            float(*nb)[5] = persp && na ? realloc(ts->abox, (size_t)cap * sizeof *nb) : NULL;
            if (nb) ts->abox = nb;
            if (!na || (persp && !nb)) {
                ts->failed = 1;
                return;
            }
            ts->cap_active = cap;
        }
        const pend *e = &bk->p[i];
        if (persp) /* the box of its sections over all its sheets */
            voxel_box(F, e->x, e->y, e->z, ts->abox[ts->nactive], &ts->abox[ts->nactive][4]);
        ts->active[ts->nactive++] = &bk->p[i];
    }
    for (int a = 0; a < ts->nactive; a++) {
        pend *e = ts->active[a];
        if (F->s->occlusion && *ts->opaque > 0) {
            float box[4] = {e->x, e->x, e->y, e->y}, sc = 1.0f;
            if (persp) {
                memcpy(box, ts->abox[a], sizeof box);
                sc = ts->abox[a][4];
            }
            if (box_occluded(t, ts->sat, box[0], box[1], box[2], box[3], sc)) {
                ts->ws->culled++;
                e->kl = k - 1; /* dropped at the next update */
                continue;
            }
        }
        section sec;
        if (!make_section(t, &sh, e->x, e->y, e->z, k, &sec)) continue;
        ts->ws->splatted++;
        if (sec.g) {
            raster_skewed(t, &sec, e->w, F->pipeline == VS_PIPELINE_POST_CD ? 1 : 4, dst, bb, NULL);
            continue;
        }
        switch (F->pipeline) {
        case VS_PIPELINE_POST_CD: raster1(t, &sec, e->w[0], dst, bb); break;
        case VS_PIPELINE_POST_GS: raster_gs(t, &sec, e->w[0], dst, bb); break;
        default: raster4(t, &sec, e->w, dst, bb);
        }
    }
}

/* The sheets opening..kl that a voxel's block reaches with a positive
 * depth integral D[j dstep] (j = k - opening): their destinations (the
 * block's offset `off` in their ring slot) and weights wv[c] D (nc
 * channels); each sheet's touched box grown by the block's.  Returns how
 * many.  Inlined with nc constant.  (Post-gs writes the same loop with
 * its four gradient weights: through this helper it measured 3 % slower.) */
static inline int reached_sheets(const float *D, int dstep, int opening, int kl, const int *slots, float *const *ring,
                                 ptrdiff_t off, rect *bbs, const rect *box, const float *wv, int nc, float **dst,
                                 float *w)
{
    int ns = 0;
    for (int j = 0; j <= kl - opening; j++) {
        const float Dk = D[j * dstep];
        if (!(Dk > 0.0f)) continue;
        const int slot = slots[j];
        dst[ns] = ring[slot] + off;
        for (int c = 0; c < nc; c++) w[nc * ns + c] = wv[c] * Dk;
        ns++;
        merge_box(&bbs[slot], box);
    }
    return ns;
}

/* Voxel at a time (separable footprints, and sheared_blocks below): each
 * voxel starting at sheet `opening` is tested once against the occlusion
 * map, builds its footprint block once (src/block.h) and adds it, weighted
 * by each slab's depth integral, to every sheet its kernel reaches; sheet k
 * lives in ring slot (k - kbase) mod R.  Only the block's rows inside the
 * buffer and its vectors that overlap it are built and added; a vector may
 * spill up to 8/ch - 1 pixels into the apron.  Sheared axis-aligned footprints
 * (sheared_blocks) are tested once the same way, then each section is
 * placed at its own centre and added to its sheet (raster_skewed). */
static void activate_sheet(tile_state *ts, int opening, float *const *ring, rect *bbs, int R, int kbase)
{
    const tile_ctx *t = ts->t;
    const vs_frame *F = t->F;
    const vs_block_geom *g = F->sheared_blocks ? &F->skew : &F->blk;
    const int ch = F->pipeline == VS_PIPELINE_POST_CD ? 1 : 4, ppv = 8 / ch, bs = 8 * g->nvec;
    const vs_pipeline pl = F->pipeline;
    const float A = F->fp.A, rk = F->fp.row_k;
    /* ring slots of the sheets from `opening` on: every voxel of this
     * bucket starts there (one division per sheet, not per section) */
    int slots[VS_MAX_VSPAN];
    for (int j = 0; j < VS_MAX_VSPAN && j < R; j++) slots[j] = (opening + j - kbase) % R;
    const char *vdata = F->vol->data;
    const size_t vsize = vs_type_size(F->vol->type);
    const size_t plane = (size_t)F->vol->dims[0] * (size_t)F->vol->dims[1], nvox = plane * (size_t)F->vol->dims[2];
    const int pre_shaded = pl == VS_PIPELINE_PRE || pl == VS_PIPELINE_POST_ALPHA;
    pend_bucket *bk = &ts->bk[opening - ts->kmin];
    /* occlusion test, placement and depth integrals a batch of voxels at a
     * time (a SIMD kernel); the occlusion map does not change while a
     * sheet is activated, so batching culls exactly what one by one did */
    const float slab = (float)F->fp.slab, rz = (float)F->fp.rz;
    const int nd = F->fp.vspan; /* sheets one kernel can reach */
    /* the voxel kernels' factors, for blocks they take whole */
    const float *colw = !F->sheared_blocks && g->bx <= VS_VOXEL1_MAX && g->ny <= VS_VOXEL1_MAX ? g->colw : NULL;
    const vs_place_in P = {.sat = F->s->occlusion && *ts->opaque > 0 ? ts->sat : NULL,
                           .tx0 = t->x0, .ty0 = t->y0, .tw = t->tw, .th = t->th,
                           .pad_x = (float)F->pad_x, .pad_y = (float)F->pad_y,
                           .rx0 = g->rx0, .ry0 = g->ry0, .phases = (float)VS_BLOCK_PHASES,
                           .ox = t->ox, .oy = t->oy, .slab = slab, .rz = rz,
                           .depth_scale = F->fp.depth_scale, .depth = F->fp.depth_table, .depth_n = F->fp.depth_n,
                           /* E: post-gs voxels (sheared_blocks sections make their own) */
                           .with_e = pl == VS_PIPELINE_POST_GS && !F->sheared_blocks, .kappa = (float)F->fp.kappa,
                           .exp_scale = F->fp.exp_scale, .exp_table = F->fp.exp_table, .exp_n = F->fp.exp_n,
                           .opening = opening, .nd = nd < VS_MAX_VSPAN ? nd : VS_MAX_VSPAN,
                           .colw = colw,
                           .roww = g->roww, .bx = g->bx, .ny = g->ny};
    const sheet_geom unscaled = {g, 1.0f, 1.0f}; /* sheared_blocks: orthographic sections */
    vs_placed pv;
    for (int i0 = 0; i0 < bk->n; i0 += VS_PLACE_BATCH) {
        const int nb = bk->n - i0 < VS_PLACE_BATCH ? bk->n - i0 : VS_PLACE_BATCH;
        /* a voxel's value is a cache miss in the volume: ask for the batch's
         * values before placing it */
        for (int l = 0; l < nb; l++) __builtin_prefetch(vdata + (size_t)bk->p[i0 + l].v * vsize);
        if (pre_shaded) /* and the neighbours its gradient reads in the planes before and after */
            for (int l = 0; l < nb; l++) {
                const size_t v = bk->p[i0 + l].v;
                if (v >= plane) __builtin_prefetch(vdata + (v - plane) * vsize);
                if (v + plane < nvox) __builtin_prefetch(vdata + (v + plane) * vsize);
            }
        unsigned live = F->kern.place_voxels(&bk->p[i0].x, (int)(sizeof(pend) / sizeof(float)), nb, &P, &pv);
        ts->ws->culled += (uint64_t)(nb - __builtin_popcount(live));
        /* the splat weights of the batch's live voxels first: pre-shaded
         * ones read the shading tables at random (cache misses), which one
         * voxel at a time waited for between footprint adds */
        float wvs[VS_PLACE_BATCH][4];
        voxel_weights_batch(F, bk->p + i0, live, wvs);
        for (; live; live &= live - 1) {
            const int lane = __builtin_ctz(live);
            const pend *e = &bk->p[i0 + lane];
            const int kl = e->kl < opening + P.nd - 1 ? e->kl : opening + P.nd - 1;
            if (F->sheared_blocks) {
                /* each section at its own centre (the kernel's centroid in
                 * its slab), placed and added as on the sheet-at-a-time
                 * path, into its sheet of the ring */
                const float *w4 = wvs[lane];
                unskewed_cols uc; /* shared by its sections when only y moves */
                uc.g = NULL;
                for (int k = opening; k <= kl; k++) {
                    section sec;
                    if (!make_section(t, &unscaled, e->x, e->y, e->z, k, &sec)) continue;
                    ts->ws->splatted++;
                    const int slot = slots[k - opening];
                    raster_skewed(t, &sec, w4, ch, ring[slot], &bbs[slot], &uc);
                }
                continue;
            }
            /* rows [j0, j1) and vectors [v0, v1) of the block inside the buffer */
            const int by = pv.by[lane], bx = pv.bx[lane];
            const int j0 = by < 0 ? -by : 0, j1 = t->bh - by < g->ny ? t->bh - by : g->ny;
            const int v0 = bx < 0 ? -bx / ppv : 0;
            int v1 = t->bw - bx <= 0 ? 0 : (t->bw - bx + ppv - 1) / ppv;
            if (v1 > g->nvec) v1 = g->nvec;
            if (j0 >= j1 || v0 >= v1) continue;
            /* the factor paths read only the phase rows and weights; the
             * gradient layout and the block fallback set the phases too */
            vs_block_place pl_ = {.x = bx + t->ox, .y = by + t->oy, .qx = pv.qx[lane], .qy = pv.qy[lane],
                                  .fx = pv.fx[lane], .fy = pv.fy[lane]};
            /* the factors of the block's part inside the buffer */
            float cwb[VS_VOXEL1_MAX + 8], rwb[VS_BLOCK_MAX_SPAN];
            const float *cw = cwb, *rw = rwb;
            if (P.colw) {
                cw = pv.cw[lane] + v0 * ppv;
                rw = pv.rw[lane] + j0;
            }
            const rect box = {bx + v0 * ppv, by + j0, bx + v1 * ppv, by + j1};
            const ptrdiff_t ds = (ptrdiff_t)t->stride * ch;
            const ptrdiff_t off = (ptrdiff_t)(by + j0) * ds + (ptrdiff_t)(bx + v0 * ppv) * ch;
            const float *wv = wvs[lane];
            float *dst[VS_MAX_VSPAN];
            if (pl == VS_PIPELINE_POST_CD && 8 * (v1 - v0) <= VS_VOXEL1_MAX) {
                /* density: the block is built in registers and added to every
                 * sheet in one kernel call */
                float w[VS_MAX_VSPAN];
                const int ns = reached_sheets(&pv.D[0][lane], VS_PLACE_BATCH, opening, kl, slots, ring, off, bbs, &box,
                                              wv, 1, dst, w);
                ts->ws->splatted += (uint64_t)ns;
                if (!P.colw) vs_block_factors(g, &pl_, j0, j1, v0, v1, cwb, rwb);
                F->kern.splat_voxel1(dst, w, ns, ds, cw, rw, j1 - j0, v1 - v0, g->thr);
                continue;
            }
            if ((pl == VS_PIPELINE_PRE || pl == VS_PIPELINE_POST_ALPHA) && 2 * (v1 - v0) <= VS_VOXEL1_MAX) {
                /* colour and opacity (or density): the same, four channels */
                float w[4 * VS_MAX_VSPAN];
                const int ns = reached_sheets(&pv.D[0][lane], VS_PLACE_BATCH, opening, kl, slots, ring, off, bbs, &box,
                                              wv, 4, dst, w);
                ts->ws->splatted += (uint64_t)ns;
                if (!P.colw) {
                    vs_block_factors(g, &pl_, j0, j1, v0, v1, cwb, rwb);
                    memset(cwb + 2 * (v1 - v0), 0, 8 * sizeof(float)); /* read up to a multiple of 8 */
                }
                F->kern.splat_voxel4(dst, w, ns, ds, cw, rw, j1 - j0, v1 - v0, g->thr);
                continue;
            }
            if (pl == VS_PIPELINE_POST_GS && P.colw && 2 * (v1 - v0) <= VS_VOXEL1_MAX) {
                /* gradient splats: the block's rows (h, h dx, h dy, h) built
                 * in registers and added to every sheet in one kernel call,
                 * with the weights and offsets the block path uses; the
                 * depth integrals D and E come from place_voxels */
                float w[4 * VS_MAX_VSPAN];
                int ns = 0;
                for (int k = opening; k <= kl; k++) { /* as reached_sheets, with the gradient weights */
                    const float Dk = pv.D[k - opening][lane];
                    if (!(Dk > 0.0f)) continue;
                    const int slot = slots[k - opening];
                    const float wD = wv[0] * Dk;
                    dst[ns] = ring[slot] + off;
                    w[4 * ns] = wD;
                    w[4 * ns + 1] = -2.0f * wD * A;
                    w[4 * ns + 2] = -2.0f * wD * rk;
                    w[4 * ns + 3] = wv[0] * pv.E[k - opening][lane];
                    ns++;
                    merge_box(&bbs[slot], &box);
                }
                ts->ws->splatted += (uint64_t)ns;
                /* offsets from the centre (vs_block_build): column i lies
                 * i + ux - rx0 away, row j lies j + uy - ry0 away */
                float dx[VS_VOXEL1_MAX + 8], dy[VS_BLOCK_MAX_SPAN];
                const float ux = vs_block_phase(e->x, g->rx0, pl_.x) - g->rx0,
                            uy = vs_block_phase(e->y, g->ry0, pl_.y) - g->ry0;
                const int np = (v1 - v0) * ppv;
                for (int i = 0; i < np; i++) dx[i] = (float)(v0 * ppv + i) + ux;
                for (int i = np; i < np + 8; i++) dx[i] = 0.0f; /* read up to a multiple of 8 */
                for (int j = j0; j < j1; j++) dy[j - j0] = (float)j + uy;
                F->kern.splat_voxel_gs(dst, w, ns, ds, cw, rw, dx, dy, j1 - j0, v1 - v0, g->thr);
                continue;
            }
            /* a block too wide for the voxel kernels: built in memory once
             * (vs_block_place_at's phases, for the gradient layout) and
             * added to each sheet */
            pl_.ux = vs_block_phase(e->x, g->rx0, pl_.x);
            pl_.uy = vs_block_phase(e->y, g->ry0, pl_.y);
            vs_block_build(g, &pl_, j0, j1, v0, v1, t->blk);
            const float *src = t->blk + (size_t)j0 * bs + 8 * v0;
            for (int k = opening; k <= kl; k++) {
                const section sec = {e->x, e->y, pv.D[k - opening][lane],
                                     pl == VS_PIPELINE_POST_GS ? pv.E[k - opening][lane] : 0.0f, 1.0f, 1.0f, NULL};
                if (!(sec.D > 0.0f)) continue;
                ts->ws->splatted++;
                const int slot = slots[k - opening];
                float w8[8];
                if (pl == VS_PIPELINE_POST_CD) {
                    float w = wv[0] * sec.D;
                    for (int c = 0; c < 8; c++) w8[c] = w;
                } else if (pl == VS_PIPELINE_POST_GS) {
                    float wD = wv[0] * sec.D;
                    w8[0] = wD;
                    w8[1] = -2.0f * wD * A;
                    w8[2] = -2.0f * wD * rk;
                    w8[3] = wv[0] * sec.E;
                    for (int c = 4; c < 8; c++) w8[c] = w8[c - 4];
                } else {
                    for (int c = 0; c < 4; c++) w8[c] = w8[c + 4] = wv[c] * sec.D;
                }
                F->kern.splat_block(ring[slot] + off, ds, src, bs, j1 - j0, v1 - v0, w8);
                merge_box(&bbs[slot], &box);
            }
        }
    }
    retire_bucket(ts, bk);
}

static inline float lookup_corr(const vs_frame *F, const float *table, float v)
{
    const vs_classify *c = F->cls;
    float x = (float)((v - c->vmin) * c->scale);
    if (!(x > 0.0f)) x = 0.0f;
    if (x >= (float)(VS_TF_TABLE - 1)) return table[VS_TF_TABLE - 1];
    int i = (int)x;
    float f = x - (float)i;
    return table[i] + f * (table[i + 1] - table[i]);
}

static inline void lookup_color(const vs_frame *F, float v, float rgb[3])
{
    const vs_classify *c = F->cls;
    float x = (float)((v - c->vmin) * c->scale);
    if (!(x > 0.0f)) x = 0.0f; /* also NaN */
    if (x >= (float)(VS_TF_TABLE - 1)) x = (float)(VS_TF_TABLE - 1); /* also +inf: no int overflow */
    int i = (int)x;
    if (i >= VS_TF_TABLE - 1) {
        rgb[0] = c->color[VS_TF_TABLE - 1][0];
        rgb[1] = c->color[VS_TF_TABLE - 1][1];
        rgb[2] = c->color[VS_TF_TABLE - 1][2];
        return;
    }
    float f = x - (float)i;
    for (int ch = 0; ch < 3; ch++) rgb[ch] = c->color[i][ch] + f * (c->color[i + 1][ch] - c->color[i][ch]);
}

static inline float pre_opacity(const vs_frame *F, float a)
{
    if (!(a > 0.0f)) return 0.0f;
    if (a >= 1.0f) return F->opacity_corr[1024];
    float x = a * 1024.0f;
    int i = (int)x;
    float f = x - (float)i;
    return F->opacity_corr[i] + f * (F->opacity_corr[i + 1] - F->opacity_corr[i]);
}

/* Per-pixel scratch of one sheet: opacity, gradient/colour. */
typedef struct shade_buf {
    float *alpha; /* tw*th */
    float *g;     /* tw*th*3: gradient, then shaded colour */
} shade_buf;

static inline void shade_gradient(const vs_frame *F, float gx, float gy, float gz, float *d, float *sp)
{
    /* view space (per pixel, per pixel, per view unit) -> eye frame per mm */
    float ppm = (float)F->cam.px_per_mm, zpm = (float)F->cam.z_per_mm;
    gx *= ppm;
    gy *= ppm;
    gz *= zpm;
    if (F->s->exact_normals) {
        double n[3] = {gx, gy, gz}, dd, ss;
        vs_light_eval(&F->light, n, &dd, &ss);
        *d = (float)dd;
        *sp = (float)ss;
    } else {
        vs_shade_lut_eval(&F->lut, gx, gy, gz, d, sp);
    }
}

/* With a transfer function that makes value 0 visible, sheet pixels whose
 * slab centre lies outside the volume (where nothing was splatted, so q = 0)
 * must stay transparent, as they are for the ray caster. */
static void clip_outside(const tile_ctx *t, int k, const spans *r, float *alpha)
{
    const vs_frame *F = t->F;
    const vs_camera *cam = &F->cam;
    const double z = (k + 0.5) * F->fp.slab;
    const double lim[3] = {F->rel->dims[0] - 0.5, F->rel->dims[1] - 0.5, F->rel->dims[2] - 0.5};
    for (int y = r->y0; y < r->y1; y++)
        for (int x = r->xa[y]; x < r->xb[y]; x++) {
            double v[3] = {x + t->ox, y + t->oy, z}, idx[3];
            vs_camera_view_to_index(cam, v, idx);
            int inside = idx[0] >= -0.5 && idx[0] <= lim[0] && idx[1] >= -0.5 && idx[1] <= lim[1] &&
                         idx[2] >= -0.5 && idx[2] <= lim[2];
            if (!inside) alpha[(y - 1) * t->tw + (x - 1)] = 0.0f;
        }
}

/* Perspective, post-cd: sheet k's central differences are per pixel of
 * that sheet, which lie 1/s_k depth-0 pixels apart, and the difference
 * across sheets runs along the pixel's ray, not along view z.  With the
 * world point P = (u Z/f, v Z/f, Z) of pixel offset (u, v) from the image
 * centre (f the focal length in pixels), dF/dZ at a fixed pixel is
 * Fx u/f + Fy v/f + Fz; solved for Fz.  Units out as in the orthographic
 * case: x, y per depth-0 pixel, z per view unit. */
static void perspective_gradients(const tile_ctx *t, int k, const spans *r, const float *alpha, float *g)
{
    const vs_camera *cam = &t->F->cam;
    const float sk = (float)vs_camera_sheet_scale(cam, k, t->F->fp.slab);
    const float cz = (float)(cam->px_per_mm / (cam->focal_px * cam->z_per_mm));
    for (int y = r->y0; y < r->y1; y++) {
        const float v = (float)((y + t->oy) - cam->cy);
        for (int x = r->xa[y]; x < r->xb[y]; x++) {
            int o = (y - 1) * t->tw + (x - 1);
            if (!(alpha[o] > 0.0f)) continue;
            const float u = (float)((x + t->ox) - cam->cx);
            float *p = g + 3 * o;
            p[0] *= sk;
            p[1] *= sk;
            p[2] -= (p[0] * u + p[1] * v) * cz;
        }
    }
}

/* Perspective: a slab is crossed by the pixel's ray over its thickness
 * times the ray's length per unit depth, so its opacity grows to
 * 1 - (1 - a)^len (the ray caster steps the same way). */
static void perspective_opacity(const tile_ctx *t, const spans *r, float *alpha)
{
    const vs_camera *cam = &t->F->cam;
    for (int y = r->y0; y < r->y1; y++)
        for (int x = r->xa[y]; x < r->xb[y]; x++) {
            float *a = alpha + (y - 1) * t->tw + (x - 1);
            if (!(*a > 0.0f && *a < 1.0f)) continue;
            const float len = (float)vs_camera_ray_length(cam, x + t->ox, y + t->oy);
            *a = 1.0f - powf(1.0f - *a, len);
        }
}

/* Pixels whose accumulated opacity is already 1 take nothing more from any
 * sheet (compositing weighs a sample by 1 - opacity = 0), so they need no
 * shading: behind the head's skin, four in five visible pixels of a
 * shaded span are such.  Clearing their opacity skips them in shading and
 * compositing and leaves the image bit-identical. */
static void skip_opaque(const tile_ctx *t, const spans *r, const float *acc, float *alpha)
{
    for (int y = r->y0; y < r->y1; y++) {
        if (r->xa[y] == r->xb[y]) continue;
        const int o = (y - 1) * t->tw + (r->xa[y] - 1);
        const float *a = acc + 4 * o + 3;
        float *al = alpha + o;
        const int n = r->xb[y] - r->xa[y];
        for (int i = 0; i < n; i++) al[i] = a[4 * i] >= 1.0f ? 0.0f : al[i]; /* a select: vectorises */
    }
}

/* The part of the touched rectangle r that is classified, shaded and
 * composited: in each row, the columns between the first and last pixel
 * not yet fully opaque (live).  Opaque runs at a row's ends are common
 * behind a surface; skip_opaque still drops those inside the span. */
static void shaded_spans(const rect *r, const int *live0, const int *live1, spans *sp)
{
    sp->y0 = r->y0;
    sp->y1 = r->y1;
    for (int y = r->y0; y < r->y1; y++) {
        const int a = live0[y - 1] + 1, b = live1[y - 1] + 1; /* own pixel x is buffer pixel x + 1 */
        sp->xa[y] = a > r->x0 ? a : r->x0;
        sp->xb[y] = b < r->x1 ? b : r->x1;
        if (sp->xb[y] < sp->xa[y]) sp->xb[y] = sp->xa[y];
    }
}

/* After compositing: the live columns of own row y shrink past pixels
 * whose accumulated opacity reached 1 (a scan from each end that stops at
 * the first pixel still open: each opaque pixel is passed once per tile). */
static void shrink_live(const tile_ctx *t, const float *acc, int y, int *live0, int *live1)
{
    const float *a = acc + 4 * (size_t)y * t->tw + 3;
    int x0 = live0[y], x1 = live1[y];
    while (x0 < x1 && a[4 * x0] >= 1.0f) x0++;
    while (x1 > x0 && a[4 * (x1 - 1)] >= 1.0f) x1--;
    live0[y] = x0;
    live1[y] = x1;
}

void vs_tile_render(void *arg, int worker, int task)
{
    vs_frame *F = arg;
    const vs_settings *s = F->s;
    vs_worker_stats *ws = &F->wstats[worker];
    if (atomic_load_explicit(&F->cancel, memory_order_relaxed)) return;
    if (worker == 0 && s->progress) {
        double frac = (double)atomic_load(&F->tiles_done) / F->ntiles;
        if (s->progress(s->progress_user, frac)) atomic_store(&F->cancel, 1);
    }
    task = F->tile_order[task];
    const int W = F->cam.width, T = F->tile;
    const int tx = task % F->tiles_x, ty = task / F->tiles_x;
    tile_ctx t;
    t.F = F;
    t.fp = &F->fp;
    t.x0 = tx * T;
    t.y0 = ty * T;
    t.tw = (t.x0 + T > W ? W : t.x0 + T) - t.x0;
    t.th = (t.y0 + T > F->cam.height ? F->cam.height : t.y0 + T) - t.y0;
    t.bw = t.tw + 2;
    t.bh = t.th + 2;
    t.ox = t.x0 - 1;
    t.oy = t.y0 - 1;
    {
        double det = (double)F->fp.A * F->fp.C - (double)F->fp.B * F->fp.B;
        t.ry0 = (float)sqrt(F->fp.emax * F->fp.A / det);
        t.rx0 = (float)sqrt(F->fp.emax * F->fp.C / det);
    }
    t.ex = malloc((size_t)t.bw * 2 * sizeof(float));
    t.exd = t.ex ? t.ex + t.bw : NULL;
    t.rxa = malloc((size_t)t.bh * 2 * sizeof(int));
    t.rxb = t.rxa ? t.rxa + t.bh : NULL;
    t.rey = malloc((size_t)t.bh * 2 * sizeof(float));
    t.rdy = t.rey ? t.rey + t.bh : NULL;
    t.stride = t.bw + 2 * VS_APRON;
    t.blk = F->use_skewed   ? malloc((size_t)F->skew_maxrows * 8 * F->skew_maxvec * sizeof(float))
            : F->use_blocks ? malloc((size_t)F->blk.ny * 8 * F->blk.nvec * sizeof(float))
                            : NULL;
    const int npix = t.tw * t.th;
    const uint32_t *ent = F->tile_entries + F->tile_start[task];
    const int nbr = (int)(F->tile_start[task + 1] - F->tile_start[task]);
    const vs_pipeline pl = F->pipeline;
    const int ch = pl == VS_PIPELINE_POST_CD ? 1 : 4;
    const float slab = (float)F->fp.slab, rz = (float)F->fp.rz;
    const float thr = (float)s->occlusion_threshold;

    float *acc = calloc((size_t)npix * 4, sizeof(float));
    int *kfb = malloc((size_t)(nbr ? nbr : 1) * sizeof(int));
    int *order = malloc((size_t)(nbr ? nbr : 1) * sizeof(int));
    /* colours padded by one float: SIMD compositing reads 4 floats a pixel */
    shade_buf sb = {malloc((size_t)npix * sizeof(float)), calloc((size_t)npix * 3 + 1, sizeof(float))};
    int *bucket = NULL;
    int *sat = calloc((size_t)(t.tw + 1) * (t.th + 1), sizeof(int));
    /* per own row, the columns [live0, live1) not yet fully opaque; per
     * buffer row, a sheet's shaded span */
    int *live0 = malloc((size_t)(2 * t.th + 2 * t.bh) * sizeof(int));
    int *live1 = live0 ? live0 + t.th : NULL;
    int *span_xa = live0 ? live0 + 2 * t.th : NULL, *span_xb = live0 ? span_xa + t.bh : NULL;
    float *sheets = NULL;
    float **ring = NULL;
    rect *bbox = NULL;
    int opaque = 0;
    int sat_from = 1 << 30; /* first tile row whose opaque pixels changed since the table was built */
    tile_state ts;
    memset(&ts, 0, sizeof ts);
    ts.t = &t;
    ts.acc = acc;
    ts.sat = sat;
    ts.opaque = &opaque;
    ts.ws = ws;
    if (!t.ex || !t.rxa || !t.rey || !sat || !live0 || !acc || !kfb || !order || !sb.alpha || !sb.g) {
        atomic_store(&F->error, 1);
        goto done;
    }
    for (int y = 0; y < t.th; y++) {
        live0[y] = 0;
        live1[y] = t.tw;
    }

    /* the sheets each brick spans, and a counting sort by its first */
    int kmin = 1 << 30, kmax = -(1 << 30);
    for (int e = 0; e < nbr; e++) {
        const struct vs_brick_view *bv = &F->bview[ent[e]];
        kfb[e] = (int)floorf((bv->z0 - rz) / slab);
        int kl = (int)floorf((bv->z1 + rz) / slab);
        if (kfb[e] < kmin) kmin = kfb[e];
        if (kl > kmax) kmax = kl;
    }
    if (nbr > 0) {
        int span = kmax - kmin + 1;
        bucket = calloc((size_t)span + 1, sizeof(int));
        ts.bk = calloc((size_t)span, sizeof *ts.bk);
        if (!bucket || !ts.bk) {
            atomic_store(&F->error, 1);
            goto done;
        }
        for (int e = 0; e < nbr; e++) bucket[kfb[e] - kmin + 1]++;
        for (int b = 0; b < span; b++) bucket[b + 1] += bucket[b];
        for (int e = 0; e < nbr; e++) order[bucket[kfb[e] - kmin]++] = e; /* stable */
        ts.kmin = kmin;
        ts.kmax = kmax;
    }

    /* Sheet buffers: voxel-at-a-time for separable and sheared_blocks
     * footprints (a ring that holds every sheet a kernel reaches, plus the
     * neighbours central differences read), else sheet-at-a-time with three
     * buffers. */
    const int vspan = F->fp.vspan;
    const int multi = F->use_blocks;
    const int R = multi ? vspan + 2 : 3;
    const size_t sheet_floats = (size_t)ch * t.stride * t.bh;
    sheets = calloc((size_t)R * sheet_floats, sizeof(float));
    ring = malloc((size_t)R * sizeof *ring);
    bbox = malloc((size_t)R * sizeof *bbox);
    if (!sheets || !ring || !bbox || ((multi || F->use_skewed) && !t.blk)) {
        atomic_store(&F->error, 1);
        goto done;
    }
    for (int i = 0; i < R; i++) {
        ring[i] = sheets + (size_t)i * sheet_floats + (size_t)VS_APRON * ch;
        rect_clear(&bbox[i]);
    }
    const int kbase = kmin - 1; /* slot of sheet k: (k - kbase) % R, never negative */
    const rect own = {1, 1, t.tw + 1, t.th + 1};
    int next_brick = 0;

    /* post-cd shades sheet k once k + 1 is complete */
    const int ahead = pl == VS_PIPELINE_POST_CD ? 1 : 0;
    for (int k = kmin - ahead; nbr > 0 && k <= kmax; k++) {
        if (atomic_load_explicit(&F->cancel, memory_order_relaxed)) break;
        const int cur = (k - kbase) % R, prev = (k - 1 - kbase + R) % R, nxt = (k + 1 - kbase) % R;
        const int opening = k + ahead;
        if (opening <= kmax) {
            double t0 = vs_now_ms();
            while (next_brick < nbr && kfb[order[next_brick]] == opening)
                expand_brick(&ts, ent[order[next_brick++]], opening);
            if (multi)
                activate_sheet(&ts, opening, ring, bbox, R, kbase);
            else
                rasterize_sheet(&ts, opening, ring[(opening - kbase) % R], &bbox[(opening - kbase) % R]);
            ws->ms_rasterize += vs_now_ms() - t0;
            if (ts.failed) {
                atomic_store(&F->error, 1);
                break;
            }
        }
        if (k < kmin) continue;
        float *const *buf = ring;
        ws->tiles_total++;
        ws->sheets++;
        /* tile counter: only the touched part of the sheet is shaded */
        rect r = own;
        if (s->tile_counters) {
            r = bbox[cur];
            if (r.x0 < own.x0) r.x0 = own.x0;
            if (r.y0 < own.y0) r.y0 = own.y0;
            if (r.x1 > own.x1) r.x1 = own.x1;
            if (r.y1 > own.y1) r.y1 = own.y1;
        }
        if (!rect_empty(&r)) {
            ws->tiles_shaded++;
            const float *q = buf[cur];
            spans sp = {.xa = span_xa, .xb = span_xb};
            shaded_spans(&r, live0, live1, &sp);
            /* 1. classification + gradients */
            double t0 = vs_now_ms();
            /* the tables the post-shaded kernels read (a few stores a sheet) */
            const vs_shade_tabs tabs = {.vmin = F->cls->vmin, .scale = F->cls->scale, .alpha = F->alpha_corr,
                                        .color = &F->cls->color[0][0], .slab = slab, .two_slab = 2.0f * slab,
                                        .ppm = (float)F->cam.px_per_mm, .zpm = (float)F->cam.z_per_mm,
                                        .nl = F->lut.nl, .lambda_bin = F->lut.lambda_bin, .radius = F->lut.radius,
                                        .phi_bin = F->lut.phi_bin, .diffuse = F->lut.diffuse,
                                        .specular = F->lut.specular};
            if (pl == VS_PIPELINE_POST_CD) {
                for (int y = sp.y0; y < sp.y1; y++) {
                    if (sp.xa[y] == sp.xb[y]) continue;
                    int o = (y - 1) * t.tw + (sp.xa[y] - 1);
                    size_t b = (size_t)y * t.stride + sp.xa[y];
                    F->kern.classify_cd(sb.alpha + o, sb.g + 3 * o, q + b, buf[prev] + b, buf[nxt] + b, t.stride,
                                        sp.xb[y] - sp.xa[y], &tabs);
                }
            } else if (pl == VS_PIPELINE_POST_GS) {
                for (int y = sp.y0; y < sp.y1; y++) {
                    if (sp.xa[y] == sp.xb[y]) continue;
                    int o = (y - 1) * t.tw + (sp.xa[y] - 1);
                    size_t b = (size_t)y * t.stride + sp.xa[y];
                    F->kern.classify_gs(sb.alpha + o, sb.g + 3 * o, q + 4 * b, sp.xb[y] - sp.xa[y], &tabs);
                }
            } else {
                for (int y = sp.y0; y < sp.y1; y++)
                    for (int x = sp.xa[y]; x < sp.xb[y]; x++) {
                        int o = (y - 1) * t.tw + (x - 1);
                        size_t b = (size_t)y * t.stride + x;
                        float a;
                        if (pl == VS_PIPELINE_PRE) {
                            a = q[4 * b + 3];
                        } else { /* post-alpha */
                            a = lookup_corr(F, F->alpha_corr, q[4 * b + 3]);
                        }
                        sb.alpha[o] = a;
                    }
            }
            if (F->clip_to_volume) clip_outside(&t, k, &sp, sb.alpha);
            if (F->cam.persp && pl == VS_PIPELINE_POST_CD) perspective_gradients(&t, k, &sp, sb.alpha, sb.g);
            if (s->occlusion) skip_opaque(&t, &sp, acc, sb.alpha);
            double t1 = vs_now_ms();
            /* 2. shading: colour per pixel */
            if ((pl == VS_PIPELINE_POST_CD || pl == VS_PIPELINE_POST_GS) && !s->exact_normals) {
                for (int y = sp.y0; y < sp.y1; y++) {
                    if (sp.xa[y] == sp.xb[y]) continue;
                    int o = (y - 1) * t.tw + (sp.xa[y] - 1);
                    size_t b = (size_t)y * t.stride + sp.xa[y];
                    F->kern.shade_lut(sb.g + 3 * o, sb.alpha + o, q + ch * b, ch, sp.xb[y] - sp.xa[y], &tabs);
                }
            } else {
                for (int y = sp.y0; y < sp.y1; y++)
                    for (int x = sp.xa[y]; x < sp.xb[y]; x++) {
                        int o = (y - 1) * t.tw + (x - 1);
                        size_t b = (size_t)y * t.stride + x;
                        float a = sb.alpha[o];
                        if (!(a > 0.0f)) continue;
                        float *c = sb.g + 3 * o;
                        if (pl == VS_PIPELINE_PRE) {
                            /* opacity-weighted colour / interpolated opacity; an
                             * opacity so small that its inverse overflows (a
                             * transfer function whose opacity rises over 1e39
                             * units) shows nothing: colour 0, not inf * 0 = NaN */
                            float inv = 1.0f / a;
                            if (!(inv <= FLT_MAX)) inv = 0.0f;
                            float cr = q[4 * b] * inv, cg = q[4 * b + 1] * inv, cb = q[4 * b + 2] * inv;
                            c[0] = cr > 1.0f ? 1.0f : cr;
                            c[1] = cg > 1.0f ? 1.0f : cg;
                            c[2] = cb > 1.0f ? 1.0f : cb;
                            sb.alpha[o] = pre_opacity(F, a);
                        } else if (pl == VS_PIPELINE_POST_ALPHA) {
                            for (int i = 0; i < 3; i++) {
                                float v = q[4 * b + i];
                                c[i] = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
                            }
                        } else {
                            float d, spec, rgb[3];
                            shade_gradient(F, c[0], c[1], c[2], &d, &spec);
                            lookup_color(F, pl == VS_PIPELINE_POST_CD ? q[b] : q[4 * b], rgb);
                            c[0] = rgb[0] * d + spec;
                            c[1] = rgb[1] * d + spec;
                            c[2] = rgb[2] * d + spec;
                        }
                    }
            }
            if (F->cam.persp) perspective_opacity(&t, &sp, sb.alpha);
            double t2 = vs_now_ms();
            /* 3. front-to-back compositing; the accumulated opacity is the
             * tile's occlusion map */
            for (int y = sp.y0; y < sp.y1; y++) {
                if (sp.xa[y] == sp.xb[y]) continue;
                int o = (y - 1) * t.tw + (sp.xa[y] - 1);
                const int crossed = F->kern.composite(acc + 4 * o, sb.alpha + o, sb.g + 3 * o, sp.xb[y] - sp.xa[y], thr);
                if (crossed) {
                    opaque += crossed;
                    if (y - 1 < sat_from) sat_from = y - 1;
                }
                if (s->occlusion) shrink_live(&t, acc, y - 1, live0, live1);
            }
            if (s->occlusion && sat_from < t.th) {
                /* rows above the first changed one keep their sums */
                build_sat(&t, acc, thr, sat, sat_from);
                sat_from = 1 << 30;
            }
            double t3 = vs_now_ms();
            ws->ms_gradient += t1 - t0;
            ws->ms_shade += t2 - t1;
            ws->ms_composite += t3 - t2;
        }
        /* retire the sheet no later sheet reads */
        int done_slot = pl == VS_PIPELINE_POST_CD ? prev : cur;
        clear_rect(ring[done_slot], t.stride, ch, &bbox[done_slot]);
        rect_clear(&bbox[done_slot]);
        if (s->occlusion && opaque >= npix) break; /* tile early termination */
    }

done:
    if (acc) {
        for (int y = 0; y < t.th; y++)
            for (int x = 0; x < t.tw; x++) {
                size_t o = (size_t)(t.y0 + y) * W + (t.x0 + x);
                vs_finish_pixel(acc + 4 * (y * t.tw + x), s->background, F->image + 4 * o);
            }
    }
    free(acc);
    free(kfb);
    free(order);
    for (int b = 0; ts.bk && b <= ts.kmax - ts.kmin; b++) free(ts.bk[b].p);
    free(ts.bk);
    free(ts.spare);
    free(ts.active);
    free(ts.abox);
    free(sheets);
    free(ring);
    free(bbox);
    free(sb.alpha);
    free(sb.g);
    free(bucket);
    free(sat);
    free(live0);
    free(t.ex);
    free(t.rxa);
    free(t.rey);
    free(t.blk);
    atomic_fetch_add(&F->tiles_done, 1);
}
