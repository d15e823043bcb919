/* vsplat-bench timing harness (the zstd bench pattern): build once, warm up,
 * then interleaved timed runs, medians and min-max.
 *
 * Contexts are shared between cases that need the same relevant-voxel list
 * (same volume, classification and pipeline family) and the same worker pool
 * (threads, pinning), so interleaving configurations never rebuilds the list
 * or the pool inside a timed run.  Pre-shaded splatting keeps a list without
 * the seam layer; post-alpha's list (seam + voxel gradients) also serves
 * post-cd and post-gs; the ray caster keeps no list. */
#include "bench.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

double bench_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* ---- shared contexts ---- */

typedef struct ctx_entry {
    char key[256];
    vs_context *ctx;
} ctx_entry;

static ctx_entry *g_ctx;
static int g_nctx, g_capctx;

static int pipeline_family(vs_pipeline p)
{
    return p == VS_PIPELINE_PRE ? 0 : p == VS_PIPELINE_RAYCAST ? 2 : 1;
}

static vs_context *ctx_for(const vs_volume *vol, const vs_settings *s)
{
    char key[256];
    snprintf(key, sizeof key, "%p|%d|%d|%.17g|%.17g|%.17g|%d|%p|%d|%d|%d|%.17g", (const void *)vol,
             pipeline_family(s->pipeline), s->has_iso, s->iso_lo, s->iso_hi, s->ramp, s->tf_count,
             (const void *)s->tf, s->threads, s->pin, s->seam, s->kernel_radius);
    for (int i = 0; i < g_nctx; i++)
        if (!strcmp(g_ctx[i].key, key)) return g_ctx[i].ctx;
    if (g_nctx == g_capctx) {
        int cap = g_capctx ? 2 * g_capctx : 16;
        ctx_entry *n = realloc(g_ctx, (size_t)cap * sizeof *n);
        if (!n) return NULL;
        g_ctx = n;
        g_capctx = cap;
    }
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return NULL;
    snprintf(g_ctx[g_nctx].key, sizeof g_ctx[g_nctx].key, "%s", key);
    g_ctx[g_nctx].ctx = ctx;
    g_nctx++;
    return ctx;
}

void bench_contexts_release(void)
{
    for (int i = 0; i < g_nctx; i++) vs_context_release(g_ctx[i].ctx);
    free(g_ctx);
    g_ctx = NULL;
    g_nctx = g_capctx = 0;
}

/* ---- progress ---- */

static double g_prog_start = -1, g_prog_last;
static int g_prog_shown;

void bench_progress(const char *label, int done, int total, const char *what)
{
    double now = bench_now_ms();
    if (g_prog_start < 0) {
        g_prog_start = now;
        g_prog_last = now;
        g_prog_shown = 0;
    }
    if (now - g_prog_start < 1000.0) return; /* nothing for short work */
    int tty = isatty(STDERR_FILENO);
    if (!tty && g_prog_shown && now - g_prog_last < 5000.0) return;
    g_prog_last = now;
    g_prog_shown = 1;
    fprintf(stderr, "%s%s: %d/%d %-40.40s %6.0f s%s", tty ? "\r" : "", label, done, total, what ? what : "",
            (now - g_prog_start) / 1000.0, tty ? "" : "\n");
    fflush(stderr);
}

void bench_progress_end(void)
{
    if (g_prog_shown && isatty(STDERR_FILENO)) fprintf(stderr, "\r%80s\r", "");
    g_prog_start = -1;
    g_prog_shown = 0;
}

/* ---- cases ---- */

void bench_case_set(bench_case *c, const char *name, const vs_volume *vol, const vs_settings *s)
{
    memset(c, 0, sizeof *c);
    snprintf(c->name, sizeof c->name, "%s", name);
    c->vol = vol;
    c->s = *s;
}

static int render_one(bench_case *c, vs_stats *st, int keep)
{
    vs_image img = {0, 0, NULL};
    memset(st, 0, sizeof *st);
    vs_status rc = vs_render(c->ctx, c->vol, &c->s, &img, st);
    if (rc != VS_OK) {
        snprintf(c->err, sizeof c->err, "%s", vs_last_error(c->ctx));
        c->failed = 1;
        vs_image_free(&img);
        return 0;
    }
    if (keep) {
        vs_image_free(&c->img);
        c->img = img;
    } else {
        vs_image_free(&img);
    }
    return 1;
}

int bench_run(const char *label, bench_case *cases, int n, int runs)
{
    int total = n * (runs + 1), done = 0, failed = 0;
    for (int i = 0; i < n; i++) {
        bench_case *c = &cases[i];
        c->ctx = ctx_for(c->vol, &c->s);
        free(c->runs);
        c->runs = calloc((size_t)(runs > 0 ? runs : 1), sizeof *c->runs);
        c->nruns = 0;
        if (!c->ctx || !c->runs) {
            snprintf(c->err, sizeof c->err, "out of memory");
            c->failed = 1;
        }
    }
    /* warm-up: builds the relevant-voxel lists and the pools, first touch */
    for (int i = 0; i < n; i++) {
        bench_case *c = &cases[i];
        bench_progress(label, done++, total, c->name);
        if (!c->failed) render_one(c, &c->warm, c->keep_image);
    }
    for (int r = 0; r < runs; r++)
        for (int k = 0; k < n; k++) {
            bench_case *c = &cases[(k + r) % n];
            bench_progress(label, done++, total, c->name);
            if (c->failed) continue;
            vs_stats st;
            if (!render_one(c, &st, 0)) continue;
            if (st.ms_relevant > 0) c->rebuilds++;
            c->runs[c->nruns++] = st;
        }
    bench_progress_end();
    for (int i = 0; i < n; i++) {
        if (cases[i].failed) {
            fprintf(stderr, "%s: %s failed: %s\n", label, cases[i].name, cases[i].err);
            failed++;
        } else if (cases[i].rebuilds) {
            fprintf(stderr, "%s: note: %s rebuilt its relevant-voxel list in %d timed run(s)\n", label,
                    cases[i].name, cases[i].rebuilds);
        }
    }
    return failed;
}

void bench_cases_free(bench_case *cases, int n)
{
    for (int i = 0; i < n; i++) {
        free(cases[i].runs);
        cases[i].runs = NULL;
        vs_image_free(&cases[i].img);
    }
}

/* ---- statistics ---- */

double bench_m_total(const vs_stats *st) { return st->ms_total; }
double bench_m_setup(const vs_stats *st) { return st->ms_stage.setup; }
double bench_m_raster(const vs_stats *st) { return st->ms_stage.rasterize; }
double bench_m_shading(const vs_stats *st) { return st->ms_stage.gradient + st->ms_stage.shade; }
double bench_m_composite(const vs_stats *st) { return st->ms_stage.composite; }

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double bench_median(double *v, int n)
{
    if (n <= 0) return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

bench_summary bench_summarize(const bench_case *c, bench_metric m)
{
    bench_summary s = {NAN, NAN, NAN};
    int n = c->nruns;
    const vs_stats *src = c->runs;
    if (c->failed) return s;
    if (n == 0) { /* no timed runs asked for: the warm-up is all there is */
        src = &c->warm;
        n = 1;
    }
    double *v = malloc((size_t)n * sizeof *v);
    if (!v) return s;
    for (int i = 0; i < n; i++) v[i] = m(&src[i]);
    s.median = bench_median(v, n);
    s.min = v[0];
    s.max = v[n - 1];
    free(v);
    return s;
}
