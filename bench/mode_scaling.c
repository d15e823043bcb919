/* vsplat-bench scaling: frame time for 1..N threads (N = logical CPUs) and
 * 2N, pinned to cores and not, on the Colin27 head (skin, view 180,0),
 * post-cd and pre; interleaved runs, medians, speedup over one thread. */
#include "bench.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int bench_scaling(const bench_opts *o)
{
    double t0 = bench_now_ms();
    const int size = o->quick ? 256 : 512;
    const int runs = bench_runs(o, 5, 2);
    const char *input = "colin27";
    vs_volume *vol = NULL;
    int ls = bench_load(o, input, &vol);
    if (ls < 0) return 2;
    if (ls > 0) { /* no data: the synthetic head keeps the mode useful */
        input = "scene:head";
        fprintf(stderr, "scaling: using the synthetic scene head instead\n");
        if (bench_load(o, input, &vol) != 0) return 2;
    }
    int ncpu = bench_cpus();
    int threads[70], nt = 0;
    for (int t = 1; t <= ncpu && nt < 64; t++) threads[nt++] = t;
    if (2 * ncpu > threads[nt - 1]) threads[nt++] = 2 * ncpu;

    static const vs_pipeline pipes[2] = {VS_PIPELINE_POST_CD, VS_PIPELINE_PRE};
    int n = 2 * 2 * nt, k = 0;
    bench_case *cases = calloc((size_t)n, sizeof *cases);
    if (!cases) return 2;
    for (int p = 0; p < 2; p++)
        for (int pin = 1; pin >= 0; pin--)
            for (int t = 0; t < nt; t++) {
                vs_settings s;
                vs_settings_init(&s);
                s.lod_pixels = 0; /* the same work at every thread count and size */
                s.pipeline = pipes[p];
                s.width = s.height = size;
                if (!strcmp(input, "colin27")) {
                    s.has_iso = 1;
                    s.iso_lo = 45;
                    s.iso_hi = INFINITY;
                    s.ramp = 10;
                    s.azimuth = 180;
                }
                s.threads = threads[t];
                s.pin = pin;
                char name[96];
                snprintf(name, sizeof name, "%s %s %d thread%s", vs_pipeline_name(s.pipeline),
                         pin ? "pinned" : "unpinned", threads[t], threads[t] == 1 ? "" : "s");
                bench_case_set(&cases[k++], name, vol, &s);
            }
    int failed = bench_run("scaling", cases, n, runs);

    printf("\nScaling: %s, %dx%d, median ms over %d interleaved runs; %d logical CPUs; machine: %s; load average %s\n", input, size,
           size, runs, ncpu, bench_machine(), bench_loadavg());
    printf("%-10s %-9s %7s %10s %21s %8s %s\n", "pipeline", "pinning", "threads", "median_ms", "min-max", "speedup",
           "note");
    if (bench_results_dir(o)) failed++;
    FILE *csv = bench_result_open(o, "scaling.csv");
    if (csv) fprintf(csv, "input,size,pipeline,pin,threads,median_ms,min_ms,max_ms,speedup,pin_warning,runs\n");
    FILE *dat = bench_result_open(o, "scaling.dat");
    for (int p = 0; p < 2; p++)
        for (int pin = 1; pin >= 0; pin--) {
            double base = NAN;
            if (dat) fprintf(dat, "# %s %s: threads median_ms speedup\n", vs_pipeline_name(pipes[p]),
                             pin ? "pinned" : "unpinned");
            for (int i = 0; i < n; i++) {
                bench_case *c = &cases[i];
                if (c->s.pipeline != pipes[p] || c->s.pin != pin) continue;
                bench_summary m = bench_summarize(c, bench_m_total);
                if (c->s.threads == 1) base = m.median;
                double sp = base / m.median;
                int warn = c->failed ? 0 : c->warm.pin_warning;
                printf("%-10s %-9s %7d %10.1f %10.1f-%-10.1f %7.2fx %s\n", vs_pipeline_name(pipes[p]),
                       pin ? "pinned" : "unpinned", c->s.threads, m.median, m.min, m.max, sp,
                       warn ? "(binding failed)" : c->s.threads > ncpu ? "(oversubscribed)" : "");
                if (csv)
                    fprintf(csv, "%s,%d,%s,%d,%d,%.3f,%.3f,%.3f,%.4f,%d,%d\n", input, size,
                            vs_pipeline_name(pipes[p]), pin, c->s.threads, m.median, m.min, m.max, sp, warn, runs);
                if (dat) fprintf(dat, "%d %.3f %.4f\n", c->s.threads, m.median, sp);
            }
            if (dat) fprintf(dat, "\n\n");
        }
    if (csv) fclose(csv);
    if (dat) {
        fclose(dat);
        char script[4096];
        snprintf(script, sizeof script,
                 "%s"
                 "set output 'scaling.png'\n"
                 "set title \"vsplat scaling: %s %dx%d, speedup over 1 thread (%d logical CPUs)\"\n"
                 "set xlabel 'threads'\n"
                 "set ylabel 'speedup'\n"
                 "set xtics 1\n"
                 "set grid\n"
                 "set key top left\n"
                 "set xrange [0.5:%d.5]\n"
                 "set yrange [0:*]\n"
                 "plot x <= %d ? x : %d with lines dt 2 lc rgb 'gray' title 'ideal',"
                 " 'scaling.dat' index 0 using 1:3 with linespoints pt 7 title 'post-cd pinned',"
                 " '' index 1 using 1:3 with linespoints pt 6 title 'post-cd unpinned',"
                 " '' index 2 using 1:3 with linespoints pt 5 title 'pre pinned',"
                 " '' index 3 using 1:3 with linespoints pt 4 title 'pre unpinned'\n",
                 bench_plot_terminal(800, 520), input, size, size, ncpu, threads[nt - 1], ncpu, ncpu);
        if (bench_plot(o, "scaling", script)) failed++;
    }
    bench_cases_free(cases, n);
    free(cases);
    bench_contexts_release();
    vs_volume_release(vol);
    printf("scaling: %.1f s, results in %s\n", (bench_now_ms() - t0) / 1000.0, o->out_dir);
    return failed ? 2 : 0;
}
