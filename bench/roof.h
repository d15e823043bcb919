/* vsplat-bench: this machine's limits, as the kernels meet them (roof.c).
 *
 * Hand-written loops in bench/ only (never in src/): read, write and
 * read-modify-write sweeps and arithmetic chains, one copy per ISA
 * (roof-ISA.c, each built with that ISA's flags from roof_body.h) chosen at
 * run time with vs_isa_detect(). */
#ifndef VSPLAT_BENCH_ROOF_H
#define VSPLAT_BENCH_ROOF_H

#include "vsplat.h"

#include <stddef.h>

enum {
    ROOF_BLOCK = 64, /* floats: the rmw source block, and the buffers' length unit */
    ROOF_CHAINS = 10 /* independent arithmetic chains (FMA latency 4 x 2 ports, with margin) */
};

typedef struct bench_roof_fns {
    int lanes; /* floats per vector */
    float (*read)(const float *buf, size_t n, long reps);
    void (*write)(float *buf, size_t n, long reps);
    void (*rmw)(float *dst, size_t n, const float *src, float w, long reps);
    float (*arith)(int fma, long iters); /* returns a sink value */
} bench_roof_fns;

void bench_roof_scalar(bench_roof_fns *f);
void bench_roof_sse4(bench_roof_fns *f);
void bench_roof_avx2(bench_roof_fns *f);
void bench_roof_avx512(bench_roof_fns *f);

/* The loops of an ISA (VS_ISA_SCALAR..VS_ISA_AVX512); 0 if this CPU lacks it. */
int bench_roof_get(vs_isa isa, bench_roof_fns *f);

/* Peak single-precision rate of an ISA in GFLOP/s on one core: fma = 1
 * counts a*b+c as 2 flops (a multiply and an add where the ISA has no FMA),
 * fma = 0 counts adds.  Best of a few trials; 0 if the CPU lacks the ISA. */
double bench_peak_gflops(vs_isa isa, int fma, int quick);

/* ---- memory and cache bandwidth ---- */
enum { ROOF_L1, ROOF_L2, ROOF_L3, ROOF_DRAM, ROOF_NLEVELS };
enum { ROOF_READ, ROOF_WRITE, ROOF_RMW, ROOF_NPATTERNS };
extern const char *const bench_roof_level_names[ROOF_NLEVELS];
extern const char *const bench_roof_pattern_names[ROOF_NPATTERNS];

typedef struct bench_cache_sizes {
    size_t cache[3];        /* L1d, L2, L3 bytes of one core's share        */
    const char *source;     /* "hwloc", "sysconf" or "fixed"                 */
    size_t set[ROOF_NLEVELS]; /* working set that fits each level (one thread) */
} bench_cache_sizes;
void bench_cache_sizes_get(bench_cache_sizes *c);

/* GB/s (1e9 bytes) of one pattern over a working set of `bytes` per thread
 * on `threads` threads (all summed).  Bytes counted as the library's
 * vs_stats counts them: read 4, write 4, rmw 8 (dst read and written; the
 * source block stays in L1) per float.  Each trial moves about `gb` GB per
 * thread; the best of `trials` counts.  0 on failure. */
double bench_bandwidth(const bench_roof_fns *f, int pattern, size_t bytes, int threads, int trials, double gb);

/* ---- hardware counters (counters.c): perf_event_open ---- */
enum { HWC_CYCLES, HWC_INSTRUCTIONS, HWC_CACHE_MISSES, HWC_N };
typedef struct bench_hwc {
    int fd[HWC_N];
    char why[200]; /* why counting is unavailable (empty when it works) */
} bench_hwc;
/* Open disabled counters of this thread and of threads it creates later
 * (create the vs_context afterwards so its workers are counted).  Returns 0,
 * or -1 with why[] set. */
int bench_hwc_open(bench_hwc *h);
void bench_hwc_start(bench_hwc *h);
/* Stop and read the counts (summed over the threads); 0 or -1. */
int bench_hwc_stop(bench_hwc *h, unsigned long long out[HWC_N]);
void bench_hwc_close(bench_hwc *h);

#endif
