/* Reference ray caster: post-classified, Phong-shaded with the same light and
 * material model as the splatting pipelines, one ray per pixel along +z of
 * view space (parallel rays, or rays from the eye with perspective).  Three reconstructions:
 *   analytic  - the scene's closed form, iso crossings refined by bisection
 *               (ground truth for error measurements);
 *   gaussian  - the exact sum of the splatting kernel b 2^(-2 r^2) over the
 *               voxels within radius R, with its analytic derivative, or
 *               (ray_normalize) that sum over the kernel's own lattice sum;
 *   trilinear - for comparison, with central-difference gradients.
 * Samples lie on a global grid z = k * ray_step (view units: planes parallel
 * to the image, like the splatting sheets), so neighbouring rays sample
 * consistently.  Rows are tasks on the context's worker pool (src/pool.h),
 * as the splatting tiles are; each pixel is computed independently, so the
 * image is identical for any thread count. */
#include "raycast.h"
#include "raycast_job.h"
#include "relevant.h"
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

/* a voxel less base; outside the volume 0, or with faces the nearest one */
static double voxel(const struct vs_volume *v, int i, int j, int k, double base, int faces)
{
    if (faces) {
        i = i < 0 ? 0 : i >= v->dims[0] ? v->dims[0] - 1 : i;
        j = j < 0 ? 0 : j >= v->dims[1] ? v->dims[1] - 1 : j;
        k = k < 0 ? 0 : k >= v->dims[2] ? v->dims[2] - 1 : k;
    } else if (i < 0 || j < 0 || k < 0 || i >= v->dims[0] || j >= v->dims[1] || k >= v->dims[2]) {
        return 0.0;
    }
    double x = vs_volume_at(v, ((size_t)k * v->dims[1] + j) * v->dims[0] + i);
    return isfinite(x) ? x - base : 0.0;
}

/* ---- Gaussian reconstruction: f(p) = b sum_j f_j 2^(-2|p-j|^2), |p-j| <= R;
 * normalised (settings' ray_normalize), f(p) = sum_j f_j 2^(-2|p-j|^2) / W(p):
 * the weights a partition of unity, so the kernel's lattice ripple, which
 * the plain sum carries into the gradient in proportion to the value (not
 * to the slope), is gone.  With faces (vs_classify_faces), near a face
 * the sum is divided by the voxels' share of the lattice sum, W_in / W
 * (normalised: W_in replaces W), as splatting divides its sheets
 * (face_cover.h) ---- */
static double gauss_sample(const rc_job *J, const double p[3], double g[3])
{
    const struct vs_volume *v = J->vol;
    /* voxels [lo, hi] within R inside the volume; the taps t0.. cover them
     * and, normalised or near a face, every lattice point within R (the
     * lattice sum W(p), which ripples within about 0.5 % of its mean over a
     * cell for R = 2, counts those outside the volume too: they read as
     * base, 0 here) */
    int ulo[3], uhi[3], lo[3], hi[3], t0[3], nt[3], near = 0;
    double d[3][MAX_TAPS], d2[3][MAX_TAPS], w[3][MAX_TAPS];
    for (int a = 0; a < 3; a++) {
        ulo[a] = (int)ceil(p[a] - J->R), uhi[a] = (int)floor(p[a] + J->R);
        lo[a] = ulo[a] < 0 ? 0 : ulo[a];
        hi[a] = uhi[a] > v->dims[a] - 1 ? v->dims[a] - 1 : uhi[a];
        if (lo[a] > hi[a]) {
            if (g) g[0] = g[1] = g[2] = 0.0;
            return 0.0;
        }
        near |= J->faces && (lo[a] != ulo[a] || hi[a] != uhi[a]);
    }
    const int all = J->normalize || near;
    for (int a = 0; a < 3; a++) {
        t0[a] = all ? ulo[a] : lo[a];
        nt[a] = (all ? uhi[a] : hi[a]) - t0[a] + 1;
        for (int i = 0; i < nt[a]; i++) {
            double t = p[a] - (t0[a] + i);
            d[a][i] = t;
            d2[a][i] = t * t;
            w[a][i] = exp2(-2.0 * t * t); /* separable factor */
        }
    }
    double row[MAX_TAPS];
    double sum = 0.0, sx = 0.0, sy = 0.0, sz = 0.0, W = 0.0, wx = 0.0, wy = 0.0, wz = 0.0;
    double Wi = 0.0, wix = 0.0, wiy = 0.0, wiz = 0.0; /* the taps inside (near a face) */
    for (int kk = 0; kk < nt[2]; kk++) {
        const int k = t0[2] + kk;
        double rz = J->R2 - d2[2][kk];
        if (rz < 0.0) continue;
        for (int jj = 0; jj < nt[1]; jj++) {
            const int j = t0[1] + jj;
            double ry = rz - d2[1][jj];
            if (ry < 0.0) continue;
            double wyz = w[1][jj] * w[2][kk];
            const int row_in = j >= lo[1] && j <= hi[1] && k >= lo[2] && k <= hi[2];
            if (nt[0] != hi[0] - lo[0] + 1 || !row_in) memset(row, 0, sizeof row); /* taps outside the volume */
            if (row_in) vs_rc_fetch_row(v, j, k, lo[0], hi[0], row + (lo[0] - t0[0]), J->base);
            double rs = 0.0, rx = 0.0, ks = 0.0, kx = 0.0, ki = 0.0, kix = 0.0;
            for (int i = 0; i < nt[0]; i++) {
                if (d2[0][i] > ry) continue;
                double fw = row[i] * w[0][i];
                rs += fw;
                rx += fw * d[0][i];
                if (all) {
                    ks += w[0][i];
                    kx += w[0][i] * d[0][i];
                }
                if (near && row_in && t0[0] + i >= lo[0] && t0[0] + i <= hi[0]) {
                    ki += w[0][i];
                    kix += w[0][i] * d[0][i];
                }
            }
            sum += rs * wyz;
            W += ks * wyz;
            Wi += ki * wyz;
            if (g) {
                sx += rx * wyz;
                sy += rs * wyz * d[1][jj];
                sz += rs * wyz * d[2][kk];
                wx += kx * wyz;
                wy += ks * wyz * d[1][jj];
                wz += ks * wyz * d[2][kk];
                wix += kix * wyz;
                wiy += ki * wyz * d[1][jj];
                wiz += ki * wyz * d[2][kk];
            }
        }
    }
    if (near && !(Wi > 0.0)) { /* no voxel within R reaches (the sphere's corners) */
        if (g) g[0] = g[1] = g[2] = 0.0;
        return 0.0;
    }
    if (J->normalize) { /* over W, or near a face over the taps inside */
        const double Wn = near ? Wi : W, f = sum / Wn;
        if (g) { /* (grad S - f grad W) / W */
            const double c = -4.0 * M_LN2 / Wn;
            g[0] = c * (sx - f * (near ? wix : wx));
            g[1] = c * (sy - f * (near ? wiy : wy));
            g[2] = c * (sz - f * (near ? wiz : wz));
        }
        return f;
    }
    if (near) { /* b sum K, K = W / W_in: grad = b (grad(sum) K + sum grad K) */
        const double c = -4.0 * M_LN2, K = W / Wi;
        if (g) {
            const double dK[3] = {c * (wx * Wi - W * wix) / (Wi * Wi), c * (wy * Wi - W * wiy) / (Wi * Wi),
                                  c * (wz * Wi - W * wiz) / (Wi * Wi)};
            g[0] = J->b * (c * sx * K + sum * dK[0]);
            g[1] = J->b * (c * sy * K + sum * dK[1]);
            g[2] = J->b * (c * sz * K + sum * dK[2]);
        }
        return J->b * sum * K;
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
            if (wt != 0.0) val += wt * voxel(v, i0[0] + dx, i0[1] + dy, i0[2] + dz, J->base, J->faces);
        }
        return val;
    }
    double win[4][4][4]; /* voxels i0-1 .. i0+2 */
    for (int z = 0; z < 4; z++)
        for (int y = 0; y < 4; y++)
            for (int x = 0; x < 4; x++)
                win[z][y][x] = voxel(v, i0[0] - 1 + x, i0[1] - 1 + y, i0[2] - 1 + z, J->base, J->faces);
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
    double t0 = J->t_near, t1 = INFINITY;
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
    if (s->ray_normalize != 0 && s->ray_normalize != 1)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "raycast: ray_normalize %d must be 0 or 1", s->ray_normalize);
    if (!(s->kernel_radius > 0.0) || !(s->kernel_radius <= 8.0))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "raycast: kernel radius %g must lie in (0, 8]",
                            s->kernel_radius);
    /* under sqrt(3)/2 a cell centre has no lattice point within R (0/0), and
     * near it the lattice sum's sampled lower bound (raycast_skip.c) misses
     * its jumps */
    if (s->ray_normalize && s->kernel_radius < 1.0)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "raycast: ray_normalize needs a kernel radius of 1 or more, not %g",
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
    J->normalize = J->mode == MODE_GAUSS && s->ray_normalize;
    J->faces = J->mode != MODE_ANALYTIC && vs_classify_faces(cls, J->base, vol->vmax);
    J->R = s->kernel_radius;
    J->R2 = J->R * J->R;
    J->b = vs_kernel_b(J->R);
    J->t_near = fmax(J->cam.near_z, vs_camera_near_cut(&J->cam, J->R, s->slab));
    J->step = s->ray_step;
    J->refine = J->mode == MODE_ANALYTIC && !cls->use_points;
    for (int a = 0; a < 3; a++) {
        /* Sampled data reaches R beyond the outer voxels.  An analytic
         * function is defined everywhere; we cut it where the voxels end
         * (half a voxel beyond the outer ones, like the cube's edge) so that
         * it describes the same finite object as the volume.  Where the
         * fall-off to the value outside would show (vs_classify_faces),
         * sampled data is cut there too, as splatting's sheets are
         * (face_cover.h). */
        double ext = J->mode == MODE_ANALYTIC || J->faces ? 0.5 : J->R;
        J->box_lo[a] = -ext;
        J->box_hi[a] = vol->dims[a] - 1 + ext;
    }
    rc = vs_context_pool(ctx, s);
    double t_setup = vs_now_ms();
    if (rc == VS_OK && J->mode != MODE_ANALYTIC) rc = vs_raycast_build_skip(ctx, J, ctx->pool);
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
