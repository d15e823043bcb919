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

int vs_block_setup(vs_block_geom *g, const vs_footprint *fp, int ch, int grad)
{
    memset(g, 0, sizeof *g);
    double det = (double)fp->A * fp->C - (double)fp->B * fp->B;
    g->ch = ch;
    g->grad = grad;
    g->rx0 = (float)sqrt(fp->emax * fp->C / det);
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
            g->roww[(size_t)q * g->ny + j] = weight(fp, fp->C * dy * dy);
        }
    }
    return 1;
}

/* out[i] = t0[i] + f (t1[i] - t0[i]) for i in [a, b) */
static void lerp(float *out, const float *t0, const float *t1, float f, int a, int b)
{
    for (int i = a; i < b; i++) out[i] = t0[i] + f * (t1[i] - t0[i]);
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
