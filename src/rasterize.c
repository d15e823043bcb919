/* Kernel sections into sheet buffers (rasterize.h).  Every rasterizer
 * multiplies and adds in one fixed order per pixel, so a section's weights
 * do not depend on the tile it is clipped to. */
#include "rasterize.h"

#include <string.h>

sheet_geom vs_sheet_geom(const vs_frame *F, int k)
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

/* Row range of a footprint inside the buffer (buffer row y is image row
 * y + oy, oy = y0 - seam). */
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
void vs_raster1(const tile_ctx *t, const section *sec, const float w4[4], float *q, rect *bb)
{
    float w = w4[0];
    int ya, yb, xa, xb;
    float cxr;
    if (!rows_of(t, sec, &ya, &yb)) return;
    w *= sec->D;
    for (int y = ya; y <= yb; y++) {
        if (!row_footprint(t, sec, y, &xa, &xb, &cxr)) continue;
        t->F->kern.splat_row1(q + (size_t)y * t->stride + xa, t->ex + xa, w, xb - xa + 1);
        t->ws->floats += (uint64_t)(xb - xa + 1);
        rect_grow(bb, xa, xb, y);
    }
}

/* Four interleaved channels with their own weights (pre, post-alpha). */
void vs_raster4(const tile_ctx *t, const section *sec, const float w4[4], float *buf, rect *bb)
{
    int ya, yb, xa, xb;
    float cxr;
    if (!rows_of(t, sec, &ya, &yb)) return;
    float w[4] = {w4[0] * sec->D, w4[1] * sec->D, w4[2] * sec->D, w4[3] * sec->D};
    for (int y = ya; y <= yb; y++) {
        if (!row_footprint(t, sec, y, &xa, &xb, &cxr)) continue;
        t->F->kern.splat_row4(buf + ((size_t)y * t->stride + xa) * 4, t->ex + xa, w, xb - xa + 1);
        t->ws->floats += 4 * (uint64_t)(xb - xa + 1);
        rect_grow(bb, xa, xb, y);
    }
}


/* 0 when the block is too wide for the fused kernels. */
static int unskewed_place_cols(const tile_ctx *t, const vs_block_geom *g, const vs_block_place *p, float cx, int ch,
                               unskewed_cols *uc)
{
    const int ppv = 8 / ch, nvec = (g->nx * ch + 7) / 8;
    const int bx = p->x - t->ox;
    uc->bx = bx;
    vs_clip_cols(t, bx, nvec, ppv, &uc->v0, &uc->v1);
    if (uc->v0 >= uc->v1) return 1;
    if ((uc->v1 - uc->v0) * ppv > VS_VOXEL1_MAX) return 0;
    const int n = (uc->v1 - uc->v0) * ppv;
    vs_block_col_factors(g, p, uc->v0 * ppv, uc->v1 * ppv, uc->cw);
    /* splat_voxel4 reads cw up to a multiple of 8 floats: defined zeros
     * past the factors (not the whole array: this runs per section) */
    if (ch == 4) memset(uc->cw + n, 0, 8 * sizeof(float));
    if (t->F->stages->gradient_splats) { /* as vs_block_build_skewed's gradient layout */
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
    int j0, j1;
    vs_clip_rows(t, by, g->ny, &j0, &j1);
    if (j0 >= j1 || v0 >= v1) return;
    const ptrdiff_t ds = (ptrdiff_t)t->stride * ch;
    float *const d = dst + (ptrdiff_t)(by + j0) * ds + (ptrdiff_t)(bx + v0 * ppv) * ch;
    float rw[VS_BLOCK_MAX_SPAN], w[4];
    const float D = sec->D;
    vs_block_row_factors(g, p, j0, j1, rw);
    if (F->stages->gradient_splats) {
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
    rect_merge(bb, &box);
    t->ws->floats += 8 * (uint64_t)(j1 - j0) * (uint64_t)(v1 - v0);
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
void vs_raster_skewed(const tile_ctx *t, const section *sec, const float w4[4], int ch, float *dst, rect *bb,
                          unskewed_cols *uc)
{
    const vs_frame *F = t->F;
    const vs_block_geom *g = sec->g;
    const int ppv = 8 / ch, bs = 8 * F->skew_maxvec, gs = F->stages->gradient_splats;
    if (t->fp->row_shift == 0.0f && raster_unskewed(t, sec, w4, ch, dst, bb, uc)) return;
    int x, y, nvec;
    vs_block_build_skewed(g, t->fp->row_shift, sec->cx, sec->cy, ch, gs, F->skew_maxvec, t->blk, &x, &y, &nvec);
    const int by = y - t->oy, bx = x - t->ox;
    int j0, j1, v0, v1;
    vs_clip_rows(t, by, g->ny, &j0, &j1);
    vs_clip_cols(t, bx, nvec, ppv, &v0, &v1);
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
    rect_merge(bb, &box);
    t->ws->floats += 8 * (uint64_t)(j1 - j0) * (uint64_t)(v1 - v0);
}

/* Density plus the three gradient splats dH/dx, dH/dy, dH/dz (FH'):
 * grad h = -2 Q v h; in-sheet (Qxx d)_x = A dx_row, (Qxx d)_y = B dx + row_k dy
 * (d relative to the shifted centre); the z part integrates exactly to
 * E - 2 D (Qzx d_x + Qzy d_y).  Layout: q, gx, gy, gz per pixel.  Offsets
 * are in footprint units, so with perspective the gradient is per pixel at
 * depth 0 for every voxel, whatever its own scale. */
void vs_raster_gs(const tile_ctx *t, const section *sec, const float w4[4], float *buf, rect *bb)
{
    const float w = w4[0];
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
        t->ws->floats += 4 * (uint64_t)(xb - xa + 1);
        rect_grow(bb, xa, xb, y);
    }
}
