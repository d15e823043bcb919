/* vsplat-bench: this machine's limits (roof.h): cache sizes, bandwidths of
 * the kernels' access patterns, peak arithmetic rates per ISA. */
#include "bench.h"
#include "roof.h"

#include <hwloc.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

const char *const bench_roof_level_names[ROOF_NLEVELS] = {"L1", "L2", "L3", "DRAM"};
const char *const bench_roof_pattern_names[ROOF_NPATTERNS] = {"read", "write", "rmw"};

int bench_roof_get(vs_isa isa, bench_roof_fns *f)
{
    if (isa < VS_ISA_SCALAR || isa > vs_isa_detect()) return 0;
    switch (isa) {
    case VS_ISA_SSE4: bench_roof_sse4(f); break;
    case VS_ISA_AVX2: bench_roof_avx2(f); break;
    case VS_ISA_AVX512: bench_roof_avx512(f); break;
    default: bench_roof_scalar(f); break;
    }
    return 1;
}

double bench_peak_gflops(vs_isa isa, int fma, int quick)
{
    bench_roof_fns f;
    if (!bench_roof_get(isa, &f)) return 0;
    /* ~20-40 ms a trial at a few GHz: long enough for the clock to settle */
    const long iters = quick ? 2000000 : 8000000;
    double best = 1e30;
    float sink = 0;
    for (int trial = 0; trial < (quick ? 2 : 4); trial++) {
        double t0 = bench_now_ms();
        sink += f.arith(fma, iters);
        double ms = bench_now_ms() - t0;
        if (ms < best) best = ms;
    }
    if (sink == 12345.0f) printf(" "); /* keeps the chains alive */
    return (double)iters * ROOF_CHAINS * f.lanes * (fma ? 2 : 1) / (best * 1e6);
}

/* ---- cache sizes ---- */

static size_t hwloc_cache(hwloc_topology_t t, hwloc_obj_type_t type)
{
    hwloc_obj_t o = hwloc_get_obj_by_type(t, type, 0);
    return o && o->attr ? (size_t)o->attr->cache.size : 0;
}

void bench_cache_sizes_get(bench_cache_sizes *c)
{
    memset(c, 0, sizeof *c);
    hwloc_topology_t t;
    if (hwloc_topology_init(&t) == 0) {
        if (hwloc_topology_load(t) == 0) {
            c->cache[0] = hwloc_cache(t, HWLOC_OBJ_L1CACHE);
            c->cache[1] = hwloc_cache(t, HWLOC_OBJ_L2CACHE);
            c->cache[2] = hwloc_cache(t, HWLOC_OBJ_L3CACHE);
        }
        hwloc_topology_destroy(t);
    }
    c->source = "hwloc";
    if (!c->cache[0] || !c->cache[1]) {
        /* glibc's figures (its L3 is sometimes the whole package's) */
        long l1 = sysconf(_SC_LEVEL1_DCACHE_SIZE), l2 = sysconf(_SC_LEVEL2_CACHE_SIZE),
             l3 = sysconf(_SC_LEVEL3_CACHE_SIZE);
        c->cache[0] = l1 > 0 ? (size_t)l1 : 0;
        c->cache[1] = l2 > 0 ? (size_t)l2 : 0;
        c->cache[2] = l3 > 0 ? (size_t)l3 : 0;
        c->source = "sysconf";
    }
    if (!c->cache[0] || !c->cache[1] || c->cache[1] <= c->cache[0]) {
        c->source = "fixed";
        c->set[ROOF_L1] = 16 << 10;
        c->set[ROOF_L2] = 256 << 10;
        c->set[ROOF_L3] = 4 << 20;
        c->set[ROOF_DRAM] = 256 << 20;
        return;
    }
    /* half a private cache fits it with room for the stack, tables and the
     * source block; a quarter of the L3 (at least 4 L2s, so it misses L2)
     * is an L3 set; DRAM is well past the L3 */
    c->set[ROOF_L1] = c->cache[0] / 2;
    c->set[ROOF_L2] = c->cache[1] / 2;
    size_t l3 = c->cache[2] ? c->cache[2] / 4 : (size_t)4 << 20;
    if (l3 < 4 * c->cache[1]) l3 = 4 * c->cache[1];
    c->set[ROOF_L3] = l3;
    size_t dram = (size_t)256 << 20;
    if (c->cache[2] && 8 * c->cache[2] > dram) dram = 8 * c->cache[2];
    if (dram > (size_t)1 << 30) dram = (size_t)1 << 30;
    c->set[ROOF_DRAM] = dram;
}

/* ---- bandwidth ---- */

typedef struct bw_job {
    const bench_roof_fns *f;
    int pattern;
    float *buf;
    const float *src;
    size_t n;
    long reps;
    atomic_int *go, *done; /* go: 1 sweep, -1 leave without sweeping */
    float sink;
} bw_job;

static void bw_sweep(bw_job *j)
{
    switch (j->pattern) {
    case ROOF_READ: j->sink += j->f->read(j->buf, j->n, j->reps); break;
    case ROOF_WRITE: j->f->write(j->buf, j->n, j->reps); break;
    default: j->f->rmw(j->buf, j->n, j->src, 1e-6f, j->reps); break;
    }
}

/* Spin until told to go (a barrier would hang if a later thread failed to
 * start), sweep, count in. */
static void *bw_thread(void *arg)
{
    bw_job *j = arg;
    int g;
    while ((g = atomic_load(j->go)) == 0) {
    }
    if (g > 0) bw_sweep(j);
    atomic_fetch_add(j->done, 1);
    return NULL;
}

/* One timed trial on `threads` threads; GB/s or 0 if a thread did not start. */
static double bw_trial(bw_job *jobs, int threads, double per_float)
{
    pthread_t tid[256];
    atomic_int go = 0, done = 0;
    int started = 1;
    for (int t = 1; t < threads; t++) {
        jobs[t].go = &go;
        jobs[t].done = &done;
        if (pthread_create(&tid[t], NULL, bw_thread, &jobs[t]) != 0) break;
        started++;
    }
    const int ok = started == threads;
    double t0 = bench_now_ms();
    atomic_store(&go, ok ? 1 : -1);
    if (ok) bw_sweep(&jobs[0]);
    while (atomic_load(&done) < started - 1) {
    }
    double ms = bench_now_ms() - t0;
    for (int t = 1; t < started; t++) pthread_join(tid[t], NULL);
    if (!ok) {
        fprintf(stderr, "limits: could start only %d of %d threads\n", started, threads);
        return 0;
    }
    return (double)threads * (double)jobs[0].reps * (double)jobs[0].n * per_float / (ms * 1e6);
}

double bench_bandwidth(const bench_roof_fns *f, int pattern, size_t bytes, int threads, int trials, double gb)
{
    if (threads < 1) threads = 1;
    if (threads > 256) threads = 256;
    const size_t unit = ROOF_BLOCK * sizeof(float);
    size_t n = (bytes / unit) * ROOF_BLOCK; /* floats per thread */
    if (n == 0) n = ROOF_BLOCK;
    const double per_float = pattern == ROOF_RMW ? 8.0 : 4.0;
    /* `gb` a trial per thread (tens of ms: above scheduling noise), at least 2 sweeps */
    long reps = (long)(gb * 1e9 / ((double)n * per_float));
    if (reps < 2) reps = 2;

    bw_job *jobs = calloc((size_t)threads, sizeof *jobs);
    float *src = aligned_alloc(64, unit);
    int ok = jobs && src;
    for (int t = 0; ok && t < threads; t++) {
        jobs[t] = (bw_job){.f = f, .pattern = pattern, .src = src, .n = n, .reps = 1};
        jobs[t].buf = aligned_alloc(64, n * sizeof(float));
        if (!jobs[t].buf) ok = 0;
        else for (size_t i = 0; i < n; i++) jobs[t].buf[i] = (float)(i & 15); /* pages mapped now */
    }
    double best = 0;
    if (ok) {
        for (int i = 0; i < ROOF_BLOCK; i++) src[i] = 0.5f + 0.01f * (float)i;
        bw_trial(jobs, threads, per_float); /* warm: each thread's caches */
        for (int t = 0; t < threads; t++) jobs[t].reps = reps;
        for (int trial = 0; trial < trials; trial++) {
            double gbs = bw_trial(jobs, threads, per_float);
            if (gbs <= 0) {
                best = 0;
                break;
            }
            if (gbs > best) best = gbs;
        }
    }
    float sink = 0;
    for (int t = 0; jobs && t < threads; t++) {
        sink += jobs[t].sink;
        free(jobs[t].buf);
    }
    if (sink == 12345.0f) printf(" ");
    free(jobs);
    free(src);
    return best;
}
