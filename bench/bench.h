/* vsplat-bench: shared declarations.
 *
 * One concern per file: timing.c (the harness: shared contexts, warm-up,
 * interleaved runs, medians, progress), data.c (where the volumes are and how
 * each bench input is loaded), results.c (results folder, CSV, printing
 * helpers), plot.c (gnuplot), roof.c, roof-ISA.c and counters.c (the machine's
 * limits, roof.h), and one file per mode (mode_*.c). */
#ifndef VSPLAT_BENCH_H
#define VSPLAT_BENCH_H

#include "vsplat.h"

#include <stdio.h>

/* ---- options common to every mode ---- */
typedef struct bench_opts {
    const char *out_dir;  /* --out DIR (default bench/results)                   */
    const char *data_dir; /* --data DIR, else $VSPLAT_DATA, else source/../shared/data */
    int quick;            /* --quick: smaller images, fewer runs and rows         */
    int runs;             /* --runs N: timed runs per configuration (0: mode default) */
    int threads;          /* --threads N for the N-thread rows (0: one per core)  */
    int plot;             /* 0 with --no-plot                                     */
} bench_opts;

/* Timed runs: --runs if given, else `quick_default` / `full_default`. */
int bench_runs(const bench_opts *o, int full_default, int quick_default);
/* Logical CPUs online (the N of "threads 1..N"). */
int bench_cpus(void);

/* ---- timing.c: the harness ---- */
double bench_now_ms(void);

typedef struct bench_case {
    char name[96];
    const vs_volume *vol;
    vs_settings s;
    vs_context *ctx;  /* shared per (volume, classification, pipeline family, threads, pin) */
    int keep_image;   /* keep the warm-up image in img                              */
    vs_image img;
    vs_stats warm;    /* the warm-up render (builds the relevant-voxel list)        */
    vs_stats *runs;   /* nruns timed renders                                        */
    int nruns;
    int failed;       /* render failed: message in err                              */
    char err[256];
    int rebuilds;     /* timed runs that rebuilt the relevant-voxel list (should be 0) */
} bench_case;

/* Fill a case (no rendering yet). */
void bench_case_set(bench_case *c, const char *name, const vs_volume *vol, const vs_settings *s);
/* Warm up every case once (in order), then `runs` rounds over all cases, the
 * configurations interleaved (round r starts at case r mod n), so a slow
 * phase of a shared machine spreads over all of them.  Progress on stderr.
 * Returns the number of failed cases (each reported on stderr). */
int bench_run(const char *label, bench_case *cases, int n, int runs);
void bench_cases_free(bench_case *cases, int n);
/* Release every context the harness created (call when a mode is done). */
void bench_contexts_release(void);

typedef double (*bench_metric)(const vs_stats *);
double bench_m_total(const vs_stats *st);     /* ms_total (wall clock)         */
double bench_m_setup(const vs_stats *st);     /* ms_stage.setup                */
double bench_m_raster(const vs_stats *st);    /* ms_stage.rasterize            */
double bench_m_shading(const vs_stats *st);   /* gradient + shade              */
double bench_m_composite(const vs_stats *st); /* ms_stage.composite            */

typedef struct bench_summary {
    double median, min, max;
} bench_summary;
bench_summary bench_summarize(const bench_case *c, bench_metric m);
double bench_median(double *v, int n); /* sorts v */

/* Progress line on stderr for anything that runs longer than a second:
 * overwritten in place on a terminal, else a line every few seconds. */
void bench_progress(const char *label, int done, int total, const char *what);
void bench_progress_end(void);

/* ---- data.c: inputs ---- */
/* Resolve the data folder (--data, $VSPLAT_DATA, VSPLAT_SOURCE_DIR/../shared/data). */
const char *bench_data_dir(const char *override);
/* Load a named bench input: "colin27", "brain", "em", "ct", or "scene:SPEC"
 * (a synthetic scene).  Returns 1 and prints "skipped" if the file is absent,
 * 0 on success, -1 on a load error (message printed). */
int bench_load(const bench_opts *o, const char *key, vs_volume **out);

/* The volumes, classifications and first views that `peers` and `oracle`
 * share (data.c), with a synthetic stand-in for --quick. */
typedef struct bench_peer_case {
    const char *name;         /* printed, CSV, PNG name                    */
    const char *input;        /* bench_load key (real data)                */
    const char *quick;        /* bench_load key with --quick (synthetic)   */
    double iso, ramp, az, el; /* real data                                 */
    double qiso, qramp;       /* the synthetic stand-in                    */
} bench_peer_case;
extern const bench_peer_case bench_peer_cases[];
extern const int bench_npeer_cases;
/* Their settings: the size (512², --quick 128²), the first view (angles in
 * the world frame), the iso-range and ramp, --threads (default 2). */
void bench_peer_settings(const bench_opts *o, const bench_peer_case *pc, vs_settings *s);

/* ---- results.c ---- */
/* Create the results folder (and parents).  Returns 0 or prints and returns 1. */
int bench_results_dir(const bench_opts *o);
/* Open OUT/NAME for writing ("w"); prints a message on failure. */
FILE *bench_result_open(const bench_opts *o, const char *name);
/* "model name" of the CPU and the logical CPU count, for headers. */
const char *bench_machine(void);
/* 1-minute load average (/proc/loadavg): a shared machine makes timings noisy. */
const char *bench_loadavg(void);

/* ---- plot.c ---- */
/* Write OUT/NAME.gp (the script text, which must set its own output NAME.png
 * and refer to data files by names relative to OUT) and run gnuplot in OUT.
 * Without gnuplot (or with --no-plot) it prints a note and returns 0. */
int bench_plot(const bench_opts *o, const char *name, const char *script);
/* The gnuplot terminal preamble: pngcairo if available, else png. */
const char *bench_plot_terminal(int width, int height);

/* ---- modes ---- */
int bench_table1(const bench_opts *o);
int bench_error(const bench_opts *o);
int bench_scaling(const bench_opts *o);
int bench_growth(const bench_opts *o);
int bench_kernels(const bench_opts *o); /* mode_kernels.c: SIMD kernels per ISA */
int bench_limits(const bench_opts *o);  /* mode_limits.c: each stage against the machine's limits */
/* mode_peers.c: vsplat against VolPack's octree renderer (a note if built without VolPack) */
int bench_peers(const bench_opts *o);
/* mode_oracle.c: post-cd with and without the voxels that cannot show */
int bench_oracle(const bench_opts *o);
int bench_lod(const bench_opts *o);
/* frame takes the render options of `vsplat render` (argv after "frame") */
int bench_frame(const bench_opts *o, int argc, char **argv);

#endif
