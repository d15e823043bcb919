/* vsplat-bench limits: each stage's distance to this machine's limits.
 *
 * 1. The machine (roof.c): peak add and FMA rates per ISA on one core, and
 *    the bandwidth of the kernels' access patterns (read, write, and the
 *    footprint adds' read-modify-write dst[i] += w * src[i]) for working sets
 *    that fit L1, L2, L3 and DRAM, on one thread and on all.
 * 2. The frames: Colin27 at 512^2 (iso 45, ramp 10, the face) on every
 *    splatting pipeline (--quick, or without the data: a scene), interleaved
 *    runs.  Per stage, from vs_stats: ms_stage (summed over threads, so a
 *    rate per thread), the work count and the bytes the stage reads and
 *    writes by construction; the rate achieved, the limit it is held to, and
 *    the share of that limit.
 * 3. Hardware counters around a whole frame where the kernel allows it.
 *
 * Which limit.  Every sheet stage works on one tile's sheet buffers: a
 * 64 x 64 tile plus the footprint margin (~80 x 80 pixels) of 1-4 channels,
 * in the 2-5 sheets a voxel's footprint and the gradient stencil span, is
 * 100-500 KB, and the tile's image (64 KB) sits next to them.  That is past
 * L1 (32-48 KB) and within L2 (0.5-2 MB on current x86 cores), so every
 * stage is held to the L2 bandwidth of one thread: rasterize to the
 * read-modify-write figure (its bytes are the sheet floats it reads and
 * writes back), the others to their mix of reads and writes (time at the
 * limit = read bytes / read bandwidth + written bytes / write bandwidth).
 * ms_stage is summed over the workers, so bytes / ms_stage is one thread's
 * rate, compared with the single-thread bandwidth (L2 is private per core).
 * Rasterize's floats are also one FMA each, so its items/s are set against
 * the FMA peak of the frame's ISA as well. */
#include "bench.h"
#include "roof.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { ST_RASTER, ST_GRADIENT, ST_SHADE, ST_COMPOSITE, NST };
static const char *const stage_names[NST] = {"rasterize", "gradient", "shade", "composite"};
static const char *const item_names[NST] = {"floats", "pixels", "pixels", "pixels"};

static const vs_pipeline pipes[] = {VS_PIPELINE_PRE, VS_PIPELINE_POST_CD, VS_PIPELINE_POST_GS,
                                    VS_PIPELINE_POST_ALPHA};
#define NPIPES ((int)(sizeof pipes / sizeof pipes[0]))

typedef struct stage_row {
    double ms, items, rd, wr; /* ms summed over threads (median), counts of one frame */
    double gbs, mitems, limit, pct, pct_fma;
} stage_row;

static double stage_ms(const vs_stats *st, int k)
{
    return k == ST_RASTER ? st->ms_stage.rasterize : k == ST_GRADIENT ? st->ms_stage.gradient
                                                 : k == ST_SHADE      ? st->ms_stage.shade
                                                                      : st->ms_stage.composite;
}

static void stage_counts(const vs_stats *st, int k, double *items, double *rd, double *wr)
{
    const vs_stage_bytes *r = &st->bytes_read, *w = &st->bytes_written;
    switch (k) {
    case ST_RASTER: *items = (double)st->footprint_floats, *rd = (double)r->rasterize, *wr = (double)w->rasterize; break;
    case ST_GRADIENT: *items = (double)st->pixels_classified, *rd = (double)r->gradient, *wr = (double)w->gradient; break;
    case ST_SHADE: *items = (double)st->pixels_shaded, *rd = (double)r->shade, *wr = (double)w->shade; break;
    default: *items = (double)st->pixels_classified, *rd = (double)r->composite, *wr = (double)w->composite;
    }
}

/* bw[level][pattern][0 one thread, 1 all threads] in GB/s */
typedef double bw_table[ROOF_NLEVELS][ROOF_NPATTERNS][2];

static void measure_machine(const bench_opts *o, vs_isa isa, int nthr, bw_table bw, double peak[][2], FILE *csv)
{
    bench_cache_sizes cs;
    bench_cache_sizes_get(&cs);
    printf("caches (%s): L1d %zu KiB, L2 %zu KiB, L3 %zu KiB; working sets: L1 %zu KiB, L2 %zu KiB, L3 %zu KiB, "
           "DRAM %zu MiB per thread (L3 and DRAM split among threads when all run)\n",
           cs.source, cs.cache[0] >> 10, cs.cache[1] >> 10, cs.cache[2] >> 10, cs.set[ROOF_L1] >> 10,
           cs.set[ROOF_L2] >> 10, cs.set[ROOF_L3] >> 10, cs.set[ROOF_DRAM] >> 20);

    printf("\npeak arithmetic, one core (%d chains; ISAs without FMA: a multiply and an add)\n", ROOF_CHAINS);
    printf("%-8s %12s %14s\n", "isa", "add GFLOP/s", "FMA GFLOP/s");
    for (vs_isa i = VS_ISA_SCALAR; i <= VS_ISA_AVX512; i = (vs_isa)(i + 1)) {
        if (i > vs_isa_detect()) {
            printf("%-8s skipped: this CPU has no %s\n", vs_isa_name(i), vs_isa_name(i));
            continue;
        }
        for (int f = 0; f < 2; f++) peak[i][f] = bench_peak_gflops(i, f, o->quick);
        printf("%-8s %12.1f %14.1f\n", vs_isa_name(i), peak[i][0], peak[i][1]);
        if (csv)
            for (int f = 0; f < 2; f++)
                fprintf(csv, "peak,%s,core,%s,1,0,%.2f,GFLOP/s\n", vs_isa_name(i), f ? "fma" : "add", peak[i][f]);
    }

    bench_roof_fns fns;
    bench_roof_get(isa, &fns);
    const int trials = o->quick ? 3 : 5;
    const double gb = o->quick ? 0.4 : 2.0;
    printf("\nbandwidth, GB/s (%s loops, best of %d; rmw = dst[i] += w * src[i], 8 bytes a float)\n",
           vs_isa_name(isa), trials);
    printf("%-6s %-32s   %d threads\n", "", "1 thread", nthr);
    printf("%-6s %10s %10s %10s   %10s %10s %10s\n", "level", "read", "write", "rmw", "read", "write", "rmw");
    int step = 0, nsteps = ROOF_NLEVELS * ROOF_NPATTERNS * 2;
    for (int l = 0; l < ROOF_NLEVELS; l++) {
        for (int t = 0; t < 2; t++)
            for (int p = 0; p < ROOF_NPATTERNS; p++) {
                const int threads = t ? nthr : 1;
                /* private levels: each thread its own set; shared ones split */
                size_t set = cs.set[l];
                if (t && l >= ROOF_L3) set /= (size_t)nthr;
                bench_progress("limits bandwidth", step++, nsteps, bench_roof_level_names[l]);
                bw[l][p][t] = bench_bandwidth(&fns, p, set, threads, trials, gb);
                if (csv)
                    fprintf(csv, "bandwidth,%s,%s,%s,%d,%zu,%.2f,GB/s\n", vs_isa_name(isa), bench_roof_level_names[l],
                            bench_roof_pattern_names[p], threads, set, bw[l][p][t]);
            }
        bench_progress_end();
        printf("%-6s %10.1f %10.1f %10.1f   %10.1f %10.1f %10.1f\n", bench_roof_level_names[l], bw[l][0][0],
               bw[l][1][0], bw[l][2][0], bw[l][0][1], bw[l][1][1], bw[l][2][1]);
    }
}

/* The roofline plot: % of the limit per stage, one bar per pipeline. */
static int write_plot(const bench_opts *o, stage_row rows[][NST], const int *present, const char *title)
{
    FILE *d = bench_result_open(o, "limits_plot.dat");
    if (!d) return 1;
    fprintf(d, "stage");
    for (int p = 0; p < NPIPES; p++)
        if (present[p]) fprintf(d, " %s", vs_pipeline_name(pipes[p]));
    fprintf(d, "\n");
    for (int k = 0; k < NST; k++) {
        fprintf(d, "%s", stage_names[k]);
        for (int p = 0; p < NPIPES; p++)
            if (present[p]) {
                if (rows[p][k].pct > 0) fprintf(d, " %.2f", rows[p][k].pct);
                else fprintf(d, " -");
            }
        fprintf(d, "\n");
    }
    fclose(d);
    int ncol = 0;
    for (int p = 0; p < NPIPES; p++) ncol += present[p];
    char script[4096];
    snprintf(script, sizeof script,
             "%s"
             "set output 'limits.png'\n"
             "set title \"%s\" noenhanced\n"
             "set ylabel '%% of the L2 limit of one thread'\n"
             "set datafile missing '-'\n"
             "set style data histograms\n"
             "set style histogram clustered gap 1\n"
             "set style fill solid 0.8 border -1\n"
             "set grid ytics\n"
             "set key top right noenhanced\n"
             "set yrange [0:*]\n"
             "plot for [i=2:%d] 'limits_plot.dat' using i:xtic(1) title columnheader(i)\n",
             bench_plot_terminal(800, 520), title, ncol + 1);
    return bench_plot(o, "limits", script);
}

/* Cycles, instructions and cache misses of one warm frame per pipeline. */
static void count_frames(const vs_volume *vol, const vs_settings *base, stage_row rows[][NST])
{
    printf("\nhardware counters, one warm frame (all threads):\n");
    for (int p = 0; p < NPIPES; p++) {
        bench_hwc h;
        if (bench_hwc_open(&h) != 0) {
            printf("  not available: %s; everything above stands without them\n", h.why);
            return;
        }
        vs_context *ctx = NULL; /* created after the counters, so its workers inherit them */
        if (vs_context_create(&ctx) != VS_OK) {
            bench_hwc_close(&h);
            return;
        }
        vs_settings s = *base;
        s.pipeline = pipes[p];
        vs_image img = {0, 0, NULL};
        vs_stats st;
        unsigned long long c[HWC_N] = {0};
        vs_status rc = vs_render(ctx, vol, &s, &img, &st); /* warm: relevant voxels, pool */
        vs_image_free(&img);
        if (rc == VS_OK) {
            bench_hwc_start(&h);
            rc = vs_render(ctx, vol, &s, &img, &st);
            int hr = bench_hwc_stop(&h, c);
            vs_image_free(&img);
            if (rc == VS_OK && hr == 0) {
                double bytes = 0;
                for (int k = 0; k < NST; k++) bytes += rows[p][k].rd + rows[p][k].wr;
                printf("  %-10s %8.1f ms  cycles %.3g  instructions %.3g  IPC %.2f  cache misses %.3g "
                       "(%.2f per KB the stages move)\n",
                       vs_pipeline_name(pipes[p]), st.ms_total, (double)c[HWC_CYCLES], (double)c[HWC_INSTRUCTIONS],
                       c[HWC_CYCLES] ? (double)c[HWC_INSTRUCTIONS] / (double)c[HWC_CYCLES] : 0.0,
                       (double)c[HWC_CACHE_MISSES], bytes > 0 ? (double)c[HWC_CACHE_MISSES] * 1024.0 / bytes : 0.0);
            } else if (hr != 0) {
                printf("  %-10s counters could not be read\n", vs_pipeline_name(pipes[p]));
            }
        }
        vs_context_release(ctx);
        bench_hwc_close(&h);
    }
}

int bench_limits(const bench_opts *o)
{
    printf("vsplat-bench limits: %s, load %s\n", bench_machine(), bench_loadavg());
    if (bench_results_dir(o)) return 1;

    /* the frames first: their ISA picks the loops the bandwidths are measured with */
    vs_volume *vol = NULL;
    const char *key = o->quick ? "scene:head:128" : "colin27";
    int lr = o->quick ? 1 : bench_load(o, key, &vol);
    if (lr != 0) {
        if (!o->quick) printf("limits: the Colin27 head is absent; a synthetic head (scene head:256) instead\n");
        key = o->quick ? "scene:head:128" : "scene:head:256";
        if (bench_load(o, key, &vol) != 0) return 1;
    }
    const int size = o->quick ? 256 : 512;
    vs_settings base;
    vs_settings_init(&base);
    base.lod_pixels = 0; /* the stages' own rates, at full resolution */
    base.width = base.height = size;
    base.azimuth = 180; /* the face */
    base.threads = o->threads;
    if (!strcmp(key, "colin27")) {
        base.has_iso = 1;
        base.iso_lo = 45;
        base.ramp = 10;
    }
    bench_case cases[NPIPES];
    for (int p = 0; p < NPIPES; p++) {
        vs_settings s = base;
        s.pipeline = pipes[p];
        char name[96];
        snprintf(name, sizeof name, "%s %s", key, vs_pipeline_name(pipes[p]));
        bench_case_set(&cases[p], name, vol, &s);
    }
    const int runs = bench_runs(o, 5, 1);
    int failed = bench_run("limits", cases, NPIPES, runs);
    bench_contexts_release(); /* idle workers out of the way of the bandwidth threads */

    vs_isa isa = vs_isa_detect();
    int threads = 1;
    for (int p = 0; p < NPIPES; p++)
        if (!cases[p].failed) {
            vs_isa fi;
            if (cases[p].warm.isa && vs_isa_parse(cases[p].warm.isa, &fi) == VS_OK && fi >= VS_ISA_SCALAR) isa = fi;
            threads = cases[p].warm.threads;
            break;
        }

    FILE *mcsv = bench_result_open(o, "limits_machine.csv");
    if (mcsv) fprintf(mcsv, "what,isa,level,pattern,threads,working_set_bytes,value,unit\n");
    bw_table bw;
    double peak[VS_ISA_AVX512 + 1][2] = {{0}};
    memset(bw, 0, sizeof bw);
    printf("\n");
    measure_machine(o, isa, bench_cpus(), bw, peak, mcsv);
    if (mcsv) fclose(mcsv);

    /* the stage table */
    stage_row rows[NPIPES][NST];
    memset(rows, 0, sizeof rows);
    int present[NPIPES] = {0};
    const double fma_items = peak[isa][1] / 2.0 * 1e3; /* FMAs per second of one core, in M */
    printf("\nstages: %s %dx%d, %d threads, ISA %s, median of %d runs; rates per thread (ms_stage is summed\n"
           "over threads), against one thread's L2 limit: rmw for rasterize, its read/write mix for the others\n",
           key, size, size, threads, vs_isa_name(isa), runs);
    printf("%-10s %-10s %9s %9s %-6s %10s %9s %10s %8s %7s\n", "pipeline", "stage", "ms", "items", "", "Mitems/s",
           "GB/s", "limit GB/s", "% limit", "% FMA");
    FILE *csv = bench_result_open(o, "limits.csv");
    if (csv)
        fprintf(csv, "input,pipeline,stage,threads,isa,ms_summed,items,item,bytes_read,bytes_written,gbs_per_thread,"
                     "mitems_per_thread,limit,limit_gbs,pct_limit,pct_fma\n");
    double *v = malloc((size_t)(runs > 0 ? runs : 1) * sizeof *v);
    for (int p = 0; p < NPIPES && v; p++) {
        const bench_case *c = &cases[p];
        if (c->failed) continue;
        present[p] = 1;
        for (int k = 0; k < NST; k++) {
            stage_row *r = &rows[p][k];
            for (int i = 0; i < c->nruns; i++) v[i] = stage_ms(&c->runs[i], k);
            r->ms = bench_median(v, c->nruns);
            stage_counts(&c->runs[0], k, &r->items, &r->rd, &r->wr);
            if (r->ms <= 0 || r->rd + r->wr <= 0) continue; /* a stage this pipeline does not have */
            const double s = r->ms / 1e3;
            r->gbs = (r->rd + r->wr) / s / 1e9;
            r->mitems = r->items / s / 1e6;
            if (k == ST_RASTER) {
                r->limit = bw[ROOF_L2][ROOF_RMW][0];
                if (fma_items > 0) r->pct_fma = 100.0 * r->mitems / fma_items;
            } else {
                const double t = r->rd / bw[ROOF_L2][ROOF_READ][0] + r->wr / bw[ROOF_L2][ROOF_WRITE][0];
                r->limit = t > 0 ? (r->rd + r->wr) / t : 0;
            }
            r->pct = r->limit > 0 ? 100.0 * r->gbs / r->limit : 0;
            const char *lim = k == ST_RASTER ? "L2 rmw" : "L2 read/write";
            char pf[16] = "-";
            if (k == ST_RASTER && r->pct_fma > 0) snprintf(pf, sizeof pf, "%.1f", r->pct_fma);
            printf("%-10s %-10s %9.2f %8.2fM %-6s %10.1f %9.2f %10.1f %8.1f %7s\n", vs_pipeline_name(pipes[p]),
                   stage_names[k], r->ms, r->items / 1e6, item_names[k], r->mitems, r->gbs, r->limit, r->pct, pf);
            if (csv)
                fprintf(csv, "%s,%s,%s,%d,%s,%.3f,%.0f,%s,%.0f,%.0f,%.3f,%.3f,%s,%.2f,%.2f,%.2f\n", key,
                        vs_pipeline_name(pipes[p]), stage_names[k], c->warm.threads, vs_isa_name(isa), r->ms, r->items,
                        item_names[k], r->rd, r->wr, r->gbs, r->mitems, lim, r->limit, r->pct, r->pct_fma);
        }
    }
    free(v);
    if (csv) fclose(csv);
    printf("(ms: summed over threads; items: footprint floats added, sheet pixels classified, shaded, composited;\n"
           " GB/s: bytes read + written by construction per second of one thread; %% FMA: rasterize's floats,\n"
           " one FMA each, against the %s FMA peak of one core; the ray caster has no stages and is left out)\n",
           vs_isa_name(isa));

    char title[300];
    snprintf(title, sizeof title, "vsplat stages against the limits: %s %dx%d, %d threads (%s)", key, size, size,
             threads, bench_machine());
    int plot_failed = 0;
    if (present[0] + present[1] + present[2] + present[3]) plot_failed = write_plot(o, rows, present, title);

    count_frames(vol, &base, rows);

    bench_cases_free(cases, NPIPES);
    bench_contexts_release();
    vs_volume_release(vol);
    return failed ? 2 : plot_failed ? 1 : 0;
}
