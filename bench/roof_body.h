/* vsplat-bench roofline kernels, one body for every ISA: included by
 * roof-scalar.c, roof-sse4.c, roof-avx2.c and roof-avx512.c, each compiled
 * with its own ISA flags (bench/CMakeLists.txt) after defining
 *   ROOF_VW    lanes of a vector (1, 4, 8, 16 floats)
 *   ROOF_FILL  the name of the function that fills a bench_roof_fns.
 * GCC's vector extensions become that ISA's instructions; -ffp-contract=fast
 * on these files turns a*b+c into an FMA where the ISA has one (AVX2,
 * AVX-512), as the library's kernels use it.  Buffers are 64-byte aligned
 * and their lengths multiples of ROOF_BLOCK floats. */
#include "roof.h"

#include <stddef.h>

#if ROOF_VW == 1
typedef float vf; /* the scalar file is also built without auto-vectorisation */
#else
typedef float vf __attribute__((vector_size(4 * ROOF_VW)));
#endif

#define NV (ROOF_BLOCK / ROOF_VW) /* vectors in a block */
#define NACC 8                    /* independent accumulators: add latency x ports */

/* Keeps a loop's stores and loads from being merged across repetitions. */
#define ROOF_BARRIER() __asm__ volatile("" ::: "memory")

static float roof_read(const float *buf, size_t n, long reps)
{
    vf acc[NACC];
    for (int k = 0; k < NACC; k++) acc[k] = (vf){0};
    for (long r = 0; r < reps; r++) {
        const vf *p = (const vf *)buf;
        for (size_t i = 0; i < n / ROOF_VW; i += NACC)
            for (int k = 0; k < NACC; k++) acc[k] += p[i + (size_t)k];
        ROOF_BARRIER();
    }
    vf s = acc[0];
    for (int k = 1; k < NACC; k++) s += acc[k];
    float t = 0;
    for (int l = 0; l < ROOF_VW; l++) t += ((const float *)&s)[l];
    return t;
}

static void roof_write(float *buf, size_t n, long reps)
{
    for (long r = 0; r < reps; r++) {
        const vf v = (vf){0} + (float)(r & 7); /* a value per repetition: no memset */
        vf *p = (vf *)buf;
        for (size_t i = 0; i < n / ROOF_VW; i++) p[i] = v;
        ROOF_BARRIER();
    }
}

/* dst[i] += w * src[i mod ROOF_BLOCK]: the footprint adds, whose source (a
 * footprint row block) is small and stays in L1 while the sheet is swept. */
static void roof_rmw(float *dst, size_t n, const float *src, float w, long reps)
{
    const vf *s = (const vf *)src;
    const vf wv = (vf){0} + w;
    for (long r = 0; r < reps; r++) {
        vf *d = (vf *)dst;
        for (size_t i = 0; i < n / ROOF_VW; i += NV)
            for (int k = 0; k < NV; k++) d[i + (size_t)k] += wv * s[k];
        ROOF_BARRIER();
    }
}

/* Arithmetic throughput: ROOF_CHAINS independent chains of a = a*m + c (an
 * FMA, or a multiply and an add without one) or a = a + c, so latency is
 * hidden and only the ports bound the rate. */
static float roof_arith(int fma, long iters)
{
    vf a[ROOF_CHAINS];
    const vf m = (vf){0} + 1.0000001f, c = (vf){0} + 1e-7f;
    for (int i = 0; i < ROOF_CHAINS; i++) a[i] = c * (float)i;
    if (fma) {
        for (long it = 0; it < iters; it++)
            for (int i = 0; i < ROOF_CHAINS; i++) a[i] = a[i] * m + c;
    } else {
        for (long it = 0; it < iters; it++)
            for (int i = 0; i < ROOF_CHAINS; i++) a[i] = a[i] + c;
    }
    float t = 0;
    for (int i = 0; i < ROOF_CHAINS; i++) t += ((const float *)&a[i])[0];
    return t;
}

void ROOF_FILL(bench_roof_fns *f)
{
    f->lanes = ROOF_VW;
    f->read = roof_read;
    f->write = roof_write;
    f->rmw = roof_rmw;
    f->arith = roof_arith;
}
