/* Reference ray caster: post-classified, Phong-shaded with the same light and
 * material model as the splatting pipelines, one ray per pixel along +z of
 * view space (parallel rays, or rays from the eye with perspective).  Three reconstructions:
 *   analytic  - the scene's closed form, iso crossings refined by bisection
 *               (ground truth for error measurements);
 *   gaussian  - the exact sum of the splatting kernel b 2^(-2 r^2) over the
 *               voxels within radius R, with its analytic derivative;
 *   trilinear - for comparison, with central-difference gradients.
 * Samples lie on a global grid z = k * ray_step (view units: planes parallel
 * to the image, like the splatting sheets), so neighbouring rays sample
 * consistently.  Rows are tasks on the context's worker pool (src/pool.h),
 * as the splatting tiles are; each pixel is computed independently, so the
 * image is identical for any thread count. */
#include "raycast.h"
#include "camera.h"
#include "classify.h"
#include "context.h"
#include "finish.h"
#include "gaussian.h"
#include "light.h"
#include "pool.h"
#include "timing.h"
#include "volume.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

enum { MODE_ANALYTIC, MODE_GAUSS, MODE_TRILINEAR };
enum { BRICK = 2, MAX_TAPS = 20 }; /* 2^3 bricks: the kernel's reach dominates */

typedef struct rc_job {
    const struct vs_volume *vol;
    const vs_settings *s;
    vs_camera cam;
    vs_classify *cls;
    vs_light light;
    int mode;
    double R, R2, b;       /* kernel radius, its square, normalization      */
    double base;           /* sampled volumes: values are reconstructed less
                              this (the volume's minimum), as splatting does,
                              so that outside the volume reads as the minimum */
    double step;           /* view units                                    */
    double box_lo[3], box_hi[3]; /* index box where samples are taken      */
    int refine;            /* bisect iso crossings (analytic, iso-range)    */
    /* empty-space skipping: brick b covers points [org + B b, org + B (b+1)) */
    double org;
    int nb[3];
    uint8_t *skip;         /* 1: no point of the brick can have opacity > 0 */
    float *rgba;
    double *ms;            /* per worker: time spent casting rows           */
    atomic_int rows_done, cancel;
} rc_job;

/* ---- voxel access: values less base; outside the volume, and non-finite
 * values, count as base (0 here) ---- */

/* Values of row (j,k) at x = i0..i1 (all inside), less base, into out[]. */
static void fetch_row(const struct vs_volume *v, int j, int k, int i0, int i1, double *out, double base)
{
    size_t row = ((size_t)k * v->dims[1] + j) * v->dims[0];
    int n = i1 - i0 + 1;
    switch (v->type) {
    case VS_U8: {
        const uint8_t *p = (const uint8_t *)v->data + row + i0;
        for (int i = 0; i < n; i++) out[i] = p[i] - base;
    } break;
    case VS_I16: {
        const int16_t *p = (const int16_t *)v->data + row + i0;
        for (int i = 0; i < n; i++) out[i] = p[i] - base;
    } break;
    case VS_U16: {
        const uint16_t *p = (const uint16_t *)v->data + row + i0;
        for (int i = 0; i < n; i++) out[i] = p[i] - base;
    } break;
    default: {
        const float *p = (const float *)v->data + row + i0;
        for (int i = 0; i < n; i++) out[i] = isfinite(p[i]) ? p[i] - base : 0.0;
    } break;
    }
}

static double voxel(const struct vs_volume *v, int i, int j, int k, double base)
{
    if (i < 0 || j < 0 || k < 0 || i >= v->dims[0] || j >= v->dims[1] || k >= v->dims[2]) return 0.0;
    double x = vs_volume_at(v, ((size_t)k * v->dims[1] + j) * v->dims[0] + i);
    return isfinite(x) ? x - base : 0.0;
}

/* ---- Gaussian reconstruction: f(p) = b sum_j f_j 2^(-2|p-j|^2), |p-j| <= R ---- */
static double gauss_sample(const rc_job *J, const double p[3], double g[3])
{
    const struct vs_volume *v = J->vol;
    int lo[3], hi[3];
    double d[3][MAX_TAPS], d2[3][MAX_TAPS], w[3][MAX_TAPS];
    for (int a = 0; a < 3; a++) {
        lo[a] = (int)ceil(p[a] - J->R);
        hi[a] = (int)floor(p[a] + J->R);
        if (lo[a] < 0) lo[a] = 0;
        if (hi[a] > v->dims[a] - 1) hi[a] = v->dims[a] - 1;
        if (lo[a] > hi[a]) {
            if (g) g[0] = g[1] = g[2] = 0.0;
            return 0.0;
        }
        for (int i = lo[a]; i <= hi[a]; i++) {
            double t = p[a] - i;
            d[a][i - lo[a]] = t;
            d2[a][i - lo[a]] = t * t;
            w[a][i - lo[a]] = exp2(-2.0 * t * t); /* separable factor */
        }
    }
    double row[MAX_TAPS];
    double sum = 0.0, sx = 0.0, sy = 0.0, sz = 0.0;
    for (int k = lo[2]; k <= hi[2]; k++) {
        int kk = k - lo[2];
        double rz = J->R2 - d2[2][kk];
        if (rz < 0.0) continue;
        for (int j = lo[1]; j <= hi[1]; j++) {
            int jj = j - lo[1];
            double ry = rz - d2[1][jj];
            if (ry < 0.0) continue;
            double wyz = w[1][jj] * w[2][kk];
            fetch_row(v, j, k, lo[0], hi[0], row, J->base);
            double rs = 0.0, rx = 0.0;
            for (int i = 0; i <= hi[0] - lo[0]; i++) {
                if (d2[0][i] > ry) continue;
                double fw = row[i] * w[0][i];
                rs += fw;
                rx += fw * d[0][i];
            }
            sum += rs * wyz;
            if (g) {
                sx += rx * wyz;
                sy += rs * wyz * d[1][jj];
                sz += rs * wyz * d[2][kk];
            }
        }
    }
    if (g) {
        /* d/dp_a 2^(-2|p-j|^2) = -4 ln2 (p_a - j_a) 2^(-2|p-j|^2) */
        double c = -4.0 * M_LN2 * J->b;
        g[0] = c * sx;
        g[1] = c * sy;
        g[2] = c * sz;
    }
    return J->b * sum;
}

/* ---- trilinear reconstruction, gradients: central differences at the grid
 * points, interpolated trilinearly ---- */
static double trilinear_sample(const rc_job *J, const double p[3], double g[3])
{
    const struct vs_volume *v = J->vol;
    int i0[3];
    double f[3];
    for (int a = 0; a < 3; a++) {
        double fl = floor(p[a]);
        i0[a] = (int)fl;
        f[a] = p[a] - fl;
    }
    if (!g) {
        double val = 0.0;
        for (int c = 0; c < 8; c++) {
            int dx = c & 1, dy = (c >> 1) & 1, dz = c >> 2;
            double wt = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
            if (wt != 0.0) val += wt * voxel(v, i0[0] + dx, i0[1] + dy, i0[2] + dz, J->base);
        }
        return val;
    }
    double win[4][4][4]; /* voxels i0-1 .. i0+2 */
    for (int z = 0; z < 4; z++)
        for (int y = 0; y < 4; y++)
            for (int x = 0; x < 4; x++)
                win[z][y][x] = voxel(v, i0[0] - 1 + x, i0[1] - 1 + y, i0[2] - 1 + z, J->base);
    double val = 0.0;
    g[0] = g[1] = g[2] = 0.0;
    for (int c = 0; c < 8; c++) {
        int dx = c & 1, dy = (c >> 1) & 1, dz = c >> 2;
        double wt = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
        int x = 1 + dx, y = 1 + dy, z = 1 + dz;
        val += wt * win[z][y][x];
        g[0] += wt * 0.5 * (win[z][y][x + 1] - win[z][y][x - 1]);
        g[1] += wt * 0.5 * (win[z][y + 1][x] - win[z][y - 1][x]);
        g[2] += wt * 0.5 * (win[z + 1][y][x] - win[z - 1][y][x]);
    }
    return val;
}

static double sample_value(const rc_job *J, const double p[3])
{
    switch (J->mode) {
    case MODE_ANALYTIC: return J->vol->analytic.f(J->vol->analytic.params, p);
    case MODE_GAUSS: return gauss_sample(J, p, NULL) + J->base;
    default: return trilinear_sample(J, p, NULL) + J->base;
    }
}

static void sample_gradient(const rc_job *J, const double p[3], double g[3])
{
    switch (J->mode) {
    case MODE_ANALYTIC: J->vol->analytic.grad(J->vol->analytic.params, p, g); break;
    case MODE_GAUSS: gauss_sample(J, p, g); break;
    default: trilinear_sample(J, p, g); break;
    }
}

static int in_iso_range(const vs_classify *c, double v) { return v >= c->lo && v <= c->hi; }

/* ---- one ray ---- */
static void cast_ray(const rc_job *J, int px, int py, double acc[4])
{
    const vs_settings *s = J->s;
    const vs_camera *cam = &J->cam;
    acc[0] = acc[1] = acc[2] = acc[3] = 0.0;
    /* the pixel's ray: index point p0 + z dir at view depth z (one direction
     * for every pixel when orthographic, diverging when perspective) */
    double p0[3], dir[3];
    vs_camera_ray(cam, px, py, p0, dir);
    const double dir_len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    /* opacity per step: the ray's length per unit of depth */
    const double step_len = J->step * vs_camera_ray_length(cam, px, py);
    /* clip the ray against the sample box (slab test), in view-z units */
    double t0 = cam->near_z, t1 = INFINITY;
    int entry_axis = -1;
    for (int a = 0; a < 3; a++) {
        double d = dir[a];
        if (fabs(d) < 1e-15) {
            if (p0[a] < J->box_lo[a] || p0[a] > J->box_hi[a]) return;
            continue;
        }
        double ta = (J->box_lo[a] - p0[a]) / d, tb = (J->box_hi[a] - p0[a]) / d;
        if (ta > tb) {
            double t = ta;
            ta = tb;
            tb = t;
        }
        if (ta > t0) {
            t0 = ta;
            entry_axis = a;
        }
        if (tb < t1) t1 = tb;
    }
    if (!(t0 <= t1)) return;
    long k0 = (long)ceil(t0 / J->step), k1 = (long)floor(t1 / J->step);
    const double *gs = J->vol->spacing;
    double A = 0.0, C[3] = {0.0, 0.0, 0.0};
    int have_prev = 0, prev_in = 0, wall = 0;
    double z_prev = 0.0, pe[3] = {0.0, 0.0, 0.0};
    if (J->refine && entry_axis >= 0) {
        /* The analytic domain ends at the volume's faces: a ray entering it
         * inside the iso-range sees a cut wall, shaded with the face normal. */
        for (int a = 0; a < 3; a++) pe[a] = p0[a] + t0 * dir[a];
        prev_in = in_iso_range(J->cls, sample_value(J, pe));
        have_prev = 1;
        z_prev = t0;
        wall = prev_in;
    }
    for (long k = k0; k <= k1; k++) {
        double z = k * J->step;
        double p[3] = {p0[0] + z * dir[0], p0[1] + z * dir[1], p0[2] + z * dir[2]};
        if (J->skip) {
            int b[3];
            for (int a = 0; a < 3; a++) {
                b[a] = (int)floor((p[a] - J->org) / BRICK);
                if (b[a] < 0) b[a] = 0;
                if (b[a] > J->nb[a] - 1) b[a] = J->nb[a] - 1;
            }
            if (J->skip[((size_t)b[2] * J->nb[1] + b[1]) * J->nb[0] + b[0]]) {
                /* jump to the first grid sample past the brick's exit */
                double texit = INFINITY;
                for (int a = 0; a < 3; a++) {
                    double d = dir[a];
                    if (fabs(d) < 1e-15) continue;
                    double plane = J->org + BRICK * (b[a] + (d > 0 ? 1 : 0));
                    double t = (plane - p0[a]) / d;
                    if (t < texit) texit = t;
                }
                long kn = (long)floor(texit / J->step) + 1;
                k = (kn > k + 1 ? kn : k + 1) - 1;
                have_prev = 0;
                continue;
            }
        }
        double val = sample_value(J, p);
        float rgb[3], alpha;
        vs_classify_eval(J->cls, s, val, rgb, &alpha);
        double ps[3] = {p[0], p[1], p[2]}; /* where this sample is shaded */
        int in = J->refine ? in_iso_range(J->cls, val) : 0;
        if (J->refine && have_prev && in && !prev_in) {
            /* The iso crossing lies in (z_prev, z]: bisect to 1e-4 voxel and
             * shade there, so the normal is that of the true surface. */
            double za = z_prev, zb = z;
            while ((zb - za) * dir_len > 1e-4) {
                double zm = 0.5 * (za + zb);
                double pm[3] = {p0[0] + zm * dir[0], p0[1] + zm * dir[1], p0[2] + zm * dir[2]};
                if (in_iso_range(J->cls, sample_value(J, pm)))
                    zb = zm;
                else
                    za = zm;
            }
            for (int a = 0; a < 3; a++) ps[a] = p0[a] + zb * dir[a];
        }
        have_prev = 1;
        prev_in = in;
        z_prev = z;
        int at_wall = wall;
        wall = 0;
        if (!(alpha > 0.0f)) continue;
        double op = vs_opacity_correct(alpha, step_len);
        double g[3], gw[3], n[3], diff, spec;
        if (at_wall) { /* inward face normal: into the dense region */
            g[0] = g[1] = g[2] = 0.0;
            g[entry_axis] = dir[entry_axis] > 0 ? 1.0 : -1.0;
        } else {
            sample_gradient(J, ps, g);
        }
        for (int a = 0; a < 3; a++) gw[a] = g[a] / gs[a];
        n[0] = gw[0] * cam->right[0] + gw[1] * cam->right[1] + gw[2] * cam->right[2];
        n[1] = -(gw[0] * cam->up[0] + gw[1] * cam->up[1] + gw[2] * cam->up[2]);
        n[2] = gw[0] * cam->dir[0] + gw[1] * cam->dir[1] + gw[2] * cam->dir[2];
        vs_light_eval(&J->light, n, &diff, &spec);
        double w = (1.0 - A) * op;
        for (int c = 0; c < 3; c++) C[c] += w * (rgb[c] * diff + spec);
        A += w;
        if (A > 0.999) break; /* early ray termination */
    }
    acc[0] = C[0];
    acc[1] = C[1];
    acc[2] = C[2];
    acc[3] = A;
}

static void render_row(rc_job *J, int y)
{
    const float *bg = J->s->background;
    float *out = J->rgba + (size_t)4 * y * J->cam.width;
    for (int x = 0; x < J->cam.width; x++) {
        double acc[4];
        cast_ray(J, x, y, acc);
        const float af[4] = {(float)acc[0], (float)acc[1], (float)acc[2], (float)acc[3]};
        vs_finish_pixel(af, bg, out + 4 * x);
    }
}

/* Progress (rows done) to the callback, on the thread that called
 * vs_render: after each of its rows, and while it waits for the others'. */
static void row_progress(void *arg)
{
    rc_job *J = arg;
    const vs_settings *s = J->s;
    if (atomic_load(&J->cancel) || !s->progress) return;
    if (s->progress(s->progress_user, (double)atomic_load(&J->rows_done) / J->cam.height) != 0)
        atomic_store(&J->cancel, 1);
}

/* Pool task: image row y; after a cancel the remaining rows return at
 * once. */
static void row_task(void *arg, int worker, int y)
{
    rc_job *J = arg;
    if (atomic_load(&J->cancel)) return;
    double t = vs_now_ms();
    render_row(J, y);
    J->ms[worker] += vs_now_ms() - t;
    atomic_fetch_add(&J->rows_done, 1);
    if (worker == 0) row_progress(J);
}

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
                    fetch_row(v, j, k, 0, nx - 1, row, J->base);
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
                fetch_row(v, j, k, 0, nx - 1, row, J->base);
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
                double vlo = fmin(m * B->wmin, m * B->wmax), vhi = fmax(M * B->wmin, M * B->wmax);
                size_t bl = ((size_t)(b - B->b0) * by + y) * bx + x;
                if (gauss) {
                    vhi = fmin(vhi, kb_hi[bl]);
                    vlo = fmax(vlo, -(double)kb_neg[bl]);
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
static vs_status build_skip(vs_context *ctx, rc_job *J, struct vs_pool *pool)
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

/* ---- entry ---- */
vs_status vs_raycast_render(vs_context *ctx, const struct vs_volume *vol, const vs_settings *s,
                            vs_image *out, vs_stats *st)
{
    if (!vol || !s || !out)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "raycast: NULL %s",
                            !vol ? "volume" : !s ? "settings" : "output image");
    out->width = out->height = 0;
    out->rgba = NULL;
    if (!vol->data) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "raycast: volume has no data");
    if (!(s->ray_step >= 1e-4) || !isfinite(s->ray_step) || s->ray_step > 1e4)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "raycast: ray step %g must lie in [1e-4, 1e4]",
                            s->ray_step);
    if (!(s->kernel_radius > 0.0) || !(s->kernel_radius <= 8.0))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "raycast: kernel radius %g must lie in (0, 8]",
                            s->kernel_radius);
    if (s->threads < 0)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "raycast: thread count %d is negative", s->threads);
    if (s->background[3] < 0.0f || s->background[3] > 1.0f || !isfinite(s->background[0]) ||
        !isfinite(s->background[1]) || !isfinite(s->background[2]))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "raycast: background must be finite with alpha in [0,1]");
    double t_start = vs_now_ms();

    rc_job *J = calloc(1, sizeof *J);
    vs_classify *cls = malloc(sizeof *cls);
    if (!J || !cls) {
        free(J);
        free(cls);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "raycast: out of memory");
    }
    vs_status rc = vs_camera_setup(ctx, vol, s, &J->cam);
    if (rc == VS_OK) rc = vs_classify_setup(ctx, vol, s, cls);
    if (rc != VS_OK) {
        free(J);
        free(cls);
        return rc;
    }
    J->vol = vol;
    J->s = s;
    J->cls = cls;
    vs_light_setup(s, &J->cam, &J->light);
    J->mode = (s->ray_analytic && vol->has_analytic) ? MODE_ANALYTIC
              : s->ray_trilinear                     ? MODE_TRILINEAR
                                                     : MODE_GAUSS;
    J->base = J->mode == MODE_ANALYTIC ? 0.0 : vs_volume_base(vol);
    J->R = s->kernel_radius;
    J->R2 = J->R * J->R;
    J->b = vs_kernel_b(J->R);
    J->step = s->ray_step;
    J->refine = J->mode == MODE_ANALYTIC && !cls->use_points;
    for (int a = 0; a < 3; a++) {
        /* Sampled data reaches R beyond the outer voxels.  An analytic
         * function is defined everywhere; we cut it where the voxels end
         * (half a voxel beyond the outer ones, like the cube's edge) so that
         * it describes the same finite object as the volume. */
        double ext = J->mode == MODE_ANALYTIC ? 0.5 : J->R;
        J->box_lo[a] = -ext;
        J->box_hi[a] = vol->dims[a] - 1 + ext;
    }
    rc = vs_context_pool(ctx, s);
    double t_setup = vs_now_ms();
    if (rc == VS_OK && J->mode != MODE_ANALYTIC) rc = build_skip(ctx, J, ctx->pool);
    if (rc != VS_OK) {
        free(cls);
        free(J);
        return rc;
    }
    double ms_setup = vs_now_ms() - t_setup;
    const int nthreads = vs_pool_threads(ctx->pool);
    size_t npix = (size_t)J->cam.width * J->cam.height;
    J->rgba = malloc(npix * 4 * sizeof(float));
    J->ms = calloc((size_t)nthreads, sizeof *J->ms);
    if (!J->rgba || !J->ms) {
        vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "raycast: cannot allocate a %dx%d image", J->cam.width,
                     J->cam.height);
        free(J->rgba);
        free(J->ms);
        free(J->skip);
        free(cls);
        free(J);
        return VS_ERR_OUT_OF_MEMORY;
    }
    atomic_init(&J->rows_done, 0);
    atomic_init(&J->cancel, 0);

    vs_pool_run_watched(ctx->pool, J->cam.height, row_task, J, s->progress ? row_progress : NULL, J);
    double ms_threads = 0.0;
    for (int i = 0; i < nthreads; i++) ms_threads += J->ms[i];
    free(J->ms);
    int cancelled = atomic_load(&J->cancel);
    free(J->skip);
    if (cancelled) {
        free(J->rgba);
        free(cls);
        free(J);
        return vs_set_error(ctx, VS_ERR_CANCELLED, "raycast: cancelled by the progress callback");
    }
    /* completion is reported even when other threads cast every row (a
     * small image), as the splatting pipelines do */
    if (s->progress) s->progress(s->progress_user, 1.0);
    out->width = J->cam.width;
    out->height = J->cam.height;
    out->rgba = J->rgba;
    if (st) {
        memset(st, 0, sizeof *st);
        st->pipeline = "raycast";
        st->isa = "scalar";
        st->threads = nthreads;
        st->width = out->width;
        st->height = out->height;
        st->voxels_total = (uint64_t)vol->dims[0] * vol->dims[1] * vol->dims[2];
        st->ms_stage.setup = ms_setup;   /* the brick grid for empty-space skipping */
        st->ms_stage.shade = ms_threads; /* casting rays, summed over threads */
        st->iso_lo = cls->lo;
        st->iso_hi = cls->hi;
        st->ramp = cls->ramp;
        st->pin_warning = vs_pool_pin_failed(ctx->pool);
        st->ms_total = vs_now_ms() - t_start;
    }
    free(cls);
    free(J);
    return VS_OK;
}
