/* Scalar reference kernels: the definition every SIMD kernel is tested
 * against (tests/test_simd.c). */
#include "kernels.h"
#include "footprint.h" /* vs_ifloor, vs_iceil, vs_depth_lookup */

#include <float.h>
#include <math.h>

void vs_splat_row1_scalar(float *row, const float *ex, float w, int n)
{
    for (int i = 0; i < n; i++) row[i] += w * ex[i];
}

void vs_splat_row4_scalar(float *row4, const float *ex, const float w[4], int n)
{
    for (int i = 0; i < n; i++) {
        float h = ex[i];
        float *p = row4 + 4 * i;
        p[0] += w[0] * h;
        p[1] += w[1] * h;
        p[2] += w[2] * h;
        p[3] += w[3] * h;
    }
}

int vs_composite_scalar(float *acc, const float *alpha, const float *rgb, int n, float thr)
{
    int crossed = 0;
    for (int i = 0; i < n; i++) {
        float a = alpha[i];
        if (!(a > 0.0f)) continue;
        float *p = acc + 4 * i;
        float before = p[3];
        float w = (1.0f - before) * a;
        p[0] += w * rgb[3 * i];
        p[1] += w * rgb[3 * i + 1];
        p[2] += w * rgb[3 * i + 2];
        float after = before + w;
        p[3] = after > 1.0f ? 1.0f : after;
        crossed += before < thr && p[3] >= thr;
    }
    return crossed;
}

void vs_splat_block_scalar(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                           const float w8[8])
{
    for (int r = 0; r < rows; r++) {
        float *d = dst + r * ds;
        const float *b = blk + r * bs;
        for (int i = 0; i < 8 * nvec; i++) d[i] += w8[i % 8] * b[i];
    }
}

/* Table coordinate of a value, in double as the per-pixel look-ups in
 * src/rasterize.c always did (the SIMD versions convert to double too, so the
 * images did not change when those loops became kernels). */
static inline float tab_coord(const vs_shade_tabs *T, float v)
{
    float x = (float)((v - T->vmin) * T->scale);
    return x > 0.0f ? x : 0.0f; /* also NaN */
}

/* the opacity table at v, interpolated linearly, clamped at its ends */
static inline float lookup_alpha(const vs_shade_tabs *T, float v)
{
    float x = tab_coord(T, v);
    if (x >= (float)(VS_KTAB - 1)) return T->alpha[VS_KTAB - 1];
    int j = (int)x;
    float f = x - (float)j;
    return T->alpha[j] + f * (T->alpha[j + 1] - T->alpha[j]);
}

/* the differences mixed with weight w (vs_shade_tabs cd_wide): one step
 * each side d1, two steps d2 */
static inline float wide_diff(float w, float d1, float d2) { return (0.5f + 2.0f * w) * d1 - w * d2; }

void vs_classify_cd_scalar(float *alpha, float *g, const float *q, const float *qp, const float *qn,
                           const float *qp2, const float *qn2, ptrdiff_t stride, int n, const vs_shade_tabs *T)
{
    const float w = T->cd_wide, wz = T->cd_wide_z;
    for (int i = 0; i < n; i++) {
        if (T->alpha) alpha[i] = lookup_alpha(T, q[i]);
        if (w > 0.0f) {
            g[3 * i + 0] = wide_diff(w, q[i + 1] - q[i - 1], q[i + 2] - q[i - 2]);
            g[3 * i + 1] = wide_diff(w, q[i + stride] - q[i - stride], q[i + 2 * stride] - q[i - 2 * stride]);
        } else {
            g[3 * i + 0] = 0.5f * (q[i + 1] - q[i - 1]);
            g[3 * i + 1] = 0.5f * (q[i + stride] - q[i - stride]);
        }
        if (wz > 0.0f)
            g[3 * i + 2] = wide_diff(wz, qn[i] - qp[i], qn2[i] - qp2[i]) / T->slab;
        else
            g[3 * i + 2] = (qn[i] - qp[i]) / T->two_slab;
    }
}

void vs_classify_gs_scalar(float *alpha, float *g, const float *q4, int n, const vs_shade_tabs *T,
                           const vs_ripple_row *R)
{
    for (int i = 0; i < n; i++) {
        if (T->alpha) alpha[i] = lookup_alpha(T, q4[4 * i]);
        g[3 * i + 0] = q4[4 * i + 1] / T->slab;
        g[3 * i + 1] = q4[4 * i + 2] / T->slab;
        g[3 * i + 2] = q4[4 * i + 3] / T->slab;
    }
    if (!R) return;
    const vs_ripple_lanes *L = R->L;
    float P[3], Q[3];
    if (n > 0) vs_ripple_block(R, R->m >> 3, P, Q);
    for (int i = 0; i < n; i++) {
        const int c = (R->m + i) >> 3, l = (R->m + i) & 7;
        if (i > 0 && l == 0) vs_ripple_block(R, c, P, Q);
        float A[3];
        for (int a = 0; a < 3; a++) A[a] = P[a] * L->cl[a][l] + Q[a] * L->sl[a][l];
        for (int j = 0; j < 3; j++) {
            const float v = (L->m[0][j] * A[0] + L->m[1][j] * A[1]) + L->m[2][j] * A[2];
            g[3 * i + j] -= q4[4 * i] * v;
        }
    }
}

/* vs_shade_lut_eval (src/shade_lut.h) on the view-space gradient c: the
 * index of its diffuse and specular terms */
static inline int lut_index(const float *c, const vs_shade_tabs *T)
{
    float gx = c[0] * T->ppm, gy = c[1] * T->ppm, gz = c[2] * T->zpm;
    float ax = gx < 0 ? -gx : gx, ay = gy < 0 ? -gy : gy, az = gz < 0 ? -gz : gz;
    float m = ax > ay ? ax : ay;
    if (az > m) m = az;
    if (!(ax <= FLT_MAX && ay <= FLT_MAX && az <= FLT_MAX) || !(m >= 1e-30f)) m = 0.0f;
    int ix = 0, iy = 0, iz = 0;
    if (m > 0.0f) {
        float k = 127.0f / m;
        ix = (int)lrintf(gx * k);
        iy = (int)lrintf(gy * k);
        iz = (int)lrintf(gz * k);
    }
    if (ix == 0 && iy == 0 && iz == 0) iz = -127;
    int li = T->lambda_bin[(iy + 127) * 255 + (ix + 127)];
    int r = T->radius[(iy + 127) * 255 + (ix + 127)];
    int pi = T->phi_bin[(iz + 127) * 181 + r];
    return pi * T->nl + li;
}

void vs_shade_lut_scalar(float *g, const float *alpha, const float *v, int vstride, int n, const vs_shade_tabs *T)
{
    for (int i = 0; i < n; i++) {
        if (!(alpha[i] > 0.0f)) continue;
        float *c = g + 3 * i;
        const int di = lut_index(c, T);
        float d = T->diffuse[di], sp = T->specular[di];
        /* colour table, clamped at its ends */
        float x = tab_coord(T, v[(ptrdiff_t)i * vstride]);
        float rgb[3];
        if (x >= (float)(VS_KTAB - 1)) {
            for (int ch = 0; ch < 3; ch++) rgb[ch] = T->color[3 * (VS_KTAB - 1) + ch];
        } else {
            int j = (int)x;
            float f = x - (float)j;
            for (int ch = 0; ch < 3; ch++)
                rgb[ch] = T->color[3 * j + ch] + f * (T->color[3 * j + 3 + ch] - T->color[3 * j + ch]);
        }
        c[0] = rgb[0] * d + sp;
        c[1] = rgb[1] * d + sp;
        c[2] = rgb[2] * d + sp;
    }
}

void vs_shade_terms_scalar(float *d, float *s, const float *g, int n, const vs_shade_tabs *T)
{
    for (int i = 0; i < n; i++) {
        const int di = lut_index(g + 3 * i, T);
        d[i] = T->diffuse[di];
        s[i] = T->specular[di];
    }
}

/* the table's opacity between (f, b) */
static inline float preint_alpha1(const vs_preint_tabs *P, float f, float b)
{
    float fx, fy;
    const int i = vs_preint_cell(P, f, &fx), j = vs_preint_cell(P, b, &fy);
    return vs_preint_bilerp(P, (size_t)i * (size_t)P->n + (size_t)j, fx, fy, 0);
}

void vs_preint_alpha_scalar(float *alpha, const float *f, const float *m, const float *b, int n,
                            const vs_preint_tabs *P)
{
    for (int i = 0; i < n; i++) {
        const float a1 = preint_alpha1(P, f[i], m[i]), a2 = preint_alpha1(P, m[i], b[i]);
        alpha[i] = a1 + (1.0f - a1) * a2;
    }
}

void vs_splat_block_mix_scalar(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                               const float m[12])
{
    for (int r = 0; r < rows; r++) {
        float *d = dst + r * ds;
        const float *b = blk + r * bs;
        for (int p = 0; p < 2 * nvec; p++) {
            const float h = b[4 * p], hx = b[4 * p + 1], hy = b[4 * p + 2];
            for (int c = 0; c < 4; c++) d[4 * p + c] += (m[3 * c] * h + m[3 * c + 1] * hx) + m[3 * c + 2] * hy;
        }
    }
}

int vs_project_brick_scalar(const uint16_t *vox, int n, const vs_project_in *P, uint16_t *keep, float *xyz)
{
    int q = 0;
    for (int i = 0; i < n; i++) {
        const float di = (float)(vox[i] & 7), dj = (float)((vox[i] >> 3) & 7), dk = (float)(vox[i] >> 6);
        const float x = P->base[0] + P->m[0][0] * di + P->m[0][1] * dj + P->m[0][2] * dk;
        const float y = P->base[1] + P->m[1][0] * di + P->m[1][1] * dj + P->m[1][2] * dk;
        const float z = P->base[2] + P->m[2][0] * di + P->m[2][1] * dj + P->m[2][2] * dk;
        if (x + P->px < P->bx0 || x - P->px > P->bx1 || y + P->py < P->by0 || y - P->py > P->by1) continue;
        keep[q] = (uint16_t)i;
        xyz[3 * q] = x;
        xyz[3 * q + 1] = y;
        xyz[3 * q + 2] = z;
        q++;
    }
    return q;
}

void vs_splat_voxel1_scalar(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                            int rows, int nvec, float thr)
{
    float h[VS_VOXEL1_MAX];
    const int n = 8 * nvec;
    for (int r = 0; r < rows; r++) {
        for (int i = 0; i < n; i++) {
            const float v = cw[i] * rw[r];
            h[i] = v > thr ? v : 0.0f;
        }
        for (int s = 0; s < ns; s++) {
            float *d = dst[s] + r * ds;
            for (int i = 0; i < n; i++) d[i] += w[s] * h[i];
        }
    }
}

void vs_splat_voxel4_scalar(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                            int rows, int nvec, float thr)
{
    float h[VS_VOXEL1_MAX];
    const int n = 2 * nvec;
    for (int r = 0; r < rows; r++) {
        for (int p = 0; p < n; p++) {
            const float v = cw[p] * rw[r];
            h[p] = v > thr ? v : 0.0f;
        }
        for (int s = 0; s < ns; s++) {
            float *d = dst[s] + r * ds;
            const float *ws = w + 4 * s;
            for (int p = 0; p < n; p++)
                for (int c = 0; c < 4; c++) d[4 * p + c] += ws[c] * h[p];
        }
    }
}

/* One row of the gradient-splat block layout (h, h dx, h dy, h) of src/block.c:
 * pixel p has h = cw[p] ry (0 where not > thr), p < n. */
static void gs_layout_row(float *b, const float *cw, float ry, const float *dx, float dy, int n, float thr)
{
    for (int p = 0; p < n; p++) {
        const float v = cw[p] * ry, h = v > thr ? v : 0.0f;
        b[4 * p] = h;
        b[4 * p + 1] = h * dx[p];
        b[4 * p + 2] = h * dy;
        b[4 * p + 3] = h;
    }
}

void vs_splat_voxel_gs_scalar(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw,
                              const float *rw, const float *dx, const float *dy, int rows, int nvec, float thr)
{
    float b[4 * VS_VOXEL1_MAX];
    const int n = 2 * nvec;
    for (int r = 0; r < rows; r++) {
        gs_layout_row(b, cw, rw[r], dx, dy[r], n, thr); /* vs_block_build's row */
        for (int s = 0; s < ns; s++) {
            float *d = dst[s] + r * ds;
            const float *ws = w + 4 * s;
            for (int i = 0; i < 4 * n; i++) d[i] += ws[i % 4] * b[i];
        }
    }
}

void vs_splat_rows_mix_scalar(float *dst, ptrdiff_t ds, const float *cw, const float *rw, const float *dx,
                              const float *dy, int rows, int nvec, float thr, const float m[12])
{
    float b[4 * VS_VOXEL1_MAX];
    for (int r = 0; r < rows; r++) { /* vs_block_build_skewed's row, then splat_block_mix on it */
        gs_layout_row(b, cw, rw[r], dx, dy[r], 2 * nvec, thr);
        vs_splat_block_mix_scalar(dst + r * ds, ds, b, 0, 1, nvec, m);
    }
}

/* G(z) as src/footprint.h's vs_fp_depth */
/* A voxel's depth integrals: the slab table's rows around its coordinate
 * x (vs_place_slab_x), interpolated, sw floats. */
static inline void slab_row(const vs_place_in *P, const float *tab, float x, float *o)
{
    int r = (int)x;
    if (r > P->sn - 1) r = P->sn - 1;
    const float f = x - (float)r;
    const float *t0 = tab + (size_t)r * P->sw, *t1 = t0 + P->sw;
    for (int j = 0; j < P->sw; j++) o[j] = t0[j] + f * (t1[j] - t0[j]);
}

/* the tile pixels within pad of (x, y) all opaque, or none of them */
static inline int occluded(const vs_place_in *P, float x, float y)
{
    int xa = vs_ifloor(x - P->pad_x) - P->tx0, xb = vs_iceil(x + P->pad_x) - P->tx0;
    int ya = vs_ifloor(y - P->pad_y) - P->ty0, yb = vs_iceil(y + P->pad_y) - P->ty0;
    if (xa < 0) xa = 0;
    if (ya < 0) ya = 0;
    if (xb > P->tw - 1) xb = P->tw - 1;
    if (yb > P->th - 1) yb = P->th - 1;
    if (xa > xb || ya > yb) return 1;
    const int w = P->tw + 1;
    const int *s = P->sat;
    const int sum = s[(yb + 1) * w + xb + 1] - s[ya * w + xb + 1] - s[(yb + 1) * w + xa] + s[ya * w + xa];
    return sum == (xb - xa + 1) * (yb - ya + 1);
}

/* a block's first pixel and phase along one axis (vs_block_place_at) */
static inline void place_axis(float c, float r0, float phases, int *p, int *q, float *f)
{
    const float l = c - r0, a = (float)vs_iceil(l), s = (a - l) * phases;
    *p = (int)a;
    *q = (int)s;
    if (*q > (int)phases - 1) *q = (int)phases - 1;
    *f = s - (float)*q;
}

unsigned vs_place_voxels_scalar(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out)
{
    unsigned live = 0;
    for (int i = 0; i < n; i++) {
        const float *c = xyz + (ptrdiff_t)i * stride;
        const float x = c[0], y = c[1], z = c[2];
        if (P->sat && occluded(P, x, y)) continue;
        live |= 1u << i;
        int px, py;
        place_axis(x, P->rx0, P->phases, &px, &out->qx[i], &out->fx[i]);
        place_axis(y, P->ry0, P->phases, &py, &out->qy[i], &out->fy[i]);
        out->bx[i] = px - P->ox;
        out->by[i] = py - P->oy;
        const float sx = vs_place_slab_x(P, z);
        slab_row(P, P->sd, sx, out->D[i]);
        if (P->with_e) slab_row(P, P->se, sx, out->E[i]);
        if (!P->colw) continue;
        const float *c0 = P->colw + (size_t)out->qx[i] * P->bx, *c1 = c0 + P->bx;
        const float *r0 = P->roww + (size_t)out->qy[i] * P->ny, *r1 = r0 + P->ny;
        const float fx = out->fx[i], fy = out->fy[i];
        for (int k = 0; k < P->bx; k++) out->cw[i][k] = c0[k] + fx * (c1[k] - c0[k]);
        for (int k = 0; k < 8; k++) out->cw[i][P->bx + k] = 0.0f;
        for (int k = 0; k < P->ny; k++) out->rw[i][k] = r0[k] + fy * (r1[k] - r0[k]);
    }
    return live;
}
