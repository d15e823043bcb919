/* Empty-space skipping for the reference ray caster: a grid of small bricks,
 * each flagged when no point in it can reconstruct a value with opacity. */
#include "raycast_job.h"
#include "context.h"
#include "gaussian.h"
#include "pool.h"

#include <stdlib.h>

/* ---- empty-space skipping ---- */

/* Bounds of the kernel weight sum W(p) = b sum_{|p-j|<=R} 2^(-2|p-j|^2) over
 * the unit cell, with a margin: reconstructed values lie in
 * [min(m Wmin, m Wmax), max(M Wmin, M Wmax)] for voxel values in [m, M]. */
static void gauss_weight_bounds(const rc_job *J, double *wmin, double *wmax)
{
    double lo = INFINITY, hi = 0.0;
    const int steps = 8;
    int r = (int)ceil(J->R) + 1;
    for (int sz = 0; sz < steps; sz++)
        for (int sy = 0; sy < steps; sy++)
            for (int sx = 0; sx < steps; sx++) {
                double p[3] = {(double)sx / steps, (double)sy / steps, (double)sz / steps};
                double sum = 0.0;
                for (int k = -r; k <= r + 1; k++)
                    for (int j = -r; j <= r + 1; j++)
                        for (int i = -r; i <= r + 1; i++) {
                            double d2 = (p[0] - i) * (p[0] - i) + (p[1] - j) * (p[1] - j) + (p[2] - k) * (p[2] - k);
                            if (d2 <= J->R2) sum += exp2(-2.0 * d2);
                        }
                sum *= J->b;
                if (sum < lo) lo = sum;
                if (sum > hi) hi = sum;
            }
    *wmin = 0.98 * lo;
    *wmax = 1.02 * hi;
}

/* Voxel interval [lo, hi] that the points of brick b depend on along one
 * axis (dilated by dil, clipped); *zero set if it reaches outside. */
static void brick_interval(const rc_job *J, int b, double dil, int n, int *lo, int *hi, uint8_t *zero)
{
    double x0 = J->org + (double)BRICK * b, x1 = x0 + BRICK;
    *lo = (int)ceil(x0 - dil);
    *hi = (int)floor(x1 + dil);
    *zero = 0;
    if (*lo < 0) {
        *lo = 0;
        *zero = 1;
    }
    if (*hi > n - 1) {
        *hi = n - 1;
        *zero = 1;
    }
}

/* Shared, read-only state of the brick-grid build; chunks of brick layers
 * [b0, b1) are independent pool tasks. */
typedef struct skip_build {
    rc_job *J;
    double dil, wmin, wmax;
    const int *ix, *iy, *iz;       /* voxel intervals per brick and axis */
    const uint8_t *zx, *zy, *zz;   /* interval reaches outside the volume */
    int b0, b1;                    /* this chunk */
    int failed;                    /* out of memory in this chunk */
} skip_build;

/* A tighter bound for the Gaussian reconstruction, which the min-max range
 * cannot give for noisy data (one bright speckle voxel makes its whole
 * neighbourhood "relevant" although b * 2^0 * speckle stays far below the
 * iso-value).  For p in the unit cell c, |p - (c+o)| along an axis is at
 * least dist(o) = max(0, -o, o-1), so
 *     f(p) <= b sum_o w(o_x) w(o_y) w(o_z) f+(c+o),  w(o) = 2^(-2 dist(o)^2),
 * a separable filter.  The same with f- bounds f from below.  We filter
 * slice by slice (x, y), keep a ring of slices for z, and take each brick's
 * maximum: hi[] bounds the f+ part, neg[] the f- part (bricks of layers
 * b0..b1-1, indexed from layer b0). */
static int gauss_brick_bounds(const skip_build *B, float *hi, float *neg)
{
    const rc_job *J = B->J;
    const struct vs_volume *v = J->vol;
    const int nx = v->dims[0], ny = v->dims[1], nz = v->dims[2];
    const int olo = -(int)ceil(J->R), ohi = (int)ceil(J->R) + 1, nt = ohi - olo + 1;
    const int org = (int)J->org;
    const int ncx = BRICK * J->nb[0], ncy = BRICK * J->nb[1];
    float w1[2 * 8 + 3], wz[2 * 8 + 3]; /* the normalization b, once: in the z taps */
    for (int o = olo; o <= ohi; o++) {
        double d = o < 0 ? -o : o > 1 ? o - 1 : 0;
        w1[o - olo] = d > J->R ? 0.0f : (float)exp2(-2.0 * d * d);
        wz[o - olo] = (float)(J->b * w1[o - olo]);
    }
    /* a row padded with zeros covers voxels org+olo .. org+ncx-1+ohi */
    const int plen = ncx + nt - 1, poff = -(org + olo);
    double *row = malloc(sizeof(double) * (size_t)nx);
    float *pad = calloc((size_t)plen, sizeof(float));
    float *tmp = malloc(sizeof(float) * (size_t)ncx * ny);
    float *ring = malloc(sizeof(float) * (size_t)nt * ncx * ncy);
    float *acc = malloc(sizeof(float) * (size_t)ncx);
    if (!row || !pad || !tmp || !ring || !acc) {
        free(row); free(pad); free(tmp); free(ring); free(acc);
        return 0;
    }
    size_t layer = (size_t)J->nb[0] * J->nb[1];
    for (size_t i = 0; i < (size_t)(B->b1 - B->b0) * layer; i++) hi[i] = neg[i] = 0.0f;
    int passes = v->vmin - J->base < 0.0 ? 2 : 1; /* values below the base */
    for (int pass = 0; pass < passes; pass++) {
        float *out = pass == 0 ? hi : neg;
        int have = -1; /* highest slice k filtered into the ring */
        for (int czi = BRICK * B->b0; czi < BRICK * B->b1; czi++) {
            int cz = org + czi;
            int kmin = cz + olo > 0 ? cz + olo : 0;
            int kmax = cz + ohi < nz - 1 ? cz + ohi : nz - 1;
            if (kmin > kmax) continue; /* no voxel slice reaches this cell layer */
            if (have < kmin - 1) have = kmin - 1;
            for (int k = have + 1; k <= kmax; k++) {
                for (int j = 0; j < ny; j++) { /* x */
                    vs_rc_fetch_row(v, j, k, 0, nx - 1, row, J->base);
                    for (int i = 0; i < nx; i++) {
                        double x = pass == 0 ? row[i] : -row[i];
                        pad[poff + i] = x > 0.0 ? (float)x : 0.0f;
                    }
                    float *t = tmp + (size_t)j * ncx;
                    for (int cxi = 0; cxi < ncx; cxi++) {
                        float a = 0.0f;
                        for (int o = 0; o < nt; o++) a += w1[o] * pad[cxi + o];
                        t[cxi] = a;
                    }
                }
                float *sl = ring + (size_t)(k % nt) * ncx * ncy;
                for (int cyi = 0; cyi < ncy; cyi++) { /* y */
                    int cy = org + cyi;
                    float *d = sl + (size_t)cyi * ncx;
                    for (int cxi = 0; cxi < ncx; cxi++) d[cxi] = 0.0f;
                    for (int o = olo; o <= ohi; o++) {
                        int j = cy + o;
                        if (j < 0 || j >= ny) continue;
                        const float *t = tmp + (size_t)j * ncx;
                        const float w = w1[o - olo];
                        for (int cxi = 0; cxi < ncx; cxi++) d[cxi] += w * t[cxi];
                    }
                }
                have = k;
            }
            size_t bzo = (size_t)(czi / BRICK - B->b0) * J->nb[1]; /* chunk-relative */
            for (int cyi = 0; cyi < ncy; cyi++) { /* z, then the brick maximum */
                for (int cxi = 0; cxi < ncx; cxi++) acc[cxi] = 0.0f;
                for (int k = kmin; k <= kmax; k++) {
                    const float *sr = ring + ((size_t)(k % nt) * ncy + cyi) * ncx;
                    const float w = wz[k - cz - olo];
                    for (int cxi = 0; cxi < ncx; cxi++) acc[cxi] += w * sr[cxi];
                }
                float *ob = out + (bzo + cyi / BRICK) * J->nb[0];
                for (int cxi = 0; cxi < ncx; cxi++) {
                    /* round up: float sums must not understate the bound */
                    float f = acc[cxi] * 1.00001f + 1e-30f;
                    if (f > ob[cxi / BRICK]) ob[cxi / BRICK] = f;
                }
            }
        }
    }
    free(row); free(pad); free(tmp); free(ring); free(acc);
    return 1;
}

/* Value range of each brick's dependency region by separable min/max passes
 * (x and y per voxel slice into a small ring of slices, then z per brick
 * layer), combined with the kernel bound, then the skip flags. */
static void skip_chunk(skip_build *B)
{
    rc_job *J = B->J;
    const struct vs_volume *v = J->vol;
    const int nx = v->dims[0], ny = v->dims[1];
    const int bx = J->nb[0], by = J->nb[1];
    const int nring = BRICK + 2 * (int)ceil(B->dil) + 2; /* slices one brick layer needs */
    size_t nlayer = (size_t)bx * by * (size_t)(B->b1 - B->b0);
    float *amin = malloc(sizeof(float) * (size_t)ny * bx), *amax = malloc(sizeof(float) * (size_t)ny * bx);
    float *cmin = malloc(sizeof(float) * (size_t)nring * by * bx);
    float *cmax = malloc(sizeof(float) * (size_t)nring * by * bx);
    double *row = malloc(sizeof(double) * (size_t)nx);
    int gauss = J->mode == MODE_GAUSS;
    /* kernel bounds for this chunk's bricks (indexed from layer b0) */
    float *kb_hi = gauss ? malloc(sizeof(float) * nlayer) : NULL;
    float *kb_neg = gauss ? malloc(sizeof(float) * nlayer) : NULL;
    if (!amin || !amax || !cmin || !cmax || !row || (gauss && (!kb_hi || !kb_neg))) {
        B->failed = 1;
    } else if (gauss) {
        B->failed = !gauss_brick_bounds(B, kb_hi, kb_neg);
    }
    if (B->failed) {
        free(amin); free(amax); free(cmin); free(cmax); free(row); free(kb_hi); free(kb_neg);
        return;
    }
    const vs_classify *c = J->cls;
    const int *ix = B->ix, *iy = B->iy, *iz = B->iz;
    int have = -1; /* highest slice reduced into the ring */
    for (int b = B->b0; b < B->b1; b++) {
        if (have < iz[2 * b] - 1) have = iz[2 * b] - 1;
        for (int k = have + 1; k <= iz[2 * b + 1]; k++) {
            /* x: per voxel row and x-brick (empty interval -> +inf/-inf) */
            for (int j = 0; j < ny; j++) {
                vs_rc_fetch_row(v, j, k, 0, nx - 1, row, J->base);
                float *mn = amin + (size_t)j * bx, *mx = amax + (size_t)j * bx;
                for (int x = 0; x < bx; x++) {
                    double lo = INFINITY, hi = -INFINITY;
                    for (int i = ix[2 * x]; i <= ix[2 * x + 1]; i++) {
                        if (row[i] < lo) lo = row[i];
                        if (row[i] > hi) hi = row[i];
                    }
                    mn[x] = (float)lo;
                    mx[x] = (float)hi;
                }
            }
            /* y: into ring slot k */
            for (int y = 0; y < by; y++) {
                float *mn = cmin + ((size_t)(k % nring) * by + y) * bx;
                float *mx = cmax + ((size_t)(k % nring) * by + y) * bx;
                for (int x = 0; x < bx; x++) {
                    mn[x] = INFINITY;
                    mx[x] = -INFINITY;
                }
                for (int j = iy[2 * y]; j <= iy[2 * y + 1]; j++) {
                    const float *smn = amin + (size_t)j * bx, *smx = amax + (size_t)j * bx;
                    for (int x = 0; x < bx; x++) {
                        if (smn[x] < mn[x]) mn[x] = smn[x];
                        if (smx[x] > mx[x]) mx[x] = smx[x];
                    }
                }
            }
            have = k;
        }
        /* z, and the decision */
        for (int y = 0; y < by; y++)
            for (int x = 0; x < bx; x++) {
                double m = INFINITY, M = -INFINITY;
                for (int k = iz[2 * b]; k <= iz[2 * b + 1]; k++) {
                    size_t i = ((size_t)(k % nring) * by + y) * bx + x;
                    if (cmin[i] < m) m = cmin[i];
                    if (cmax[i] > M) M = cmax[i];
                }
                if (B->zx[x] || B->zy[y] || B->zz[b]) { /* voxels outside count as base, 0 here */
                    if (m > 0.0) m = 0.0;
                    if (M < 0.0) M = 0.0;
                }
                /* normalised: a convex combination of the values, within [m, M] */
                double vlo = J->normalize ? m : fmin(m * B->wmin, m * B->wmax),
                       vhi = J->normalize ? M : fmax(M * B->wmin, M * B->wmax);
                size_t bl = ((size_t)(b - B->b0) * by + y) * bx + x;
                if (gauss) { /* normalised: the sums over W, at least wmin */
                    const double over = J->normalize ? 1.0 / B->wmin : 1.0;
                    vhi = fmin(vhi, kb_hi[bl] * over);
                    vlo = fmax(vlo, -(double)kb_neg[bl] * over);
                }
                J->skip[((size_t)b * by + y) * bx + x] =
                    (uint8_t)(vhi < c->alpha_lo - J->base || vlo > c->alpha_hi - J->base);
            }
    }
    free(amin); free(amax); free(cmin); free(cmax); free(row); free(kb_hi); free(kb_neg);
}

static void skip_task(void *arg, int worker, int chunk) { skip_chunk((skip_build *)arg + chunk); }

/* The brick grid, in as many chunks of brick layers as the pool has
 * workers (each chunk's scratch is its own). */
vs_status vs_raycast_build_skip(vs_context *ctx, rc_job *J, struct vs_pool *pool)
{
    int nchunks = vs_pool_threads(pool);
    const struct vs_volume *v = J->vol;
    double dil = J->mode == MODE_GAUSS ? J->R : 1.0; /* voxels a point depends on */
    J->org = -ceil(J->R) - 1.0;
    for (int a = 0; a < 3; a++) J->nb[a] = (int)ceil((v->dims[a] - 1 + J->R - J->org) / BRICK) + 1;
    const int bx = J->nb[0], by = J->nb[1], bz = J->nb[2];
    int *iv = malloc(sizeof(int) * 2 * (size_t)(bx + by + bz));
    uint8_t *zf = malloc((size_t)(bx + by + bz));
    if (nchunks > bz) nchunks = bz;
    skip_build *ch = calloc((size_t)nchunks, sizeof *ch);
    J->skip = malloc((size_t)bx * by * bz);
    if (!iv || !zf || !ch || !J->skip) {
        free(iv); free(zf); free(ch); free(J->skip);
        J->skip = NULL;
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "raycast: out of memory for the brick grid");
    }
    skip_build base = {.J = J, .dil = dil, .wmin = 1.0, .wmax = 1.0,
                       .ix = iv, .iy = iv + 2 * bx, .iz = iv + 2 * (bx + by),
                       .zx = zf, .zy = zf + bx, .zz = zf + bx + by};
    for (int b = 0; b < bx; b++) brick_interval(J, b, dil, v->dims[0], &iv[2 * b], &iv[2 * b + 1], &zf[b]);
    for (int b = 0; b < by; b++)
        brick_interval(J, b, dil, v->dims[1], &iv[2 * (bx + b)], &iv[2 * (bx + b) + 1], &zf[bx + b]);
    for (int b = 0; b < bz; b++)
        brick_interval(J, b, dil, v->dims[2], &iv[2 * (bx + by + b)], &iv[2 * (bx + by + b) + 1],
                       &zf[bx + by + b]);
    if (J->mode == MODE_GAUSS) gauss_weight_bounds(J, &base.wmin, &base.wmax);
    for (int t = 0; t < nchunks; t++) {
        ch[t] = base;
        ch[t].b0 = (int)((long)bz * t / nchunks);
        ch[t].b1 = (int)((long)bz * (t + 1) / nchunks);
    }
    vs_pool_run(pool, nchunks, skip_task, ch);
    int failed = 0;
    for (int t = 0; t < nchunks; t++) failed |= ch[t].failed;
    free(iv); free(zf); free(ch);
    if (failed) {
        free(J->skip);
        J->skip = NULL;
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "raycast: out of memory for the brick grid");
    }
    return VS_OK;
}
