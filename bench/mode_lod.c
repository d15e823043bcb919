/* vsplat-bench lod: levels of detail, a volume seen small.
 *
 * 1. Balls it generates in memory (never files): a big one, 1400x1400x1100
 *    u8 (2.16 G voxels; --quick 280x280x220), and the same ball sampled 4x
 *    coarser, rendered at the same image size (256^2, --quick 64^2) where
 *    the big one is minified ~7x.  Levels of detail (the default) and the
 *    coarse ball interleaved, then the big ball at full resolution
 *    (--no-lod).  Prints the medians, their ratio, the level, the pyramid's
 *    build time, the process's peak resident memory after each phase
 *    against the volume's size, and the PSNR of the level-of-detail frame
 *    against the full-resolution one.
 * 2. A row of balls it generates (256x256x2048 u8; --quick 64x64x512) seen
 *    down its length under perspective at 256^2 (--quick 64^2): depth bands
 *    of levels against full resolution, both against the reference.
 * 3. Real volumes (Colin27, the CT head, the EM stack; skipped with
 *    --quick) at 128^2 and 256^2, with and without levels of detail, each
 *    also compared with a reference: the full-resolution frame rendered 4x
 *    larger and box-filtered down (what the pixels should show; the
 *    full-resolution frame at the small size is aliased itself). */
#include "bench.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

static double peak_rss_gb(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss / (1024.0 * 1024.0); /* kB on Linux */
}

/* resident now (/proc/self/statm), GB; NAN where unreadable */
static double resident_gb(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    unsigned long long size = 0, res = 0;
    const int ok = f && fscanf(f, "%llu %llu", &size, &res) == 2;
    if (f) fclose(f);
    return ok ? (double)res * (double)sysconf(_SC_PAGESIZE) / (1024.0 * 1024.0 * 1024.0) : NAN;
}

/* A ball of radius 0.45 of the smallest extent, in millimetres of the big
 * ball's grid (the coarse one samples the same function with spacing 4):
 * 255 inside, 0 outside, a linear ramp 8 mm wide centred on the radius. */
static vs_volume *make_ball(vs_context *ctx, const int dims[3], double sp)
{
    vs_volume *v = NULL;
    const double spacing[3] = {sp, sp, sp};
    if (vs_volume_create(ctx, VS_U8, dims, spacing, &v) != VS_OK) {
        fprintf(stderr, "lod: %s\n", vs_last_error(ctx));
        return NULL;
    }
    uint8_t *d = vs_volume_data(v);
    double c[3], r = INFINITY;
    for (int a = 0; a < 3; a++) {
        c[a] = 0.5 * (dims[a] - 1) * sp;
        if (c[a] < r) r = c[a];
    }
    r *= 0.9;
    for (int k = 0; k < dims[2]; k++) {
        bench_progress("lod ball", k, dims[2], "");
        for (int j = 0; j < dims[1]; j++) {
            const double dz = k * sp - c[2], dy = j * sp - c[1], q = dz * dz + dy * dy;
            uint8_t *row = d + ((size_t)k * dims[1] + j) * dims[0];
            for (int i = 0; i < dims[0]; i++) {
                const double dx = i * sp - c[0], t = (r - sqrt(q + dx * dx)) / 8.0 + 0.5;
                row[i] = (uint8_t)lrint(255.0 * (t < 0 ? 0 : t > 1 ? 1 : t));
            }
        }
    }
    bench_progress_end();
    vs_volume_update_range(v);
    return v;
}

static double psnr(const vs_image *a, const vs_image *b)
{
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return NAN;
    vs_image_diff d;
    const double p = vs_image_compare(ctx, a, b, &d) == VS_OK ? d.psnr : NAN;
    vs_context_release(ctx);
    return p;
}

static void settings_for(const bench_opts *o, vs_settings *s, int size, double iso, double ramp, double az,
                         double el)
{
    vs_settings_init(s);
    s->width = s->height = size;
    s->has_iso = 1;
    s->iso_lo = iso;
    s->iso_hi = INFINITY;
    s->ramp = ramp;
    s->azimuth = az;
    s->elevation = el;
    s->threads = o->threads ? o->threads : 2;
}

/* a box filter of an image to 1/f of its size */
static vs_image shrink(const vs_image *a, int f)
{
    vs_image o = {a->width / f, a->height / f, NULL};
    o.rgba = calloc((size_t)o.width * o.height * 4, sizeof(float));
    if (!o.rgba) return o;
    for (int y = 0; y < o.height; y++)
        for (int x = 0; x < o.width; x++)
            for (int c = 0; c < 4; c++) {
                double acc = 0;
                for (int j = 0; j < f; j++)
                    for (int i = 0; i < f; i++)
                        acc += a->rgba[4 * ((size_t)(y * f + j) * a->width + x * f + i) + c];
                o.rgba[4 * ((size_t)y * o.width + x) + c] = (float)(acc / (f * f));
            }
    return o;
}

/* The reference for frame s of v: full resolution at 4x the size,
 * box-filtered (an empty image if it fails). */
static vs_image reference(const vs_volume *v, const vs_settings *s)
{
    vs_image large = {0, 0, NULL}, ref = {0, 0, NULL};
    vs_context *rc = NULL;
    vs_settings rs = *s;
    rs.width = 4 * s->width;
    rs.height = 4 * s->height;
    rs.lod_pixels = 0;
    if (vs_context_create(&rc) == VS_OK && vs_render(rc, v, &rs, &large, NULL) == VS_OK) ref = shrink(&large, 4);
    vs_context_release(rc);
    vs_image_free(&large);
    return ref;
}

static int balls(const bench_opts *o, int runs, FILE *csv)
{
    const int big[3] = {1400, 1400, 1100}, qbig[3] = {280, 280, 220};
    const int *nb = o->quick ? qbig : big, nc[3] = {nb[0] / 4, nb[1] / 4, nb[2] / 4};
    const int size = o->quick ? 64 : 256;
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return 1;
    vs_volume *vb = make_ball(ctx, nb, 1.0), *vc = make_ball(ctx, nc, 4.0);
    vs_context_release(ctx);
    if (!vb || !vc) {
        vs_volume_release(vb);
        vs_volume_release(vc);
        return 1;
    }
    const double gb = (double)nb[0] * nb[1] * nb[2] / 1e9;
    const double rss0 = peak_rss_gb();
    vs_settings s;
    settings_for(o, &s, size, 100, 10, 30, 20);
    bench_case c[3];
    char name[96];
    snprintf(name, sizeof name, "ball %dx%dx%d", nb[0], nb[1], nb[2]);
    bench_case_set(&c[0], name, vb, &s);
    snprintf(name, sizeof name, "ball %dx%dx%d (4x coarser)", nc[0], nc[1], nc[2]);
    bench_case_set(&c[1], name, vc, &s);
    c[0].keep_image = 1;
    int failed = bench_run("lod balls", c, 2, runs);
    const double rss1 = peak_rss_gb();
    s.lod_pixels = 0;
    snprintf(name, sizeof name, "ball %dx%dx%d --no-lod", nb[0], nb[1], nb[2]);
    bench_case_set(&c[2], name, vb, &s);
    c[2].keep_image = 1;
    failed += bench_run("lod balls, full resolution", c + 2, 1, runs < 3 ? runs : 3);
    const double rss2 = peak_rss_gb(), now2 = resident_gb(); /* both lists still held */
    vs_image ref = reference(vb, &s); /* s is the full-resolution frame's */

    printf("\nLevels of detail, balls: post-cd, %d^2, view 30,20, iso 100 ramp 10, %d threads, median ms over %d "
           "interleaved runs; machine: %s; load average %s\n",
           size, s.threads, runs, bench_machine(), bench_loadavg());
    printf("%-40s %6s %10s %12s %10s %10s %14s %14s\n", "case", "level", "median_ms", "splatted", "lod_ms", "list_ms",
           "psnr_vs_full", "psnr_vs_ref");
    double med[3];
    for (int i = 0; i < 3; i++) {
        const bench_summary m = bench_summarize(&c[i], bench_m_total);
        med[i] = m.median;
        const double p = i == 0 && !c[0].failed && !c[2].failed ? psnr(&c[0].img, &c[2].img) : NAN;
        const double pr = i != 1 && !c[i].failed && ref.rgba ? psnr(&c[i].img, &ref) : NAN;
        printf("%-40s %6d %10.1f %12llu %10.1f %10.1f %14.1f %14.1f\n", c[i].name, c[i].warm.lod_level, m.median,
               (unsigned long long)c[i].warm.voxels_splatted, c[i].warm.ms_lod, c[i].warm.ms_relevant, p, pr);
        if (csv)
            fprintf(csv, "%s,%d,%d,%.3f,%llu,%.3f,%.3f,%.2f,%.2f\n", c[i].name, size, c[i].warm.lod_level, m.median,
                    (unsigned long long)c[i].warm.voxels_splatted, c[i].warm.ms_lod, c[i].warm.ms_relevant, p, pr);
    }
    printf("big ball with levels of detail / coarse ball: %.2fx; full resolution / levels of detail: %.1fx\n",
           med[0] / med[1], med[2] / med[0]);
    printf("peak resident memory: %.2f GB with the balls made, %.2f GB after the level-of-detail frames, %.2f GB "
           "after the full-resolution ones, %.2f GB resident then (the big ball is %.2f GB)\n",
           rss0, rss1, rss2, now2, gb);
    if (csv)
        fprintf(csv, "# peak resident GB: balls made %.3f, after lod %.3f, after full %.3f (resident then %.3f); "
                     "volume %.3f\n",
                rss0, rss1, rss2, now2, gb);
    free(ref.rgba);
    bench_cases_free(c, 3);
    bench_contexts_release();
    vs_volume_release(vb);
    vs_volume_release(vc);
    return failed;
}

/* A row of balls (radius 18, every 64 voxels along z; a smooth edge 4
 * voxels wide) seen down its length under perspective: the near balls
 * need full resolution, the far ones a coarser level (depth bands,
 * src/lod_depth.c). */
static vs_volume *make_row(vs_context *ctx, const int d[3], int period)
{
    vs_volume *v = NULL;
    if (vs_volume_create(ctx, VS_U8, d, NULL, &v) != VS_OK) return NULL;
    uint8_t *p = vs_volume_data(v);
    const double r = 18.0 * period / 64.0, w = 4.0 * period / 64.0;
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++) {
                const double x = fmod(i, period) - 0.5 * (period - 1), y = fmod(j, period) - 0.5 * (period - 1),
                             z = fmod(k, period) - 0.5 * (period - 1);
                const double t = (r - sqrt(x * x + y * y + z * z)) / w + 0.5;
                p[((size_t)k * d[1] + j) * d[0] + i] = (uint8_t)lrint(255.0 * (t < 0 ? 0 : t > 1 ? 1 : t));
            }
    vs_volume_update_range(v);
    return v;
}

static int depth(const bench_opts *o, int runs, FILE *csv)
{
    const int d[3] = {o->quick ? 64 : 256, o->quick ? 64 : 256, o->quick ? 512 : 2048};
    const int size = o->quick ? 64 : 256, period = o->quick ? 16 : 64;
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return 1;
    vs_volume *v = make_row(ctx, d, period);
    vs_context_release(ctx);
    if (!v) return 1;
    vs_settings s;
    settings_for(o, &s, size, 128, 20, 10, 80);
    s.perspective_fov = 60;
    s.zoom = 2.0;
    bench_case c[2];
    char name[96];
    snprintf(name, sizeof name, "row %dx%dx%d, perspective 60", d[0], d[1], d[2]);
    bench_case_set(&c[0], name, v, &s);
    s.lod_pixels = 0;
    snprintf(name, sizeof name, "row %dx%dx%d, perspective 60 --no-lod", d[0], d[1], d[2]);
    bench_case_set(&c[1], name, v, &s);
    c[0].keep_image = c[1].keep_image = 1;
    int failed = bench_run("lod depth bands", c, 2, runs);
    vs_image ref = reference(v, &s);
    printf("\nLevels of detail by depth: post-cd, %d^2, perspective 60, view 10,80, zoom 2, iso 128 ramp 20, %d "
           "threads, median ms over %d interleaved runs; load average %s\n",
           size, s.threads, runs, bench_loadavg());
    printf("%-48s %6s %10s %12s %14s\n", "case", "level", "median_ms", "splatted", "psnr_vs_ref");
    double med[2];
    for (int i = 0; i < 2; i++) {
        const bench_summary m = bench_summarize(&c[i], bench_m_total);
        med[i] = m.median;
        const double pr = !c[i].failed && ref.rgba ? psnr(&c[i].img, &ref) : NAN;
        printf("%-48s %6d %10.1f %12llu %14.1f\n", c[i].name, c[i].warm.lod_level, m.median,
               (unsigned long long)c[i].warm.voxels_splatted, pr);
        if (csv)
            fprintf(csv, "%s,%d,%d,%.3f,%llu,%.2f\n", c[i].name, size, c[i].warm.lod_level, m.median,
                    (unsigned long long)c[i].warm.voxels_splatted, pr);
    }
    const double pf = !c[0].failed && !c[1].failed ? psnr(&c[0].img, &c[1].img) : NAN;
    printf("full resolution / depth bands: %.2fx; bands against full resolution %.1f dB\n", med[1] / med[0], pf);
    free(ref.rgba);
    bench_cases_free(c, 2);
    bench_contexts_release();
    vs_volume_release(v);
    return failed;
}

static int real(const bench_opts *o, int runs, FILE *csv)
{
    static const struct {
        const char *name, *key;
        double iso, ramp, az, el;
    } vols[] = {{"colin27", "colin27", 45, 10, 180, 0}, {"ct-head", "ct", 400, 100, 180, 15},
                {"em", "em", 124, 10, 30, 30}};
    static const int sizes[] = {128, 256};
    int failed = 0;
    printf("\nLevels of detail, real volumes: post-cd, %d threads; PSNR against the full-resolution frame and "
           "against the reference (full resolution at 4x the size, box-filtered)\n",
           o->threads ? o->threads : 2);
    printf("%-10s %5s %6s %10s %10s %8s %12s %12s %12s\n", "volume", "size", "level", "lod_ms", "full_ms", "speed",
           "lod_vs_full", "lod_vs_ref", "full_vs_ref");
    for (size_t v = 0; v < sizeof vols / sizeof vols[0]; v++) {
        vs_volume *vol = NULL;
        const int st = bench_load(o, vols[v].key, &vol);
        if (st) {
            failed += st < 0;
            continue;
        }
        for (int z = 0; z < 2; z++) {
            vs_settings s;
            settings_for(o, &s, sizes[z], vols[v].iso, vols[v].ramp, vols[v].az, vols[v].el);
            bench_case c[2];
            bench_case_set(&c[0], "lod", vol, &s);
            s.lod_pixels = 0;
            bench_case_set(&c[1], "full", vol, &s);
            c[0].keep_image = c[1].keep_image = 1;
            failed += bench_run(vols[v].name, c, 2, runs);
            /* the reference, once */
            s.width = s.height = 4 * sizes[z];
            vs_context *ctx = NULL;
            vs_image big = {0, 0, NULL}, ref = {0, 0, NULL};
            if (vs_context_create(&ctx) == VS_OK && vs_render(ctx, vol, &s, &big, NULL) == VS_OK) ref = shrink(&big, 4);
            vs_context_release(ctx);
            const bench_summary a = bench_summarize(&c[0], bench_m_total), b = bench_summarize(&c[1], bench_m_total);
            const double pf = psnr(&c[0].img, &c[1].img), pr = ref.rgba ? psnr(&c[0].img, &ref) : NAN,
                         pfr = ref.rgba ? psnr(&c[1].img, &ref) : NAN;
            printf("%-10s %5d %6d %10.1f %10.1f %7.2fx %12.1f %12.1f %12.1f\n", vols[v].name, sizes[z],
                   c[0].warm.lod_level, a.median, b.median, b.median / a.median, pf, pr, pfr);
            if (csv)
                fprintf(csv, "%s,%d,%d,%.3f,%.3f,%.2f,%.2f,%.2f\n", vols[v].name, sizes[z], c[0].warm.lod_level,
                        a.median, b.median, pf, pr, pfr);
            vs_image_free(&big);
            free(ref.rgba);
            bench_cases_free(c, 2);
            bench_contexts_release();
        }
        vs_volume_release(vol);
    }
    return failed;
}

int bench_lod(const bench_opts *o)
{
    const double t0 = bench_now_ms();
    const int runs = bench_runs(o, 5, 2);
    if (bench_results_dir(o)) return 2;
    FILE *csv = bench_result_open(o, "lod_balls.csv");
    if (csv) fprintf(csv, "case,size,level,median_ms,splatted,lod_build_ms,list_build_ms,psnr_vs_full,psnr_vs_ref\n");
    int failed = balls(o, runs, csv);
    if (csv) fclose(csv);
    csv = bench_result_open(o, "lod_depth.csv");
    if (csv) fprintf(csv, "case,size,nearest_level,median_ms,splatted,psnr_vs_ref\n");
    failed += depth(o, runs, csv);
    if (csv) fclose(csv);
    if (!o->quick) {
        csv = bench_result_open(o, "lod_real.csv");
        if (csv) fprintf(csv, "volume,size,level,lod_ms,full_ms,psnr_lod_vs_full,psnr_lod_vs_ref,psnr_full_vs_ref\n");
        failed += real(o, runs, csv);
        if (csv) fclose(csv);
    }
    printf("lod: %.1f s, results in %s\n", (bench_now_ms() - t0) / 1000.0, o->out_dir);
    return failed ? 2 : 0;
}
