/* Footprint blocks: phase tables and per-voxel blocks (see block.h). */
#include "block.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void vs_block_free(vs_block_geom *g)
{
    free(g->colw);
    g->colw = g->roww = NULL;
}

/* exp(-e) inside the kernel's radius, else exactly 0, from the frame's
 * exponential table (so --footprint-res means what it does elsewhere) */
static float weight(const vs_footprint *fp, double e)
{
    return e < fp->emax ? vs_fp_exp(fp, (float)e) : 0.0f;
}

static int setup(vs_block_geom *g, const vs_footprint *fp, int ch, int grad, int skewed)
{
    memset(g, 0, sizeof *g);
    double det = (double)fp->A * fp->C - (double)fp->B * fp->B;
    /* the row weight's exponent per dy^2: C when separable, C - B^2/A when
     * each row's centre moves (skewed) */
    const double ky = skewed ? fp->row_k : fp->C;
    g->ch = ch;
    g->grad = grad;
    g->rx0 = (float)sqrt(skewed && fp->B != 0.0f ? fp->emax / fp->A : fp->emax * fp->C / det);
    g->ry0 = (float)sqrt(fp->emax * fp->A / det);
    g->nx = (int)floorf(2.0f * g->rx0) + 1;
    g->ny = (int)floorf(2.0f * g->ry0) + 1;
    if (g->nx > VS_BLOCK_MAX_SPAN || g->ny > VS_BLOCK_MAX_SPAN) return 0;
    g->nvec = (g->nx * ch + 7) / 8;
    g->bx = 8 * g->nvec / ch;
    g->thr = (float)exp(-fp->emax);
    const int np = VS_BLOCK_PHASES + 1;
    size_t nc = (size_t)np * g->bx, nr = (size_t)np * g->ny;
    g->colw = malloc((nc + nr) * sizeof(float));
    if (!g->colw) return 0;
    g->roww = g->colw + nc;
    for (int q = 0; q < np; q++) {
        double u = (double)q / VS_BLOCK_PHASES;
        for (int i = 0; i < g->bx; i++) {
            double dx = i + u - g->rx0;
            g->colw[(size_t)q * g->bx + i] = i < g->nx ? weight(fp, fp->A * dx * dx) : 0.0f;
        }
        for (int j = 0; j < g->ny; j++) {
            double dy = j + u - g->ry0;
            g->roww[(size_t)q * g->ny + j] = weight(fp, ky * dy * dy);
        }
    }
    return 1;
}

int vs_block_setup(vs_block_geom *g, const vs_footprint *fp, int ch, int grad)
{
    return setup(g, fp, ch, grad, 0);
}

int vs_block_setup_skewed(vs_block_geom *g, const vs_footprint *fp)
{
    return setup(g, fp, 1, 0, 1);
}

static void lerp(float *out, const float *t0, const float *t1, float f, int a, int b);

int vs_block_skewed_nvec(const vs_block_geom *g, float row_shift, int ch)
{
    int width = g->nx + (int)ceilf(fabsf(row_shift) * (float)g->ny) + 2;
    return (width * ch + 7) / 8;
}

static inline int phase_row(float u, float *f)
{
    float s = u * (float)VS_BLOCK_PHASES;
    int q = (int)s;
    if (q > VS_BLOCK_PHASES - 1) q = VS_BLOCK_PHASES - 1;
    *f = s - (float)q;
    return q;
}

/* Gradient-splat layout: channels 1 and 2 of every pixel become h times
 * its offset from the centre, in pixels. */
static void gradient_layout(float *blk, int stride, int rows, int width, int x, int y, float cx, float cy)
{
    for (int j = 0; j < rows; j++) {
        float *row = blk + (size_t)j * stride;
        const float dy = (float)(y + j) - cy;
        for (int i = 0; i < width; i++) {
            row[4 * i + 1] *= (float)(x + i) - cx;
            row[4 * i + 2] *= dy;
        }
    }
}

void vs_block_build_skewed(const vs_block_geom *g, float row_shift, float cx, float cy, int ch, int grad, int maxvec,
                           float *blk, int *x, int *y, int *nvec)
{
    int xs[VS_BLOCK_MAX_SPAN];
    float ux[VS_BLOCK_MAX_SPAN];
    const float ly = cy - g->ry0, py = ceilf(ly), uy = py - ly;
    float fy;
    const float *r0 = g->roww + (size_t)phase_row(uy, &fy) * g->ny;
    /* each row's centre and first pixel; the rows' left edges lx are
     * monotonic in the row, so equal ends mean every row has the same one:
     * no skew (axis-aligned, only sheared) */
    const float lx0 = cx + row_shift * (uy - g->ry0) - g->rx0;
    const float lx1 = cx + row_shift * ((float)(g->ny - 1) + uy - g->ry0) - g->rx0;
    const int uniform = lx0 == lx1;
    int xmin = 1 << 30, xmax = -(1 << 30);
    for (int j = 0; j < (uniform ? 1 : g->ny); j++) {
        const float c = cx + row_shift * ((float)j + uy - g->ry0);
        const float lx = c - g->rx0, px = ceilf(lx);
        xs[j] = (int)px;
        ux[j] = px - lx;
        if (xs[j] < xmin) xmin = xs[j];
        if (xs[j] > xmax) xmax = xs[j];
    }
    int n = ((xmax - xmin + g->nx) * ch + 7) / 8;
    if (n > maxvec) n = maxvec; /* cannot happen: vs_block_skewed_nvec bounds the drift */
    const int stride = 8 * maxvec, width = 8 * n / ch;
    *x = xmin;
    *y = (int)py;
    *nvec = n;
    if (uniform) {
        /* every row at the same phase (no skew: axis-aligned, only sheared):
         * one column look-up serves all rows; the table is 0 past nx and
         * at least `width` wide, so whole rows are written */
        float cw[VS_BLOCK_MAX_SPAN + 8], rw[VS_BLOCK_MAX_SPAN], fx;
        const float *c0 = g->colw + (size_t)phase_row(ux[0], &fx) * g->bx;
        lerp(cw, c0, c0 + g->bx, fx, 0, width);
        lerp(rw, r0, r0 + g->ny, fy, 0, g->ny);
        const float thr = g->thr;
        for (int j = 0; j < g->ny; j++) {
            float *row = blk + (size_t)j * stride;
            const float ry = rw[j];
            if (ch == 1) {
                for (int i = 0; i < width; i++) {
                    float h = cw[i] * ry;
                    row[i] = h > thr ? h : 0.0f;
                }
            } else {
                for (int i = 0; i < width; i++) {
                    float h = cw[i] * ry;
                    h = h > thr ? h : 0.0f;
                    row[4 * i] = row[4 * i + 1] = row[4 * i + 2] = row[4 * i + 3] = h;
                }
            }
        }
        if (grad && ch == 4) gradient_layout(blk, stride, g->ny, width, xmin, (int)py, cx, cy);
        return;
    }
    for (int j = 0; j < g->ny; j++) {
        float *row = blk + (size_t)j * stride;
        memset(row, 0, (size_t)8 * n * sizeof(float));
        const float rw = r0[j] + fy * (r0[g->ny + j] - r0[j]);
        if (!(rw > 0.0f)) continue;
        float fx;
        const float *c0 = g->colw + (size_t)phase_row(ux[j], &fx) * g->bx, *c1 = c0 + g->bx;
        const int o = xs[j] - xmin;
        const int m = o + g->nx <= width ? g->nx : width - o;
        const float thr = g->thr;
        /* simple loops per layout, so the compiler vectorises them */
        if (ch == 1) {
            float *r = row + o;
            for (int i = 0; i < m; i++) {
                float h = (c0[i] + fx * (c1[i] - c0[i])) * rw;
                r[i] = h > thr ? h : 0.0f;
            }
        } else {
            float *r = row + 4 * o;
            for (int i = 0; i < m; i++) {
                float h = (c0[i] + fx * (c1[i] - c0[i])) * rw;
                h = h > thr ? h : 0.0f;
                r[4 * i] = r[4 * i + 1] = r[4 * i + 2] = r[4 * i + 3] = h;
            }
        }
    }
    if (grad && ch == 4) gradient_layout(blk, stride, g->ny, width, xmin, (int)py, cx, cy);
}

/* out[i] = t0[i] + f (t1[i] - t0[i]) for i in [a, b) */
static void lerp(float *out, const float *t0, const float *t1, float f, int a, int b)
{
    for (int i = a; i < b; i++) out[i] = t0[i] + f * (t1[i] - t0[i]);
}

void vs_block_factors(const vs_block_geom *g, const vs_block_place *p, int j0, int j1, int v0, int v1, float *cw,
                      float *rw)
{
    vs_block_factors_ch(g, p, g->ch, j0, j1, v0, v1, cw, rw);
}

void vs_block_col_factors(const vs_block_geom *g, const vs_block_place *p, int i0, int i1, float *cw)
{
    const float *c0 = g->colw + (size_t)p->qx * g->bx + i0;
    lerp(cw, c0, c0 + g->bx, p->fx, 0, i1 - i0);
}

void vs_block_row_factors(const vs_block_geom *g, const vs_block_place *p, int j0, int j1, float *rw)
{
    const float *r0 = g->roww + (size_t)p->qy * g->ny + j0;
    lerp(rw, r0, r0 + g->ny, p->fy, 0, j1 - j0);
}

void vs_block_factors_ch(const vs_block_geom *g, const vs_block_place *p, int ch, int j0, int j1, int v0, int v1,
                         float *cw, float *rw)
{
    vs_block_col_factors(g, p, v0 * 8 / ch, v1 * 8 / ch, cw);
    vs_block_row_factors(g, p, j0, j1, rw);
}

void vs_block_build(const vs_block_geom *g, const vs_block_place *p, int j0, int j1, int v0, int v1, float *blk)
{
    const int stride = 8 * g->nvec;
    const float thr = g->thr;
    /* pixels covered by vectors [v0, v1) */
    const int ppv = 8 / g->ch, i0 = v0 * ppv, i1 = v1 * ppv;
    float cw[VS_BLOCK_MAX_SPAN], rw[VS_BLOCK_MAX_SPAN];
    const float *c0 = g->colw + (size_t)p->qx * g->bx, *r0 = g->roww + (size_t)p->qy * g->ny;
    lerp(cw, c0, c0 + g->bx, p->fx, i0, i1);
    lerp(rw, r0, r0 + g->ny, p->fy, j0, j1);
    for (int j = j0; j < j1; j++) {
        float *row = blk + (size_t)j * stride;
        const float ry = rw[j];
        if (g->ch == 1) {
            for (int i = i0; i < i1; i++) {
                float h = cw[i] * ry;
                row[i] = h > thr ? h : 0.0f; /* outside the radius: exactly 0 */
            }
        } else if (!g->grad) {
            for (int i = i0; i < i1; i++) {
                float h = cw[i] * ry;
                h = h > thr ? h : 0.0f;
                row[4 * i] = row[4 * i + 1] = row[4 * i + 2] = row[4 * i + 3] = h;
            }
        } else {
            /* offsets from the centre: pixel i lies i + u - r0 away */
            const float dy = (float)j + (p->uy - g->ry0), ux = p->ux - g->rx0;
            for (int i = i0; i < i1; i++) {
                float h = cw[i] * ry;
                h = h > thr ? h : 0.0f;
                row[4 * i] = h;
                row[4 * i + 1] = h * ((float)i + ux);
                row[4 * i + 2] = h * dy;
                row[4 * i + 3] = h;
            }
        }
    }
}
