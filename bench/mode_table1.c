/* vsplat-bench table1: the paper's Table 1 (R10000 seconds) reproduced in
 * milliseconds.  Rows: footprint rasterization = ms_stage.rasterize, shading =
 * gradient + shade, compositing = composite, total = ms_total (wall clock),
 * all on one thread, plus the N-thread total; then speedups over the paper. */
#include "bench.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct t1_col {
    const char *image;  /* column group, as the paper's figure                 */
    const char *method; /* pre / post-cd / post-gs                              */
    const char *input;  /* bench_load key                                       */
    vs_pipeline pipeline;
    double iso_lo, iso_hi, ramp;
    double az, el, zoom;
    int has_center;
    double center[3];
    double paper[4]; /* seconds: rasterization, shading, compositing, total; NAN: none */
} t1_col;

#define NOP {NAN, NAN, NAN, NAN}
/* Colin27 skin: iso 45, ramp 10, view 180,0 looks at the face.  The eye: its
 * voxel coordinates were found by rendering and looking (the subject's right
 * eye at x 125, z 28; y only moves it in depth).  brainsmall: view 0,-90 is
 * the classic lateral view (face left, brain exposed where VolPack's authors
 * removed the skull); iso 45 (the grey-matter shoulder of the histogram,
 * between the background and the 72 white-matter peak) shows the gyri.  The
 * zoom centres on the exposed cortex. */
static const t1_col cols[] = {
    {"full head", "pre", "colin27", VS_PIPELINE_PRE, 45, INFINITY, 10, 180, 0, 0.8, 0, {0, 0, 0}, {15.6, 1.8, 3.5, 21.0}},
    {"full head", "post-cd", "colin27", VS_PIPELINE_POST_CD, 45, INFINITY, 10, 180, 0, 0.8, 0, {0, 0, 0}, {11.4, 14.0, 3.5, 29.9}},
    {"eye", "pre", "colin27", VS_PIPELINE_PRE, 45, INFINITY, 10, 180, 0, 4.0, 1, {125, 150, 28}, {17.4, 0.7, 2.4, 20.5}},
    {"eye", "post-cd", "colin27", VS_PIPELINE_POST_CD, 45, INFINITY, 10, 180, 0, 4.0, 1, {125, 150, 28}, {14.5, 17.1, 2.7, 35.2}},
    {"brain", "pre", "brain", VS_PIPELINE_PRE, 45, INFINITY, 8, 0, -90, 0.8, 0, {0, 0, 0}, {14.5, 1.8, 3.9, 20.3}},
    {"brain", "post-cd", "brain", VS_PIPELINE_POST_CD, 45, INFINITY, 8, 0, -90, 0.8, 0, {0, 0, 0}, {13.0, 13.6, 4.3, 31.7}},
    {"brain zoomed", "pre", "brain", VS_PIPELINE_PRE, 45, INFINITY, 8, 0, -90, 2.4, 1, {85, 50, 41}, {16.7, 0.3, 1.4, 18.5}},
    {"brain zoomed", "post-cd", "brain", VS_PIPELINE_POST_CD, 45, INFINITY, 8, 0, -90, 2.4, 1, {85, 50, 41}, {16.2, 17.8, 1.4, 36.2}},
    {"brain zoomed", "post-gs", "brain", VS_PIPELINE_POST_GS, 45, INFINITY, 8, 0, -90, 2.4, 1, {85, 50, 41}, {16.8, 17.0, 1.4, 36.0}},
    {"cell (scene)", "pre", "scene:cell", VS_PIPELINE_PRE, 100, INFINITY, 10, 0, 90, 0.8, 0, {0, 0, 0}, {9.4, 3.5, 2.7, 15.7}},
    {"cell (scene)", "post-cd", "scene:cell", VS_PIPELINE_POST_CD, 100, INFINITY, 10, 0, 90, 0.8, 0, {0, 0, 0}, {6.5, 15.6, 3.0, 25.6}},
    /* extra columns (not in the paper): real data */
    {"EM stack", "pre", "em", VS_PIPELINE_PRE, 124, INFINITY, 10, 30, 30, 0.8, 0, {0, 0, 0}, NOP},
    {"EM stack", "post-cd", "em", VS_PIPELINE_POST_CD, 124, INFINITY, 10, 30, 30, 0.8, 0, {0, 0, 0}, NOP},
    {"CT head", "pre", "ct", VS_PIPELINE_PRE, 300, INFINITY, 60, 180, 10, 0.8, 0, {0, 0, 0}, NOP},
    {"CT head", "post-cd", "ct", VS_PIPELINE_POST_CD, 300, INFINITY, 60, 180, 10, 0.8, 0, {0, 0, 0}, NOP},
};
#define NCOLS ((int)(sizeof cols / sizeof cols[0]))

enum { R_RASTER, R_SHADING, R_COMPOSITE, R_TOTAL, R_SETUP, R_TOTAL_N, NROWS };
static const char *row_names[NROWS] = {"footprint rasterization", "shading (gradient+shade)", "compositing",
                                       "total (1 thread)", "setup (not in paper)", "total (N threads)"};
static const char *row_keys[NROWS] = {"rasterize", "shading", "composite", "total", "setup", "total_nthreads"};

static const char *input_keys[] = {"colin27", "brain", "scene:cell", "em", "ct"};
#define NINPUTS ((int)(sizeof input_keys / sizeof input_keys[0]))

static int input_index(const char *key)
{
    for (int i = 0; i < NINPUTS; i++)
        if (!strcmp(input_keys[i], key)) return i;
    return -1;
}

/* Short two-line labels for the printed table. */
static void short_image(const char *image, char *buf, size_t cap)
{
    if (!strcmp(image, "full head")) snprintf(buf, cap, "head");
    else if (!strcmp(image, "brain zoomed")) snprintf(buf, cap, "brain-zoom");
    else if (!strcmp(image, "cell (scene)")) snprintf(buf, cap, "cell");
    else if (!strcmp(image, "EM stack")) snprintf(buf, cap, "EM");
    else if (!strcmp(image, "CT head")) snprintf(buf, cap, "CT");
    else snprintf(buf, cap, "%s", image);
}

static void print_header(const int *present, const char *title)
{
    printf("%s\n", title);
    printf("%-26s", "image");
    for (int c = 0; c < NCOLS; c++) {
        if (!present[c]) continue;
        char b[32];
        short_image(cols[c].image, b, sizeof b);
        printf(" %10s", b);
    }
    printf("\n%-26s", "method");
    for (int c = 0; c < NCOLS; c++)
        if (present[c]) printf(" %10s", cols[c].method);
    printf("\n");
}

int bench_table1(const bench_opts *o)
{
    double t0 = bench_now_ms();
    const int size = o->quick ? 128 : 512;
    const int runs = bench_runs(o, 3, 1);
    int nthreads = o->threads;
    vs_volume *vols[NINPUTS] = {0};
    int status[NINPUTS];
    for (int i = 0; i < NINPUTS; i++) status[i] = bench_load(o, input_keys[i], &vols[i]);

    bench_case cases[2 * NCOLS];
    int case_col[2 * NCOLS], case_mt[2 * NCOLS], nc = 0;
    int present[NCOLS] = {0};
    for (int mt = 0; mt < 2; mt++)
        for (int c = 0; c < NCOLS; c++) {
            int vi = input_index(cols[c].input);
            if (vi < 0 || status[vi] != 0) continue;
            /* the EM stack is noise almost everywhere (every voxel is relevant): too slow for --quick */
            if (o->quick && !strcmp(cols[c].input, "em")) continue;
            present[c] = 1;
            vs_settings s;
            vs_settings_init(&s);
            s.lod_pixels = 0; /* the paper's stages at full resolution */
            s.pipeline = cols[c].pipeline;
            s.width = s.height = size;
            s.has_iso = 1;
            s.iso_lo = cols[c].iso_lo;
            s.iso_hi = cols[c].iso_hi;
            s.ramp = cols[c].ramp;
            s.azimuth = cols[c].az;
            s.elevation = cols[c].el;
            s.zoom = cols[c].zoom;
            s.has_center = cols[c].has_center;
            memcpy(s.center, cols[c].center, sizeof s.center);
            s.threads = mt ? nthreads : 1;
            char name[96];
            snprintf(name, sizeof name, "%s %s %s", cols[c].image, cols[c].method, mt ? "N threads" : "1 thread");
            bench_case_set(&cases[nc], name, vols[vi], &s);
            case_col[nc] = c;
            case_mt[nc] = mt;
            nc++;
        }
    if (nc == 0) {
        fprintf(stderr, "table1: no inputs found in %s; nothing to do\n", o->data_dir);
        return 0;
    }
    int failed = bench_run("table1", cases, nc, runs);

    /* gather medians: med[row][col] */
    double med[NROWS][NCOLS], mn[NROWS][NCOLS], mx[NROWS][NCOLS];
    int threads_used = 0;
    unsigned long long relevant[NCOLS] = {0}, splatted[NCOLS] = {0};
    for (int r = 0; r < NROWS; r++)
        for (int c = 0; c < NCOLS; c++) med[r][c] = mn[r][c] = mx[r][c] = NAN;
    static const bench_metric metrics[5] = {bench_m_raster, bench_m_shading, bench_m_composite, bench_m_total,
                                            bench_m_setup};
    for (int i = 0; i < nc; i++) {
        int c = case_col[i];
        if (cases[i].failed) continue;
        if (case_mt[i]) {
            bench_summary s = bench_summarize(&cases[i], bench_m_total);
            med[R_TOTAL_N][c] = s.median;
            mn[R_TOTAL_N][c] = s.min;
            mx[R_TOTAL_N][c] = s.max;
            threads_used = cases[i].warm.threads;
        } else {
            for (int r = 0; r < 5; r++) {
                bench_summary s = bench_summarize(&cases[i], metrics[r]);
                med[r][c] = s.median;
                mn[r][c] = s.min;
                mx[r][c] = s.max;
            }
            relevant[c] = (unsigned long long)cases[i].warm.voxels_relevant;
            splatted[c] = (unsigned long long)cases[i].warm.voxels_splatted;
        }
    }

    /* the table, in the paper's layout */
    char title[512];
    printf("\nTable 1 reproduced: median ms over %d interleaved run%s (paper: seconds on a 194 MHz R10000)\n",
           runs, runs == 1 ? "" : "s");
    printf("%dx%d image, stage times on 1 thread, ISA %s; machine: %s; load average %s\n", size, size,
           vs_isa_name(vs_isa_detect()), bench_machine(), bench_loadavg());
    snprintf(title, sizeof title, "-- milliseconds --");
    print_header(present, title);
    for (int r = 0; r < NROWS; r++) {
        char rn[64];
        if (r == R_TOTAL_N) snprintf(rn, sizeof rn, "total (%d threads)", threads_used);
        else snprintf(rn, sizeof rn, "%s", row_names[r]);
        printf("%-26s", rn);
        for (int c = 0; c < NCOLS; c++)
            if (present[c]) {
                if (isnan(med[r][c])) printf(" %10s", "-");
                else printf(" %10.1f", med[r][c]);
            }
        printf("\n");
    }
    printf("%-26s", "relevant voxels (k)");
    for (int c = 0; c < NCOLS; c++)
        if (present[c]) printf(" %10.0f", relevant[c] / 1000.0);
    printf("\n\n");

    print_header(present, "-- speedup over the paper (paper seconds / our time) --");
    static const int sp_rows[5] = {R_RASTER, R_SHADING, R_COMPOSITE, R_TOTAL, R_TOTAL_N};
    for (int k = 0; k < 5; k++) {
        int r = sp_rows[k];
        char rn[64];
        if (r == R_TOTAL_N) snprintf(rn, sizeof rn, "total (%d threads)", threads_used);
        else snprintf(rn, sizeof rn, "%s", row_names[r]);
        printf("%-26s", rn);
        for (int c = 0; c < NCOLS; c++) {
            if (!present[c]) continue;
            double paper = cols[c].paper[r == R_TOTAL_N ? 3 : r];
            double v = med[r][c];
            if (isnan(paper) || isnan(v) || v <= 0) printf(" %10s", "-");
            else printf(" %9.0fx", paper * 1000.0 / v);
        }
        printf("\n");
    }
    double spread = 0;
    for (int c = 0; c < NCOLS; c++)
        if (present[c] && med[R_TOTAL][c] > 0 && (mx[R_TOTAL][c] - mn[R_TOTAL][c]) / med[R_TOTAL][c] > spread)
            spread = (mx[R_TOTAL][c] - mn[R_TOTAL][c]) / med[R_TOTAL][c];
    printf("(largest 1-thread total spread, (max-min)/median: %.0f%%; min-max of every entry in table1.csv)\n",
           100.0 * spread);

    /* CSV */
    if (bench_results_dir(o)) failed++;
    FILE *f = bench_result_open(o, "table1.csv");
    if (f) {
        fprintf(f, "image,method,input,pipeline,size,threads,row,median_ms,min_ms,max_ms,paper_s,speedup,"
                   "voxels_relevant,voxels_splatted,runs\n");
        for (int c = 0; c < NCOLS; c++) {
            if (!present[c]) continue;
            for (int r = 0; r < NROWS; r++) {
                double paper = r == R_SETUP ? NAN : cols[c].paper[r == R_TOTAL_N ? 3 : r];
                double sp = isnan(paper) || !(med[r][c] > 0) ? NAN : paper * 1000.0 / med[r][c];
                fprintf(f, "%s,%s,%s,%s,%d,%d,%s,%.3f,%.3f,%.3f,%.1f,%.1f,%llu,%llu,%d\n", cols[c].image,
                        cols[c].method, cols[c].input, vs_pipeline_name(cols[c].pipeline), size,
                        r == R_TOTAL_N ? threads_used : 1, row_keys[r], med[r][c], mn[r][c], mx[r][c], paper, sp,
                        relevant[c], splatted[c], runs);
            }
        }
        fclose(f);
    }
    /* stage bars */
    f = bench_result_open(o, "table1_stages.dat");
    if (f) {
        fprintf(f, "# label setup rasterize shading composite total_1thread total_Nthreads (median ms)\n");
        for (int c = 0; c < NCOLS; c++) {
            if (!present[c]) continue;
            char b[32];
            short_image(cols[c].image, b, sizeof b);
            fprintf(f, "\"%s %s\" %.3f %.3f %.3f %.3f %.3f %.3f\n", b, cols[c].method, med[R_SETUP][c],
                    med[R_RASTER][c], med[R_SHADING][c], med[R_COMPOSITE][c], med[R_TOTAL][c], med[R_TOTAL_N][c]);
        }
        fclose(f);
        char script[4096];
        snprintf(script, sizeof script,
                 "%s"
                 "set output 'table1_stages.png'\n"
                 "set title \"vsplat Table 1: stage times, %dx%d, 1 thread (median ms)\"\n"
                 "set style data histograms\n"
                 "set style histogram rowstacked\n"
                 "set style fill solid 0.85 border -1\n"
                 "set boxwidth 0.75\n"
                 "set ylabel 'ms'\n"
                 "set xtics rotate by -40 scale 0 font ',9'\n"
                 "set key top left\n"
                 "set grid ytics\n"
                 "plot 'table1_stages.dat' using 2:xtic(1) title 'setup', '' using 3 title 'footprint rasterization',"
                 " '' using 4 title 'shading', '' using 5 title 'compositing',"
                 " '' using 0:7 with points pt 7 ps 1.2 lc rgb 'black' title 'total, %d threads'\n",
                 bench_plot_terminal(1000, 520), size, size, threads_used);
        if (bench_plot(o, "table1_stages", script)) failed++;
    }
    bench_cases_free(cases, nc);
    bench_contexts_release();
    for (int i = 0; i < NINPUTS; i++)
        if (vols[i]) vs_volume_release(vols[i]);
    printf("table1: %.1f s, results in %s\n", (bench_now_ms() - t0) / 1000.0, o->out_dir);
    return failed ? 2 : 0;
}
