/* vsplat-bench growth: how frame time grows with the volume (sphere:N,
 * N = 32..1024, fixed image; at full resolution and with levels of detail,
 * against the volume's voxel count) and
 * with the image size (sphere:128, 128^2..2048^2; and a volume seen small,
 * sphere:512 at 128^2..1024^2, with and without levels of detail), with
 * least-squares slopes on log-log axes. */
#include "bench.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Least squares y = a + b x on (log x, log y); returns b, r2 in *r2. */
static double loglog_slope(const double *x, const double *y, int n, double *r2)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
    int m = 0;
    for (int i = 0; i < n; i++) {
        if (!(x[i] > 0) || !(y[i] > 0)) continue;
        double lx = log(x[i]), ly = log(y[i]);
        sx += lx;
        sy += ly;
        sxx += lx * lx;
        sxy += lx * ly;
        syy += ly * ly;
        m++;
    }
    *r2 = NAN;
    if (m < 2) return NAN;
    double vx = sxx - sx * sx / m, vy = syy - sy * sy / m, cxy = sxy - sx * sy / m;
    if (!(vx > 0)) return NAN;
    if (vy > 0) *r2 = cxy * cxy / (vx * vy);
    return cxy / vx;
}

/* x of a series' points: the volume's voxels, or the image's pixels */
enum { X_VOXELS, X_PIXELS };

/* One curve: sphere:N over n volumes at one image size, or one sphere
 * over image sizes; full resolution (lod 0) or levels of detail. */
typedef struct series {
    const char *name;  /* CSV and growth.dat */
    char title[48];    /* plot key           */
    int lod, x, n;
    int vol[6];        /* sphere sides (one, repeated, for an image series) */
    int size[6];       /* image sides                                       */
    int first;         /* its first case                                    */
    double slope, r2;
} series;

/* A case: post-cd, view 20,15; lod 0 renders full resolution. */
static void add_case(bench_case *c, const bench_opts *o, const vs_volume *v, int n, int size, int lod)
{
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = size;
    s.azimuth = 20;
    s.elevation = 15;
    s.threads = o->threads;
    if (!lod) s.lod_pixels = 0;
    char name[64];
    snprintf(name, sizeof name, "sphere:%d at %d^2%s", n, size, lod ? ", lod" : "");
    bench_case_set(c, name, v, &s);
}

/* The series: full mode, or --quick (smaller volumes and images). */
static int make_series(const bench_opts *o, series *sr)
{
    const int q = o->quick;
    const int vs = q ? 128 : 256; /* image side of the voxel series */
    const int big = q ? 256 : 512; /* the volume seen small          */
    const int nvol = q ? 4 : 6, nimg = q ? 4 : 5, nbig = q ? 3 : 4;
    static const int sides[] = {32, 64, 128, 256, 512, 1024}, images[] = {128, 256, 512, 1024, 2048};
    series all[5] = {
        {"voxels", "full resolution", 0, X_VOXELS, nvol, {0}, {0}, 0, 0, 0},
        {"voxels_lod", "levels of detail", 1, X_VOXELS, nvol, {0}, {0}, 0, 0, 0},
        {"image", "sphere:128", 1, X_PIXELS, nimg, {0}, {0}, 0, 0, 0},
        {"image_small", "", 0, X_PIXELS, nbig, {0}, {0}, 0, 0, 0},
        {"image_small_lod", "", 1, X_PIXELS, nbig, {0}, {0}, 0, 0, 0},
    };
    for (int i = 0; i < 6; i++) {
        all[0].vol[i] = all[1].vol[i] = sides[i];
        all[0].size[i] = all[1].size[i] = vs;
        all[2].vol[i] = 128;
        all[2].size[i] = i < 5 ? images[i] : 0;
        all[3].vol[i] = all[4].vol[i] = big;
        all[3].size[i] = all[4].size[i] = i < 5 ? images[i] : 0;
    }
    snprintf(all[3].title, sizeof all[3].title, "sphere:%d, full resolution", big);
    snprintf(all[4].title, sizeof all[4].title, "sphere:%d, levels of detail", big);
    memcpy(sr, all, sizeof all);
    return 5;
}

int bench_growth(const bench_opts *o)
{
    double t0 = bench_now_ms();
    const int runs = bench_runs(o, 3, 1);
    series sr[5];
    const int ns = make_series(o, sr);
    int failed = 0;

    /* each sphere once, shared by the series that use it */
    enum { MAXV = 8 };
    int side[MAXV], nload = 0;
    vs_volume *vols[MAXV] = {0};
    for (int k = 0; k < ns; k++)
        for (int i = 0; i < sr[k].n; i++) {
            int have = 0;
            for (int j = 0; j < nload; j++) have |= side[j] == sr[k].vol[i];
            if (!have && nload < MAXV) side[nload++] = sr[k].vol[i];
        }
    for (int j = 0; j < nload && !failed; j++) {
        char key[64];
        snprintf(key, sizeof key, "scene:sphere:%d", side[j]);
        if (bench_load(o, key, &vols[j]) != 0) failed++;
    }
    if (failed) {
        for (int j = 0; j < nload; j++)
            if (vols[j]) vs_volume_release(vols[j]);
        return 2;
    }

    bench_case cases[32];
    int n = 0;
    for (int k = 0; k < ns; k++) {
        sr[k].first = n;
        for (int i = 0; i < sr[k].n; i++) {
            int j = 0;
            while (side[j] != sr[k].vol[i]) j++;
            add_case(&cases[n++], o, vols[j], sr[k].vol[i], sr[k].size[i], sr[k].lod);
        }
    }
    failed += bench_run("growth", cases, n, runs);

    printf("\nGrowth: post-cd, view 20,15, threads %d (0 = one per core), median ms over %d interleaved run%s; "
           "machine: %s; load average %s\n",
           o->threads, runs, runs == 1 ? "" : "s", bench_machine(), bench_loadavg());
    if (bench_results_dir(o)) failed++;
    FILE *csv = bench_result_open(o, "growth.csv");
    FILE *dat = bench_result_open(o, "growth.dat");
    if (csv) fprintf(csv, "series,scene,size,image,voxels_total,voxels_relevant,voxels_splatted,pixels,lod_level,"
                          "median_ms,min_ms,max_ms,ms_relevant_build,runs\n");
    printf("%-28s %12s %12s %12s %5s %10s %21s %12s\n", "case", "voxels", "relevant", "splatted", "level",
           "median_ms", "min-max", "list_build_ms");
    for (int k = 0; k < ns; k++) {
        double x[6], y[6];
        if (dat) fprintf(dat, "%s# %s: x median_ms splatted\n", k ? "\n\n" : "", sr[k].name);
        for (int i = 0; i < sr[k].n; i++) {
            const bench_case *c = &cases[sr[k].first + i];
            bench_summary m = bench_summarize(c, bench_m_total);
            const double px = (double)c->s.width * c->s.height;
            x[i] = sr[k].x == X_VOXELS ? (double)c->warm.voxels_total : px;
            y[i] = m.median;
            printf("%-28s %12llu %12llu %12llu %5d %10.1f %10.1f-%-10.1f %12.1f\n", c->name,
                   (unsigned long long)c->warm.voxels_total, (unsigned long long)c->warm.voxels_relevant,
                   (unsigned long long)c->warm.voxels_splatted, c->warm.lod_level, m.median, m.min, m.max,
                   c->warm.ms_relevant);
            if (csv)
                fprintf(csv, "%s,sphere,%d,%d,%llu,%llu,%llu,%.0f,%d,%.3f,%.3f,%.3f,%.3f,%d\n", sr[k].name,
                        sr[k].vol[i], sr[k].size[i], (unsigned long long)c->warm.voxels_total,
                        (unsigned long long)c->warm.voxels_relevant, (unsigned long long)c->warm.voxels_splatted, px,
                        c->warm.lod_level, m.median, m.min, m.max, c->warm.ms_relevant, runs);
            if (dat) fprintf(dat, "%.0f %.3f %llu\n", x[i], m.median, (unsigned long long)c->warm.voxels_splatted);
        }
        sr[k].slope = loglog_slope(x, y, sr[k].n, &sr[k].r2);
    }
    for (int k = 0; k < ns; k++) {
        const series *s = &sr[k];
        printf("log-log slope of frame time, %-16s (%s against %s): %.3f (R^2 %.3f)\n", s->name, s->title,
               s->x == X_PIXELS ? "pixels" : "voxels", s->slope, s->r2);
        if (csv) fprintf(csv, "slope,%s,,,,,,,,%.4f,,,,\n", s->name, s->slope);
    }
    printf("(slope 1: linear; the relevant-voxel list is built once per classification (list_build_ms, in the warm-up\n"
           " render, 0 where a case shares the list of an earlier one) and is not in the frame time)\n");
    if (csv) fclose(csv);
    if (dat) {
        fclose(dat);
        char script[4096];
        snprintf(script, sizeof script,
                 "%s"
                 "set output 'growth.png'\n"
                 "set multiplot layout 1,2 title 'vsplat growth (post-cd, log-log)'\n"
                 "set logscale xy\n"
                 "set grid\n"
                 "set key top left\n"
                 "set ylabel 'frame ms'\n"
                 "set xlabel 'voxels (sphere:N, %d^2)'\n"
                 "set title 'slope %.2f full resolution, %.2f levels of detail'\n"
                 "plot 'growth.dat' index 0 using 1:2 with linespoints pt 7 title '%s', "
                 "'growth.dat' index 1 using 1:2 with linespoints pt 5 title '%s'\n"
                 "set xlabel 'pixels'\n"
                 "set title 'slopes %.2f, %.2f, %.2f'\n"
                 "plot 'growth.dat' index 2 using 1:2 with linespoints pt 7 title '%s', "
                 "'growth.dat' index 3 using 1:2 with linespoints pt 9 title '%s', "
                 "'growth.dat' index 4 using 1:2 with linespoints pt 5 title '%s'\n"
                 "unset multiplot\n",
                 bench_plot_terminal(1000, 450), sr[0].size[0], sr[0].slope, sr[1].slope, sr[0].title, sr[1].title,
                 sr[2].slope, sr[3].slope, sr[4].slope, sr[2].title, sr[3].title, sr[4].title);
        if (bench_plot(o, "growth", script)) failed++;
    }
    bench_cases_free(cases, n);
    bench_contexts_release();
    for (int j = 0; j < nload; j++) vs_volume_release(vols[j]);
    printf("growth: %.1f s, results in %s\n", (bench_now_ms() - t0) / 1000.0, o->out_dir);
    return failed ? 2 : 0;
}
