/* vsplat-bench oracle: what perfect visibility would buy.
 *
 * For each view, an oracle volume keeps only the voxels that can reach the
 * picture: a ray march of the same iso-range finds, per line of sight, the
 * depth where the accumulated opacity reaches ORACLE_OPAQUE; every voxel more
 * than the kernel's depth extent plus the gradient's reach behind that depth,
 * within the kernel's footprint radius around its line of sight, becomes air
 * (the volume's minimum, which the iso-range must classify transparent).
 * vsplat then renders the full and the oracle volume, frames interleaved,
 * each with its own context (so the relevant-voxel lists are built before
 * timing), and prints the medians, their ratio, the work counters and the
 * PSNR between the two pictures (which shows that nothing visible was cut).
 *
 * The oracle frame is the ceiling of any visibility culling at voxel grain:
 * hidden voxels are never projected, tested or splatted, and the sheets
 * shrink to what the front voxels touch.  Voxels in front of the first
 * opacity are transparent already, so the relevant-voxel list drops them.
 * Orthographic views only; the same volumes, iso-ranges and 12 views as
 * `vsplat-bench peers` (bench_peer_cases). */
#include "bench.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define ORACLE_OPAQUE 0.999 /* stricter than the renderer's 0.995 threshold */

/* The classification of docs/DESIGN.md §2: 0 at iso - ramp, 1 at iso + ramp. */
static double ramp_alpha(double v, double iso, double ramp)
{
    double a = (v - (iso - ramp)) / (2.0 * ramp);
    return a < 0 ? 0 : a > 1 ? 1 : a;
}

typedef struct grid {
    const float *f; /* voxels as float */
    int n[3];
    double sp[3];
} grid;

static double sample(const grid *g, const double x[3])
{
    int i0[3];
    double t[3];
    for (int a = 0; a < 3; a++) {
        if (!(x[a] >= 0.0) || x[a] > g->n[a] - 1) return -INFINITY;
        i0[a] = (int)x[a];
        if (i0[a] >= g->n[a] - 1) i0[a] = g->n[a] > 1 ? g->n[a] - 2 : 0;
        t[a] = x[a] - i0[a];
    }
    const size_t sx = 1, sy = (size_t)g->n[0], sz = (size_t)g->n[0] * g->n[1];
    const size_t b = i0[0] + sy * i0[1] + sz * i0[2];
    const size_t dx = g->n[0] > 1 ? sx : 0, dy = g->n[1] > 1 ? sy : 0, dz = g->n[2] > 1 ? sz : 0;
    double c00 = g->f[b] * (1 - t[0]) + g->f[b + dx] * t[0];
    double c10 = g->f[b + dy] * (1 - t[0]) + g->f[b + dy + dx] * t[0];
    double c01 = g->f[b + dz] * (1 - t[0]) + g->f[b + dz + dx] * t[0];
    double c11 = g->f[b + dz + dy] * (1 - t[0]) + g->f[b + dz + dy + dx] * t[0];
    return (c00 * (1 - t[1]) + c10 * t[1]) * (1 - t[2]) + (c01 * (1 - t[1]) + c11 * t[1]) * t[2];
}

/* The viewing direction in the grid frame (mm along the index axes), from
 * the library's camera, and two unit vectors across it: any pair serves,
 * as lines of sight and voxels are placed on the same plane. */
static int view_axes(vs_context *ctx, const vs_volume *vol, const vs_settings *s, const double sp[3], double R[3],
                     double U[3], double D[3])
{
    double di[3], eye[3];
    if (vs_view_in_index(ctx, vol, s, di, eye) != VS_OK) return 1;
    double n = 0.0;
    for (int a = 0; a < 3; a++) D[a] = di[a] * sp[a], n += D[a] * D[a];
    n = sqrt(n);
    for (int a = 0; a < 3; a++) D[a] /= n;
    const double t[3] = {fabs(D[0]) < 0.9 ? 1.0 : 0.0, fabs(D[0]) < 0.9 ? 0.0 : 1.0, 0.0};
    R[0] = t[1] * D[2] - t[2] * D[1], R[1] = t[2] * D[0] - t[0] * D[2], R[2] = t[0] * D[1] - t[1] * D[0];
    n = sqrt(R[0] * R[0] + R[1] * R[1] + R[2] * R[2]);
    for (int a = 0; a < 3; a++) R[a] /= n;
    U[0] = D[1] * R[2] - D[2] * R[1], U[1] = D[2] * R[0] - D[0] * R[2], U[2] = D[0] * R[1] - D[1] * R[0];
    return 0;
}

/* Writes the oracle voxels into `dst` (a copy of the source's voxels) and
 * returns how many were made air. */
static size_t oracle_cull(const grid *g, vs_volume *dst, double air, size_t keep, double iso, double ramp,
                          const double R[3], const double U[3], const double D[3])
{
    double spmin = fmin(g->sp[0], fmin(g->sp[1], g->sp[2]));
    double spmax = fmax(g->sp[0], fmax(g->sp[1], g->sp[2]));
    const double h = spmin;        /* line-of-sight spacing on the image plane */
    const double dt = 0.5 * spmin; /* march step                               */
    /* extents of the volume on the image plane and in depth (voxel i at (i - (n-1)/2) * sp) */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < 8; c++) {
        double w[3];
        for (int a = 0; a < 3; a++) w[a] = ((c >> a & 1) ? 0.5 : -0.5) * (g->n[a] - 1) * g->sp[a];
        const double p[3] = {w[0] * R[0] + w[1] * R[1] + w[2] * R[2], w[0] * U[0] + w[1] * U[1] + w[2] * U[2],
                             w[0] * D[0] + w[1] * D[1] + w[2] * D[2]};
        for (int a = 0; a < 3; a++) lo[a] = fmin(lo[a], p[a]), hi[a] = fmax(hi[a], p[a]);
    }
    /* the footprints reach the kernel radius past the volume's outline: lines
     * of sight there see nothing opaque and keep the voxels that reach them */
    const double reach = 2.0 * spmax + 2.0 * h;
    for (int a = 0; a < 2; a++) lo[a] -= reach, hi[a] += reach;
    const int W = (int)ceil((hi[0] - lo[0]) / h) + 1, H = (int)ceil((hi[1] - lo[1]) / h) + 1;
    float *depth = malloc((size_t)W * H * sizeof *depth), *tmp = malloc((size_t)W * H * sizeof *tmp);
    if (!depth || !tmp) {
        free(depth);
        free(tmp);
        return 0;
    }
    const double step_exp = dt / spmin; /* opacity per unit step (the renderer's slab is one voxel) */
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const double u = lo[0] + x * h, v = lo[1] + y * h;
            double trans = 1.0, hit = INFINITY;
            for (double t = lo[2]; t <= hi[2]; t += dt) {
                double idx[3];
                for (int a = 0; a < 3; a++)
                    idx[a] = (u * R[a] + v * U[a] + t * D[a]) / g->sp[a] + 0.5 * (g->n[a] - 1);
                double s = sample(g, idx);
                if (s == -INFINITY) continue;
                double al = ramp_alpha(s, iso, ramp);
                if (al <= 0.0) continue;
                trans *= al >= 1.0 ? 0.0 : pow(1.0 - al, step_exp);
                if (1.0 - trans >= ORACLE_OPAQUE) {
                    hit = t;
                    break;
                }
            }
            depth[(size_t)y * W + x] = (float)hit;
        }
    /* a voxel's footprint reaches the kernel radius (2 voxels) around its
     * line of sight: the deepest opaque point in that square still lets it show */
    const int rad = (int)ceil((2.0 * spmax + h) / h);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float m = -INFINITY;
            for (int k = x - rad; k <= x + rad; k++)
                if (k >= 0 && k < W) m = fmaxf(m, depth[(size_t)y * W + k]);
            tmp[(size_t)y * W + x] = m;
        }
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float m = -INFINITY;
            for (int k = y - rad; k <= y + rad; k++)
                if (k >= 0 && k < H) m = fmaxf(m, tmp[(size_t)k * W + x]);
            depth[(size_t)y * W + x] = m;
        }
    /* behind that depth: the kernel's depth extent (2 voxels) and the
     * gradient's neighbours (2 more) still shape what shows */
    const double margin = 4.0 * spmax;
    size_t culled = 0;
    void *data = vs_volume_data(dst);
    const vs_type type = vs_volume_type(dst);
    size_t i = 0;
    for (int k = 0; k < g->n[2]; k++)
        for (int j = 0; j < g->n[1]; j++)
            for (int ii = 0; ii < g->n[0]; ii++, i++) {
                const double w[3] = {(ii - 0.5 * (g->n[0] - 1)) * g->sp[0], (j - 0.5 * (g->n[1] - 1)) * g->sp[1],
                                     (k - 0.5 * (g->n[2] - 1)) * g->sp[2]};
                const double u = w[0] * R[0] + w[1] * R[1] + w[2] * R[2];
                const double v = w[0] * U[0] + w[1] * U[1] + w[2] * U[2];
                const double t = w[0] * D[0] + w[1] * D[1] + w[2] * D[2];
                int x = (int)lround((u - lo[0]) / h), y = (int)lround((v - lo[1]) / h);
                x = x < 0 ? 0 : x >= W ? W - 1 : x;
                y = y < 0 ? 0 : y >= H ? H - 1 : y;
                if (!(t > depth[(size_t)y * W + x] + margin) || i == keep) continue;
                culled++;
                switch (type) {
                case VS_U8: ((uint8_t *)data)[i] = (uint8_t)air; break;
                case VS_I16: ((int16_t *)data)[i] = (int16_t)air; break;
                case VS_U16: ((uint16_t *)data)[i] = (uint16_t)air; break;
                default: ((float *)data)[i] = (float)air; break;
                }
            }
    free(depth);
    free(tmp);
    return culled;
}

static double voxel_at(const vs_volume *v, size_t i)
{
    const void *d = vs_volume_data((vs_volume *)v);
    switch (vs_volume_type(v)) {
    case VS_U8: return ((const uint8_t *)d)[i];
    case VS_I16: return ((const int16_t *)d)[i];
    case VS_U16: return ((const uint16_t *)d)[i];
    default: return ((const float *)d)[i];
    }
}

static size_t type_bytes(vs_type t) { return t == VS_U8 ? 1 : t == VS_F32 ? 4 : 2; }

typedef struct oracle_view {
    vs_volume *vol;
    vs_context *ctx;
    size_t culled;
} oracle_view;

static int run_oracle(const bench_opts *o, const bench_peer_case *od, FILE *csv)
{
    const char *key = o->quick ? od->quick : od->input;
    vs_volume *vol = NULL;
    int ls = bench_load(o, key, &vol);
    if (ls) return ls < 0;
    const int nviews = o->quick ? 4 : 12;
    const int runs = bench_runs(o, 3, 1);
    int failed = 0;
    vs_settings base;
    bench_peer_settings(o, od, &base);
    base.pipeline = VS_PIPELINE_POST_CD;
    const int size = base.width, threads = base.threads;
    const double iso = base.iso_lo, ramp = base.ramp;

    grid g;
    vs_volume_dims(vol, g.n);
    vs_volume_spacing(vol, g.sp);
    const size_t n = (size_t)g.n[0] * g.n[1] * g.n[2];
    double air, vmax;
    vs_volume_range(vol, &air, &vmax);
    if (ramp_alpha(air, iso, ramp) > 0.0) {
        printf("oracle %s: skipped: the volume's minimum %g is not transparent at iso %g ramp %g\n", od->name, air,
               iso, ramp);
        vs_volume_release(vol);
        return 0;
    }
    float *f = malloc(n * sizeof *f);
    oracle_view *ov = calloc((size_t)nviews, sizeof *ov);
    double *ms_full = calloc((size_t)runs * nviews, sizeof(double));
    double *ms_orc = calloc((size_t)runs * nviews, sizeof(double));
    vs_context *full = NULL;
    if (!f || !ov || !ms_full || !ms_orc || vs_context_create(&full) != VS_OK) {
        fprintf(stderr, "vsplat-bench: oracle: out of memory\n");
        failed = 1;
        goto done;
    }
    /* the brightest voxel stays: the classification tables span the value
     * range, which must not change */
    size_t keep = 0;
    for (size_t i = 0; i < n; i++) {
        f[i] = (float)voxel_at(vol, i);
        if (f[i] > f[keep]) keep = i;
    }
    g.f = f;


    /* the oracle volumes, and both renders of every view once: warm-up, work
     * counters and the picture check */
    double psnr_min = INFINITY;
    uint64_t proj[2] = {0, 0}, splat[2] = {0, 0}, cls[2] = {0, 0};
    size_t culled = 0;
    for (int v = 0; v < nviews && !failed; v++) {
        const double az = od->az + 360.0 * v / nviews;
        bench_progress(od->name, v, nviews, "oracle volumes");
        if (vs_volume_create(full, vs_volume_type(vol), g.n, g.sp, &ov[v].vol) != VS_OK ||
            vs_context_create(&ov[v].ctx) != VS_OK) {
            failed = 1;
            break;
        }
        memcpy(vs_volume_data(ov[v].vol), vs_volume_data(vol), n * type_bytes(vs_volume_type(vol)));
        vs_settings vs = base;
        vs.azimuth = az;
        double R[3], U[3], D[3];
        if (view_axes(full, vol, &vs, g.sp, R, U, D)) {
            fprintf(stderr, "vsplat-bench: oracle %s: %s\n", od->name, vs_last_error(full));
            failed = 1;
            break;
        }
        ov[v].culled = oracle_cull(&g, ov[v].vol, air, keep, iso, ramp, R, U, D);
        vs_volume_update_range(ov[v].vol);
        culled += ov[v].culled;
        vs_settings s = base;
        s.azimuth = az;
        vs_image a = {0, 0, NULL}, b = {0, 0, NULL};
        vs_stats sa, sb;
        vs_image_diff d;
        if (vs_render(full, vol, &s, &a, &sa) != VS_OK || vs_render(ov[v].ctx, ov[v].vol, &s, &b, &sb) != VS_OK ||
            vs_image_compare(full, &a, &b, &d) != VS_OK) {
            fprintf(stderr, "vsplat-bench: oracle %s: %s\n", od->name, vs_last_error(full));
            failed = 1;
        } else {
            psnr_min = fmin(psnr_min, d.psnr);
            proj[0] += sa.voxels_projected, proj[1] += sb.voxels_projected;
            splat[0] += sa.voxels_splatted, splat[1] += sb.voxels_splatted;
            cls[0] += sa.pixels_classified, cls[1] += sb.pixels_classified;
        }
        vs_image_free(&a);
        vs_image_free(&b);
    }
    bench_progress_end();
    if (failed) goto done;

    /* timed: full and oracle frames of each view interleaved, the order alternating */
    int nf = 0, no = 0;
    for (int r = 0; r < runs; r++)
        for (int v = 0; v < nviews; v++) {
            bench_progress(od->name, r * nviews + v, runs * nviews, "frames");
            vs_settings s = base;
            s.azimuth = od->az + 360.0 * v / nviews;
            for (int k = 0; k < 2; k++) {
                int which = (k + r + v) & 1;
                vs_image img = {0, 0, NULL};
                vs_stats st;
                vs_context *c = which ? ov[v].ctx : full;
                if (vs_render(c, which ? ov[v].vol : vol, &s, &img, &st) != VS_OK) {
                    fprintf(stderr, "vsplat-bench: oracle %s: %s\n", od->name, vs_last_error(c));
                    failed = 1;
                } else if (which) {
                    ms_orc[no++] = st.ms_total;
                } else {
                    ms_full[nf++] = st.ms_total;
                }
                vs_image_free(&img);
            }
        }
    bench_progress_end();
    if (failed || !nf || !no) goto done;
    {
        const double mf = bench_median(ms_full, nf), mo = bench_median(ms_orc, no);
        printf("-- %s (%s, %dx%dx%d), iso %g ramp %g, post-cd, %d threads, %dx%d, views %g+k*%g,%g, %d frames x %d "
               "runs --\n",
               od->name, key, g.n[0], g.n[1], g.n[2], iso, ramp, threads, size, size, od->az, 360.0 / nviews, od->el,
               nviews, runs);
        printf("%-8s %10s %14s %14s %16s\n", "frame", "median_ms", "voxels_proj", "voxels_splat", "pixels_classif");
        printf("%-8s %10.2f %14.0f %14.0f %16.0f\n", "full", mf, (double)proj[0] / nviews, (double)splat[0] / nviews,
               (double)cls[0] / nviews);
        printf("%-8s %10.2f %14.0f %14.0f %16.0f\n", "oracle", mo, (double)proj[1] / nviews,
               (double)splat[1] / nviews, (double)cls[1] / nviews);
        printf("oracle/full %.3f; voxels made air per view %.0f of %zu; PSNR oracle vs full (worst view) %.1f dB\n",
               mo / mf, (double)culled / nviews, n, psnr_min);
        fprintf(csv, "%s,%s,%d,%d,%d,%.3f,%.3f,%.4f,%.0f,%.0f,%.0f,%.0f,%.2f\n", od->name, key, size, threads, nviews,
                mf, mo, mo / mf, (double)proj[0] / nviews, (double)proj[1] / nviews, (double)splat[0] / nviews,
                (double)splat[1] / nviews, psnr_min);
        fflush(csv);
    }

done:
    for (int v = 0; ov && v < nviews; v++) {
        vs_volume_release(ov[v].vol);
        if (ov[v].ctx) vs_context_release(ov[v].ctx);
    }
    free(ov);
    free(f);
    free(ms_full);
    free(ms_orc);
    if (full) vs_context_release(full);
    vs_volume_release(vol);
    return failed;
}

int bench_oracle(const bench_opts *o)
{
    if (bench_results_dir(o)) return 2;
    FILE *csv = bench_result_open(o, "oracle.csv");
    if (!csv) return 2;
    fprintf(csv, "volume,input,size,threads,views,full_ms,oracle_ms,ratio,full_projected,oracle_projected,"
                 "full_splatted,oracle_splatted,psnr_oracle_vs_full\n");
    printf("\nOracle: vsplat post-cd on every voxel against only the voxels that can show (hidden ones made air "
           "from a ray march of the same iso-range), frames interleaved, medians; machine: %s; load average %s\n",
           bench_machine(), bench_loadavg());
    int failed = 0;
    for (int i = 0; i < bench_npeer_cases; i++) failed += run_oracle(o, &bench_peer_cases[i], csv);
    fclose(csv);
    return failed ? 2 : 0;
}
