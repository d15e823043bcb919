/* vsplat-bench growth: how frame time grows with the volume (sphere:N,
 * N = 32..1024, fixed image; at full resolution against the relevant-voxel
 * count, and with levels of detail against the volume's voxel count) and
 * with the image size (sphere:128, 128^2..2048^2), with least-squares
 * slopes on log-log axes. */
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

/* A case of the series: post-cd, view 20,15; lod 0 full resolution (the
 * voxel series), 1 the default (the image series), 2 levels of detail
 * named as such. */
static void add_case(bench_case *c, const bench_opts *o, const vs_volume *v, int n, int size, int lod)
{
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = size;
    s.azimuth = 20;
    s.elevation = 15;
    s.threads = o->threads;
    if (lod == 0) s.lod_pixels = 0;
    char name[64];
    snprintf(name, sizeof name, "sphere:%d at %d^2%s", n, size, lod == 2 ? ", lod" : "");
    bench_case_set(c, name, v, &s);
}

int bench_growth(const bench_opts *o)
{
    double t0 = bench_now_ms();
    const int runs = bench_runs(o, 3, 1);
    static const int vol_full[] = {32, 64, 128, 256, 512, 1024}, vol_quick[] = {32, 64, 128, 256};
    static const int img_full[] = {128, 256, 512, 1024, 2048}, img_quick[] = {128, 256, 512, 1024};
    const int *vn = o->quick ? vol_quick : vol_full, *in = o->quick ? img_quick : img_full;
    const int nv = o->quick ? 4 : 6, ni = o->quick ? 4 : 5;
    const int vol_image = o->quick ? 128 : 256;
    const int img_volume = 128;
    int failed = 0;

    vs_volume *vols[6] = {0}, *ivol = NULL;
    for (int i = 0; i < nv; i++) {
        char key[64];
        snprintf(key, sizeof key, "scene:sphere:%d", vn[i]);
        if (bench_load(o, key, &vols[i]) != 0) failed++;
    }
    int ishared = -1; /* the image series reuses sphere:128 of the voxel series */
    for (int i = 0; i < nv; i++)
        if (vn[i] == img_volume) ishared = i;
    if (ishared >= 0) {
        ivol = vols[ishared];
    } else {
        char ikey[64];
        snprintf(ikey, sizeof ikey, "scene:sphere:%d", img_volume);
        if (bench_load(o, ikey, &ivol) != 0) failed++;
    }
    if (failed) {
        for (int i = 0; i < nv; i++)
            if (vols[i]) vs_volume_release(vols[i]);
        if (ivol && ishared < 0) vs_volume_release(ivol);
        return 2;
    }

    bench_case cases[17];
    int n = 0;
    for (int i = 0; i < nv; i++) add_case(&cases[n++], o, vols[i], vn[i], vol_image, 0);
    for (int i = 0; i < ni; i++) add_case(&cases[n++], o, ivol, img_volume, in[i], 1);
    for (int i = 0; i < nv; i++) add_case(&cases[n++], o, vols[i], vn[i], vol_image, 2);
    failed += bench_run("growth", cases, n, runs);

    double xv[6], yv[6], xi[5], yi[5], xl[6], yl[6];
    printf("\nGrowth: post-cd, view 20,15, threads %d (0 = one per core), median ms over %d interleaved run%s; "
           "machine: %s; load average %s\n",
           o->threads, runs, runs == 1 ? "" : "s", bench_machine(), bench_loadavg());
    if (bench_results_dir(o)) failed++;
    FILE *csv = bench_result_open(o, "growth.csv");
    FILE *dat = bench_result_open(o, "growth.dat");
    if (csv) fprintf(csv, "series,scene,size,voxels_total,voxels_relevant,voxels_splatted,pixels,median_ms,min_ms,"
                          "max_ms,ms_relevant_build,runs\n");
    printf("%-28s %12s %12s %12s %10s %21s %12s\n", "case", "voxels", "relevant", "splatted", "median_ms", "min-max",
           "list_build_ms");
    for (int i = 0; i < n; i++) {
        const bench_case *c = &cases[i];
        bench_summary m = bench_summarize(c, bench_m_total);
        int series_vox = i < nv, series_lod = i >= nv + ni;
        double px = (double)c->s.width * c->s.height;
        if (series_vox) {
            xv[i] = (double)c->warm.voxels_relevant;
            yv[i] = m.median;
        } else if (series_lod) {
            xl[i - nv - ni] = (double)c->warm.voxels_total;
            yl[i - nv - ni] = m.median;
        } else {
            xi[i - nv] = px;
            yi[i - nv] = m.median;
        }
        printf("%-28s %12llu %12llu %12llu %10.1f %10.1f-%-10.1f %12.1f\n", c->name,
               (unsigned long long)c->warm.voxels_total, (unsigned long long)c->warm.voxels_relevant,
               (unsigned long long)c->warm.voxels_splatted, m.median, m.min, m.max, c->warm.ms_relevant);
        if (csv)
            fprintf(csv, "%s,%s,%d,%llu,%llu,%llu,%.0f,%.3f,%.3f,%.3f,%.3f,%d\n",
                    series_vox ? "voxels" : series_lod ? "voxels_lod" : "image", "sphere",
                    series_vox ? vn[i] : series_lod ? vn[i - nv - ni] : img_volume,
                    (unsigned long long)c->warm.voxels_total, (unsigned long long)c->warm.voxels_relevant,
                    (unsigned long long)c->warm.voxels_splatted, px, m.median, m.min, m.max, c->warm.ms_relevant,
                    runs);
        if (dat) {
            if (i == nv || i == nv + ni) fprintf(dat, "\n\n");
            if (i == 0) fprintf(dat, "# voxels series, full resolution: relevant median_ms splatted\n");
            if (i == nv) fprintf(dat, "# image series: pixels median_ms\n");
            if (i == nv + ni) fprintf(dat, "# voxels series, levels of detail: voxels median_ms splatted\n");
            fprintf(dat, "%.0f %.3f %llu\n", series_vox ? xv[i] : series_lod ? xl[i - nv - ni] : px, m.median,
                    (unsigned long long)c->warm.voxels_splatted);
        }
    }
    double r2v, r2i;
    double r2l;
    double sv = loglog_slope(xv, yv, nv, &r2v), si = loglog_slope(xi, yi, ni, &r2i),
           sl = loglog_slope(xl, yl, nv, &r2l);
    printf("log-log slope, frame time vs relevant voxels (sphere:%d..%d at %d^2): %.3f (R^2 %.3f)\n", vn[0],
           vn[nv - 1], vol_image, sv, r2v);
    printf("log-log slope, frame time vs voxels with levels of detail (same spheres):          %.3f (R^2 %.3f)\n",
           sl, r2l);
    printf("log-log slope, frame time vs pixels (sphere:%d, %d^2..%d^2):        %.3f (R^2 %.3f)\n", img_volume,
           in[0], in[ni - 1], si, r2i);
    printf("(slope 1: linear; the relevant-voxel list is built once per classification (list_build_ms, in the warm-up\n"
           " render, 0 where a case shares the list of an earlier one) and is not in the frame time)\n");
    if (csv) {
        fprintf(csv, "slope,voxels,,,,,,%.4f,,,,\n", sv);
        fprintf(csv, "slope,image,,,,,,%.4f,,,,\n", si);
        fprintf(csv, "slope,voxels_lod,,,,,,%.4f,,,,\n", sl);
        fclose(csv);
    }
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
                 "set xlabel 'relevant voxels, or voxels with levels of detail (sphere:N, %d^2)'\n"
                 "set title 'slope %.2f full resolution, %.2f levels of detail'\n"
                 "plot 'growth.dat' index 0 using 1:2 with linespoints pt 7 title 'full resolution (relevant)', "
                 "'growth.dat' index 2 using 1:2 with linespoints pt 5 title 'levels of detail (all voxels)'\n"
                 "set xlabel 'pixels (sphere:%d)'\n"
                 "set title 'slope %.2f'\n"
                 "plot 'growth.dat' index 1 using 1:2 with linespoints pt 7 title 'frame time'\n"
                 "unset multiplot\n",
                 bench_plot_terminal(1000, 450), vol_image, sv, sl, img_volume, si);
        if (bench_plot(o, "growth", script)) failed++;
    }
    bench_cases_free(cases, n);
    bench_contexts_release();
    for (int i = 0; i < nv; i++) vs_volume_release(vols[i]);
    if (ishared < 0) vs_volume_release(ivol);
    printf("growth: %.1f s, results in %s\n", (bench_now_ms() - t0) / 1000.0, o->out_dir);
    return failed ? 2 : 0;
}
