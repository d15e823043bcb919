/* Every SIMD kernel against the scalar reference (src/kernels.c) on every
 * ISA this CPU has: seeded random inputs, lengths 0 .. 3 x vector width + 1,
 * unaligned pointers, tails, zero and one weights.  Tolerance: none — the
 * kernels do one multiply and one add per element in the reference's order
 * (no FMA), so results must be bit-identical; that is also what makes images
 * independent of the ISA.  ISAs the machine lacks are skipped with a message.
 * The whole-image suite runs once per forced ISA (VSPLAT_ISA, see
 * tests/CMakeLists.txt). */
#include "kernels.h"
#include "testutil.h"

#include <string.h>


typedef void (*row4_fn)(float *, const float *, const float *, int);
typedef void (*gs_fn)(float *, const float *, const float *, const float *, int);

static unsigned rng_state = 12345u;
static float frand(void)
{
    rng_state = rng_state * 1664525u + 1013904223u;
    return (float)(rng_state >> 8) / 16777216.0f * 2.0f - 1.0f;
}

enum { MAXN = 3 * 16 + 1, PAD = 8 };

static void check_row4(const char *isa, row4_fn fn, int is_gs, gs_fn gfn)
{
    float ref[4 * (MAXN + PAD)], out[4 * (MAXN + PAD)], ex[MAXN + PAD], exd[MAXN + PAD];
    const float weights[3][4] = {{0.3f, -1.5f, 2.0f, 1e-3f}, {0, 0, 0, 0}, {1, 1, 1, 1}};
    int cases = 0;
    for (int n = 0; n <= MAXN; n++)
        for (int off = 0; off < 4; off++) /* unaligned starts */
            for (int wi = 0; wi < 3; wi++) {
                for (int i = 0; i < 4 * (MAXN + PAD); i++) ref[i] = out[i] = frand();
                for (int i = 0; i < MAXN + PAD; i++) {
                    ex[i] = frand();
                    exd[i] = frand();
                }
                if (is_gs) {
                    vs_splat_row_gs_scalar(ref + off, ex + off, exd + off, weights[wi], n);
                    gfn(out + off, ex + off, exd + off, weights[wi], n);
                } else {
                    vs_splat_row4_scalar(ref + off, ex + off, weights[wi], n);
                    fn(out + off, ex + off, weights[wi], n);
                }
                /* includes the floats around the span: nothing outside may change */
                if (memcmp(ref, out, sizeof ref) != 0) {
                    CHECK(0, "%s %s differs from scalar at n=%d offset=%d weights %d", is_gs ? "splat_row_gs" : "splat_row4",
                          isa, n, off, wi);
                    return;
                }
                cases++;
            }
    printf("%-13s %-7s bit-identical to scalar in %d cases\n", is_gs ? "splat_row_gs" : "splat_row4", isa, cases);
}

/* Footprint blocks: rows 0..9, 0 .. 2 x 16 + 1 vectors (tails of the
 * AVX-512 pairs), unaligned destination and block, strides wider than the
 * block, weight patterns of period 1 (density), 4 (RGBA) and zero; the
 * floats around the block (the rest of each row, the rows between) must
 * not change, and a block of exact zeros must leave the sheet bit-exact. */
static void check_block(const char *isa, vs_splat_block_fn fn)
{
    enum { MAXV = 33, MAXR = 9, DS = 8 * MAXV + 13, BS = 8 * MAXV + 5 };
    static float ref[(MAXR + 1) * DS + 8], out[(MAXR + 1) * DS + 8], blk[(MAXR + 1) * BS + 8];
    const float pats[3][8] = {{0.7f, 0.7f, 0.7f, 0.7f, 0.7f, 0.7f, 0.7f, 0.7f},
                              {0.3f, -1.5f, 2.0f, 1e-3f, 0.3f, -1.5f, 2.0f, 1e-3f},
                              {0, 0, 0, 0, 0, 0, 0, 0}};
    int cases = 0;
    for (int rows = 0; rows <= MAXR; rows++)
        for (int nvec = 0; nvec <= MAXV; nvec += (nvec < 4 ? 1 : 5))
            for (int off = 0; off < 3; off++)
                for (int pi = 0; pi < 4; pi++) {
                    for (size_t i = 0; i < sizeof ref / sizeof *ref; i++) ref[i] = out[i] = frand();
                    for (size_t i = 0; i < sizeof blk / sizeof *blk; i++) blk[i] = pi == 3 ? 0.0f : frand();
                    const float *w = pats[pi == 3 ? 1 : pi];
                    vs_splat_block_scalar(ref + off, DS, blk + 2 * off, BS, rows, nvec, w);
                    fn(out + off, DS, blk + 2 * off, BS, rows, nvec, w);
                    if (memcmp(ref, out, sizeof ref) != 0) {
                        CHECK(0, "splat_block %s differs from scalar: rows=%d nvec=%d offset=%d pattern %d", isa,
                              rows, nvec, off, pi);
                        return;
                    }
                    cases++;
                }
    /* a zero block adds +0 and -0 only: the sheet must come back bit-exact */
    for (size_t i = 0; i < sizeof out / sizeof *out; i++) ref[i] = out[i] = frand();
    for (size_t i = 0; i < sizeof blk / sizeof *blk; i++) blk[i] = 0.0f;
    fn(out, DS, blk, BS, MAXR, MAXV, pats[1]);
    CHECK(memcmp(ref, out, sizeof ref) == 0, "splat_block %s: a zero block changed the sheet", isa);
    printf("%-13s %-7s bit-identical to scalar in %d cases\n", "splat_block", isa, cases);
}

/* The dispatch honours the cap and never goes past the CPU. */
static void check_dispatch(void)
{
    vs_isa best = vs_isa_detect();
    for (int cap = VS_ISA_SCALAR; cap <= VS_ISA_AVX512; cap++) {
        vs_kernels k;
        vs_kernels_init(&k, (vs_isa)cap);
        vs_isa want = (vs_isa)cap > best ? best : (vs_isa)cap;
        CHECK(k.isa == want, "cap %s gave %s, expected %s", vs_isa_name((vs_isa)cap), vs_isa_name(k.isa),
              vs_isa_name(want));
        CHECK(k.splat_row1 && k.splat_row4 && k.splat_row_gs && k.composite && k.splat_block, "cap %s: empty entry",
              vs_isa_name((vs_isa)cap));
    }
    vs_kernels k;
    vs_kernels_init(&k, VS_ISA_SCALAR);
    CHECK(k.splat_row4 == vs_splat_row4_scalar, "scalar cap must use the scalar reference");
}

int main(void)
{
    vs_isa best = vs_isa_detect();
    printf("this CPU: best ISA %s\n", vs_isa_name(best));
    check_dispatch();
    check_block("scalar", vs_splat_block_scalar);
    if (best >= VS_ISA_SSE4) {
        check_row4("sse4", vs_splat_row4_sse4, 0, NULL);
        check_row4("sse4", NULL, 1, vs_splat_row_gs_sse4);
        check_block("sse4", vs_splat_block_sse4);
    } else {
        printf("SKIP: sse4 kernels: this CPU has no SSE4.1\n");
    }
    if (best >= VS_ISA_AVX2) {
        check_row4("avx2", vs_splat_row4_avx2, 0, NULL);
        check_row4("avx2", NULL, 1, vs_splat_row_gs_avx2);
        check_block("avx2", vs_splat_block_avx2);
    } else {
        printf("SKIP: avx2 kernels: this CPU has no AVX2\n");
    }
    if (best >= VS_ISA_AVX512) {
        check_row4("avx512", vs_splat_row4_avx512, 0, NULL);
        check_block("avx512", vs_splat_block_avx512);
    } else {
        printf("SKIP: avx512 kernels: this CPU has no AVX-512\n");
    }
    TEST_DONE();
}
