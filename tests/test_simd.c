/* Every SIMD kernel against the scalar reference (simd/scalar.c) on every
 * ISA this CPU has: seeded random inputs, lengths 0 .. 3 x vector width + 1,
 * unaligned pointers, tails, zero and one weights.  Tolerance: none — the
 * kernels do one multiply and one add per element in the reference's order
 * (no FMA), so results must be bit-identical; that is also what makes images
 * independent of the ISA.  ISAs the machine lacks are skipped with a message.
 * The whole-image suite runs once per forced ISA (VSPLAT_ISA, see
 * tests/CMakeLists.txt). */
#include "block.h"
#include "kernels.h"
#include "testutil.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>


typedef void (*row4_fn)(float *, const float *, const float *, int);

static unsigned rng_state = 12345u;
static float frand(void)
{
    rng_state = rng_state * 1664525u + 1013904223u;
    return (float)(rng_state >> 8) / 16777216.0f * 2.0f - 1.0f;
}

enum { MAXN = 3 * 16 + 1, PAD = 8 };

static void check_row4(const char *isa, row4_fn fn)
{
    float ref[4 * (MAXN + PAD)], out[4 * (MAXN + PAD)], ex[MAXN + PAD];
    const float weights[3][4] = {{0.3f, -1.5f, 2.0f, 1e-3f}, {0, 0, 0, 0}, {1, 1, 1, 1}};
    int cases = 0;
    for (int n = 0; n <= MAXN; n++)
        for (int off = 0; off < 4; off++) /* unaligned starts */
            for (int wi = 0; wi < 3; wi++) {
                for (int i = 0; i < 4 * (MAXN + PAD); i++) ref[i] = out[i] = frand();
                for (int i = 0; i < MAXN + PAD; i++) ex[i] = frand();
                vs_splat_row4_scalar(ref + off, ex + off, weights[wi], n);
                fn(out + off, ex + off, weights[wi], n);
                /* includes the floats around the span: nothing outside may change */
                if (memcmp(ref, out, sizeof ref) != 0) {
                    CHECK(0, "splat_row4 %s differs from scalar at n=%d offset=%d weights %d", isa, n, off, wi);
                    return;
                }
                cases++;
            }
    printf("%-13s %-7s bit-identical to scalar in %d cases\n", "splat_row4", isa, cases);
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


/* Gradient-splat blocks mixed into 4-channel sheets: same sizes and
 * offsets as check_block, random mixing matrices and one with zero rows;
 * returns the failures (so a wrong kernel can be shown to fail). */
typedef void (*block_mix_fn)(float *, ptrdiff_t, const float *, ptrdiff_t, int, int, const float *);
static int check_block_mix(const char *isa, block_mix_fn fn)
{
    enum { MAXV = 33, MAXR = 9, DS = 8 * MAXV + 12, BS = 8 * MAXV + 4 };
    static float ref[(MAXR + 1) * DS + 8], out[(MAXR + 1) * DS + 8], blk[(MAXR + 1) * BS + 8];
    int cases = 0;
    for (int rows = 0; rows <= MAXR; rows++)
        for (int nvec = 0; nvec <= MAXV; nvec += (nvec < 4 ? 1 : 5))
            for (int off = 0; off < 3; off++)
                for (int mi = 0; mi < 2; mi++) {
                    float m[12];
                    for (int i = 0; i < 12; i++) m[i] = mi == 1 && i % 3 ? 0.0f : frand();
                    for (size_t i = 0; i < sizeof ref / sizeof *ref; i++) ref[i] = out[i] = frand();
                    for (size_t i = 0; i < sizeof blk / sizeof *blk; i++) blk[i] = frand();
                    /* sheet pixels start on 4-float boundaries plus 4 off, as
                     * block pixels do (offsets shift both) */
                    vs_splat_block_mix_scalar(ref + 4 * off, DS, blk + 4 * off, BS, rows, nvec, m);
                    fn(out + 4 * off, DS, blk + 4 * off, BS, rows, nvec, m);
                    if (memcmp(ref, out, sizeof ref) != 0) {
                        if (isa)
                            CHECK(0, "splat_block_mix %s differs from scalar: rows=%d nvec=%d offset=%d matrix %d",
                                  isa, rows, nvec, off, mi);
                        return 1;
                    }
                    cases++;
                }
    if (isa) printf("%-13s %-7s bit-identical to scalar in %d cases\n", "splat_block_mix", isa, cases);
    return 0;
}

/* A deliberately wrong mixing kernel (channel 3 takes h dy's weight for
 * h dx) must fail check_block_mix. */
static void block_mix_off(float *dst, ptrdiff_t ds, const float *blk, ptrdiff_t bs, int rows, int nvec,
                          const float *m)
{
    float w[12];
    memcpy(w, m, sizeof w);
    w[10] = m[11];
    vs_splat_block_mix_scalar(dst, ds, blk, bs, rows, nvec, w);
}

/* Shading tables filled with random entries (every index mistake shows),
 * padded by 4 bytes as vs_shade_lut_setup does for 32-bit gathers. */
enum { NL = 64, NP = NL / 2 + 1 };
typedef struct shade_fixture {
    float alpha[VS_KTAB], color[3 * VS_KTAB], diffuse[NP * NL], specular[NP * NL];
    float zalpha[VS_KTAB]; /* 0 on the table's lower half, as an iso-surface's */
    uint16_t lambda_bin[255 * 255 + 2], phi_bin[255 * 181 + 2];
    uint8_t radius[255 * 255 + 4];
    vs_shade_tabs T;
} shade_fixture;

static void fixture_init(shade_fixture *F)
{
    for (int i = 0; i < VS_KTAB; i++) F->alpha[i] = frand() > 0.0f ? frand() * 0.5f + 0.5f : 0.0f;
    F->alpha[0] = 0.0f;
    F->alpha[VS_KTAB - 1] = 1.0f; /* alpha 1 at the top end */
    for (int i = 0; i < 3 * VS_KTAB; i++) F->color[i] = frand() * 0.5f + 0.5f;
    for (int i = 0; i < NP * NL; i++) {
        F->diffuse[i] = frand() * 0.5f + 0.5f;
        F->specular[i] = frand() * 0.5f + 0.5f;
    }
    memset(F->lambda_bin, 0, sizeof F->lambda_bin);
    memset(F->phi_bin, 0, sizeof F->phi_bin);
    memset(F->radius, 0, sizeof F->radius);
    for (int i = 0; i < 255 * 255; i++) {
        rng_state = rng_state * 1664525u + 1013904223u;
        F->lambda_bin[i] = (uint16_t)((rng_state >> 8) % NL);
        F->radius[i] = (uint8_t)((rng_state >> 20) % 181);
    }
    for (int i = 0; i < 255 * 181; i++) {
        rng_state = rng_state * 1664525u + 1013904223u;
        F->phi_bin[i] = (uint16_t)((rng_state >> 8) % NP);
    }
    /* x = (v + 10) * 4095 / 20: v in [-10, 10] spans the table */
    F->T = (vs_shade_tabs){.vmin = -10.0, .scale = 4095.0 / 20.0, .alpha = F->alpha, .color = F->color,
                           .slab = 0.375f, .two_slab = 0.75f, .ppm = 1.3f, .zpm = 0.9f, .nl = NL,
                           .lambda_bin = F->lambda_bin, .radius = F->radius, .phi_bin = F->phi_bin,
                           .diffuse = F->diffuse, .specular = F->specular};
    F->T.alpha_zero_x = vs_alpha_zero_x(F->alpha);
    for (int i = 0; i < VS_KTAB; i++) F->zalpha[i] = i < VS_KTAB / 2 ? 0.0f : F->alpha[i];
}

/* The classification tables of variant var: 0 the fixture's, 1 a zero
 * lower half (whole vectors of transparent pixels), 2 gradients only. */
static vs_shade_tabs classify_tabs(const shade_fixture *F, int var)
{
    vs_shade_tabs T = F->T;
    if (var == 1) {
        T.alpha = F->zalpha;
        T.alpha_zero_x = vs_alpha_zero_x(F->zalpha);
    }
    if (var == 2) T.alpha = NULL;
    return T;
}

/* A classification kernel's outputs (ao, go) against the reference's
 * (ar, gr) over npix pixels, the span [off, off + n) written: the same
 * opacities bit for bit; gradients the same bits where ar is positive
 * (everywhere with `all`: no opacity table), else the same bits or left as
 * they were (g0), and left as they were outside the span.  Reports the
 * case (kernel name, isa, n, off, rep, tables var) unless isa is NULL. */
static int classified_agree(const char *name, const char *isa, const float *ar, const float *ao, const float *gr,
                            const float *go, const float *g0, int npix, int off, int n, int rep, int var)
{
    int ok = memcmp(ar, ao, (size_t)npix * sizeof *ar) == 0;
    for (int i = 0; ok && i < npix; i++) {
        const int in = i >= off && i < off + n;
        const size_t b = 3 * sizeof(float);
        const int same = memcmp(gr + 3 * i, go + 3 * i, b) == 0, kept = memcmp(g0 + 3 * i, go + 3 * i, b) == 0;
        ok = !in ? kept : (var == 2 || ar[i] > 0.0f) ? same : same || kept;
    }
    if (!ok && isa)
        CHECK(0, "%s %s differs from scalar at n=%d offset=%d rep %d tables %d", name, isa, n, off, rep, var);
    return ok;
}

/* a density: mostly inside the table, plus its ends, beyond them, NaN, +-Inf */
static float density(void)
{
    rng_state = rng_state * 1664525u + 1013904223u;
    switch ((rng_state >> 24) % 16) {
    case 0: return NAN;
    case 1: return INFINITY;
    case 2: return -INFINITY;
    case 3: return -10.0f; /* x = 0 */
    case 4: return 10.0f;  /* x = 4095: the last entry */
    case 5: return 1e30f;
    case 6: return -1e30f;
    case 7: return 0.0f;
    case 8: return 9.998f; /* x = 4094.6: the last interpolated interval */
    default: return frand() * 11.0f;
    }
}

/* a density mostly under the zero half of the fixture's zalpha (x below
 * 1740), so that whole vectors are transparent, sometimes above it or
 * NaN, Inf */
static float low_density(void)
{
    rng_state = rng_state * 1664525u + 1013904223u;
    return (rng_state >> 24) % 16 == 0 ? density() : -6.0f + 4.5f * frand();
}

/* a gradient component: random, zero, tiny, huge, NaN, Inf */
static float gcomp(void)
{
    rng_state = rng_state * 1664525u + 1013904223u;
    switch ((rng_state >> 24) % 16) {
    case 0: return 0.0f;
    case 1: return -0.0f;
    case 2: return 1e-31f;
    case 3: return FLT_MAX;
    case 4: return -INFINITY;
    case 5: return NAN;
    case 6: return 0.0f;
    default: return frand() * 50.0f;
    }
}

/* step 1 of post-cd: a 5-row density sheet and its neighbours two each
 * side, with the two-point differences, the four-point ones and mixes
 * within (rep 2, 3) and across sheets (rep 1, 2, 3); the outputs' guard
 * floats must not change */
static int check_classify(const char *isa, vs_classify_cd_fn fn, const shade_fixture *F)
{
    enum { S = MAXN + 2 * PAD, NPIX = MAXN + PAD };
    static const float wide[4] = {0.0f, 0.0f, 1.0f / 12.0f, 0.03125f}, wide_z[4] = {0.0f, 1.0f / 12.0f, 0.03125f,
                                                                                      1.0f / 12.0f};
    float q[5 * S], qp[5 * S], qn[5 * S], qp2[5 * S], qn2[5 * S];
    float ar[NPIX], ao[NPIX], gr[3 * NPIX], go[3 * NPIX], g0[3 * NPIX];
    int cases = 0;
    for (int n = 0; n <= MAXN; n++)
        for (int off = 0; off < 4; off++)
            for (int rep = 0; rep < 4; rep++)
                for (int var = 0; var < 3; var++) {
                    vs_shade_tabs T = classify_tabs(F, var);
                    T.cd_wide = wide[rep];
                    T.cd_wide_z = wide_z[rep];
                    for (int i = 0; i < 5 * S; i++) {
                        q[i] = var == 1 ? low_density() : density();
                        qp[i] = rep == 1 ? q[i] : density(); /* rep 1: zero two-point z difference */
                        qn[i] = density();
                        qp2[i] = density();
                        qn2[i] = density();
                    }
                    for (int i = 0; i < NPIX; i++) ar[i] = ao[i] = frand();
                    for (int i = 0; i < 3 * NPIX; i++) gr[i] = go[i] = g0[i] = frand();
                    const int b = 2 * S + PAD / 2 + off; /* middle row, unaligned */
                    const float *p2 = T.cd_wide_z > 0.0f ? qp2 + b : NULL, *n2 = T.cd_wide_z > 0.0f ? qn2 + b : NULL;
                    vs_classify_cd_scalar(ar + off, gr + 3 * off, q + b, qp + b, qn + b, p2, n2, S, n, &T);
                    fn(ao + off, go + 3 * off, q + b, qp + b, qn + b, p2, n2, S, n, &T);
                    if (!classified_agree("classify_cd", isa, ar, ao, gr, go, g0, NPIX, off, n, rep, var)) return 0;
                    cases++;
                }
    if (isa) printf("%-13s %-7s bit-identical to scalar in %d cases\n", "classify_cd", isa, cases);
    return 1;
}

/* The reference's in-sheet differences against the derivative itself: on
 * the cubic q = x^3 - 2 y^3 + xy / 2 the four-point stencil (cd_wide 1/12)
 * is exact, the two-point one is off by 1 in x and 2 in y (h^2 q'''/6), a
 * mix by the mix's share of that; a linear sheet is exact for any weight. */
static void check_cd_reference(const shade_fixture *F)
{
    enum { S = 16 };
    float q[9 * S], lin[9 * S], qz[9 * S], g[3 * 4];
    for (int y = 0; y < 9; y++)
        for (int x = 0; x < S; x++) {
            const float u = (float)(x - 8), v = (float)(y - 4);
            q[y * S + x] = u * u * u - 2.0f * v * v * v + 0.5f * u * v;
            lin[y * S + x] = 3.0f * u - 5.0f * v + 7.0f;
            qz[y * S + x] = 0.0f;
        }
    static const float wide[3] = {0.0f, 1.0f / 12.0f, 1.0f / 24.0f};
    for (int w = 0; w < 3; w++) {
        vs_shade_tabs T = F->T;
        T.alpha = NULL;
        T.cd_wide = wide[w];
        const int b = 4 * S + 6; /* pixels (u, v) = (-2..1, 0) */
        vs_classify_cd_scalar(NULL, g, q + b, qz + b, qz + b, NULL, NULL, S, 4, &T);
        const float share = 1.0f - 12.0f * wide[w]; /* of the two-point error */
        for (int i = 0; i < 4; i++) {
            const float u = (float)(i - 2), v = 0.0f;
            const float ex = 3.0f * u * u + 0.5f * v + share, ey = -6.0f * v * v + 0.5f * u - 2.0f * share;
            CHECK(fabsf(g[3 * i] - ex) < 1e-5f && fabsf(g[3 * i + 1] - ey) < 1e-5f,
                  "in-sheet differences (weight %g) at u=%g: %g %g, expected %g %g", (double)wide[w], (double)u,
                  (double)g[3 * i], (double)g[3 * i + 1], (double)ex, (double)ey);
        }
        vs_classify_cd_scalar(NULL, g, lin + b, qz + b, qz + b, NULL, NULL, S, 4, &T);
        for (int i = 0; i < 4; i++)
            CHECK(fabsf(g[3 * i] - 3.0f) < 1e-5f && fabsf(g[3 * i + 1] + 5.0f) < 1e-5f,
                  "in-sheet differences (weight %g) of a linear sheet: %g %g", (double)wide[w], (double)g[3 * i],
                  (double)g[3 * i + 1]);
    }
    /* across sheets, one slab apart: q = z^3 at z = 1 + (-2 .. 2), q' = 3;
     * the two-point difference reads 4 (h^2 q'''/6 = 1 off), the stencil 3 */
    float zs[5][S];
    for (int d = 0; d < 5; d++)
        for (int x = 0; x < S; x++) zs[d][x] = (float)((d - 1) * (d - 1) * (d - 1));
    for (int w = 0; w < 3; w++) {
        vs_shade_tabs T = F->T;
        T.alpha = NULL;
        T.cd_wide = 0.0f;
        T.cd_wide_z = wide[w];
        T.slab = 1.0f;
        T.two_slab = 2.0f;
        const int b = 4 * S + 6;
        vs_classify_cd_scalar(NULL, g, lin + b, zs[1] + 6, zs[3] + 6, zs[0] + 6, zs[4] + 6, S, 4, &T);
        const float ez = 3.0f + (1.0f - 12.0f * wide[w]);
        for (int i = 0; i < 4; i++)
            CHECK(fabsf(g[3 * i + 2] - ez) < 1e-5f && fabsf(g[3 * i] - 3.0f) < 1e-5f,
                  "differences across sheets (weight %g): %g, expected %g", (double)wide[w], (double)g[3 * i + 2],
                  (double)ez);
    }
    printf("classify_cd   scalar  differences within and across sheets: 4-point exact on a cubic, mixes by their "
           "share\n");
}

/* a row of post-gs's lattice ripple (kernels.h vs_ripple_row): w[a]
 * cycles a pixel and phase ph[a] per axis at x = 0, random terms; the
 * span starts at pixel x = 8 b0 + m of the row (random block b0 and lane
 * m), so pixel i of the span lies at phase ph + w (x + i) */
enum { RIPPLE_N = 61 }; /* check_ripple_reference's row (check_classify_gs's are at most MAXN) */
/* blocks a span of n pixels from lane m < 8 reads: up to (7 + n - 1) / 8 + 1 */
enum { RIPPLE_BLOCKS = (7 + ((int)RIPPLE_N > (int)MAXN ? (int)RIPPLE_N : (int)MAXN) - 1) / 8 + 2 };
typedef struct ripple_case {
    vs_ripple_row R;
    vs_ripple_lanes L;
    float xr[RIPPLE_BLOCKS][6];
    double w[3], ph[3];
    int x; /* the span's first pixel */
} ripple_case;

static void ripple_random(ripple_case *rc)
{
    const int b0 = (int)(rand() % 1000), m = (int)(rand() % 8);
    rc->x = 8 * b0 + m;
    for (int a = 0; a < 3; a++) {
        rc->w[a] = frand();
        rc->ph[a] = 0.5 * (frand() + 1.0);
        rc->L.ca[a] = 0.01f * frand();
        rc->L.cb[a] = 0.01f * frand();
        for (int j = 0; j < 3; j++) rc->L.m[a][j] = frand();
        for (int l = 0; l < 8; l++) {
            rc->L.cl[a][l] = (float)cos(2.0 * M_PI * rc->w[a] * l);
            rc->L.sl[a][l] = (float)sin(2.0 * M_PI * rc->w[a] * l);
        }
        for (int c = 0; c < RIPPLE_BLOCKS; c++) {
            const double t = 2.0 * M_PI * fmod(rc->w[a] * 8.0 * (b0 + c), 1.0);
            rc->xr[c][a] = (float)cos(t);
            rc->xr[c][3 + a] = (float)sin(t);
        }
        rc->R.C[a] = (float)cos(2.0 * M_PI * rc->ph[a]);
        rc->R.S[a] = (float)sin(2.0 * M_PI * rc->ph[a]);
    }
    rc->R.xr = (const float(*)[6])rc->xr;
    rc->R.m = m;
    rc->R.L = &rc->L;
}

/* step 1 of post-gs: (density, gradient splats) per pixel; densities as
 * above, gradient splats with zeros, NaN and Inf; without and with a
 * lattice ripple */
static int check_classify_gs(const char *isa, vs_classify_gs_fn fn, const shade_fixture *F)
{
    enum { NPIX = MAXN + PAD };
    float q4[4 * NPIX], ar[NPIX], ao[NPIX], gr[3 * NPIX], go[3 * NPIX], g0[3 * NPIX];
    int cases = 0;
    for (int n = 0; n <= MAXN; n++)
        for (int off = 0; off < 4; off++)
            for (int rep = 0; rep < 2; rep++)
                for (int var = 0; var < 3; var++)
                    for (int rip = 0; rip < 2; rip++) {
                        const vs_shade_tabs T = classify_tabs(F, var);
                        ripple_case rc;
                        ripple_random(&rc);
                        const vs_ripple_row *row = rip ? &rc.R : NULL;
                        for (int i = 0; i < NPIX; i++) {
                            q4[4 * i] = var == 1 ? low_density() : density();
                            for (int c = 1; c < 4; c++) q4[4 * i + c] = rep ? frand() : gcomp();
                            ar[i] = ao[i] = frand();
                        }
                        for (int i = 0; i < 3 * NPIX; i++) gr[i] = go[i] = g0[i] = frand();
                        vs_classify_gs_scalar(ar + off, gr + 3 * off, q4 + 4 * off, n, &T, row);
                        fn(ao + off, go + 3 * off, q4 + 4 * off, n, &T, row);
                        if (!classified_agree("classify_gs", isa, ar, ao, gr, go, g0, NPIX, off, n, rep, var)) return 0;
                        cases++;
                    }
    if (isa) printf("%-13s %-7s bit-identical to scalar in %d cases\n", "classify_gs", isa, cases);
    return 1;
}

/* The reference's ripple against its definition in double: pixel i's
 * gradient less q v(i), v = Minv-like m of the terms ca cos + cb sin at
 * phase ph + w (x + i) (the lanes and the blocks' turns in float); and a
 * pixel's term must not depend on where its span starts: the same row
 * classified from each of its first 9 pixels on gives the same bits */
static void check_ripple_reference(const shade_fixture *F)
{
    enum { N = RIPPLE_N };
    float q4[4 * N], a[N], g[3 * N], g2[3 * N];
    double worst = 0.0;
    int moved = 0;
    for (int rep = 0; rep < 50; rep++) {
        const vs_shade_tabs T = classify_tabs(F, 2);
        ripple_case rc;
        ripple_random(&rc);
        for (int i = 0; i < 4 * N; i++) q4[i] = 4.0f * frand();
        vs_classify_gs_scalar(a, g, q4, N, &T, &rc.R);
        for (int i = 0; i < N; i++)
            for (int j = 0; j < 3; j++) {
                double v = 0.0;
                for (int x = 0; x < 3; x++) {
                    const double t = 2.0 * M_PI * (rc.ph[x] + rc.w[x] * (rc.x + i));
                    v += rc.L.m[x][j] * (rc.L.ca[x] * cos(t) + rc.L.cb[x] * sin(t));
                }
                const double want = (double)q4[4 * i + 1 + j] / T.slab - q4[4 * i] * v;
                worst = fmax(worst, fabs(g[3 * i + j] - want));
            }
        for (int s0 = 1; s0 <= 8; s0++) {
            vs_ripple_row R = rc.R;
            const int m = rc.R.m + s0;
            R.xr = rc.R.xr + (m >> 3);
            R.m = m & 7;
            vs_classify_gs_scalar(a, g2, q4 + 4 * s0, N - s0, &T, &R);
            if (memcmp(g2, g + 3 * s0, sizeof(float) * 3 * (N - s0))) moved++;
        }
    }
    printf("classify_gs   scalar  lattice ripple within %.2g of its definition over %d pixels, "
           "the same bits from any span start\n", worst, N);
    CHECK(worst < 2e-5, "classify_gs's ripple off its definition by %g", worst);
    CHECK(moved == 0, "classify_gs's ripple changed with the span's start in %d rows", moved);
}

/* step 2: gradients with zeros, tiny, huge, NaN and Inf components,
 * opacities 0, -0, NaN, 1 and random; densities read with stride 1 (post-cd)
 * and 4 (post-gs) */
static int check_shade(const char *isa, vs_shade_lut_fn fn, const shade_fixture *F)
{
    float al[MAXN + PAD], v[4 * (MAXN + PAD)], gr[3 * (MAXN + PAD)], go[3 * (MAXN + PAD)];
    int cases = 0;
    for (int n = 0; n <= MAXN; n++)
        for (int off = 0; off < 4; off++)
            for (int vs = 1; vs <= 4; vs += 3)
                for (int rep = 0; rep < 3; rep++) {
                    for (int i = 0; i < MAXN + PAD; i++) {
                        rng_state = rng_state * 1664525u + 1013904223u;
                        unsigned c = (rng_state >> 24) % 8;
                        al[i] = c == 0 ? 0.0f : c == 1 ? -0.0f : c == 2 ? NAN : c == 3 ? 1.0f : frand();
                        if (rep == 2) al[i] = 1.0f; /* every pixel shaded */
                    }
                    for (int i = 0; i < 4 * (MAXN + PAD); i++) v[i] = density();
                    for (int i = 0; i < 3 * (MAXN + PAD); i++) gr[i] = go[i] = rep == 1 ? frand() * 5.0f : gcomp();
                    vs_shade_lut_scalar(gr + 3 * off, al + off, v + off, vs, n, &F->T);
                    fn(go + 3 * off, al + off, v + off, vs, n, &F->T);
                    if (memcmp(gr, go, sizeof gr) != 0) {
                        if (isa)
                            CHECK(0, "shade_lut %s differs from scalar at n=%d offset=%d vstride=%d rep %d", isa, n,
                                  off, vs, rep);
                        return 0;
                    }
                    cases++;
                }
    if (isa) printf("%-13s %-7s bit-identical to scalar in %d cases\n", "shade_lut", isa, cases);
    return 1;
}

/* the Phong terms alone over dense gradients (the pre-integrated shading
 * packs its live pixels): n up to past three 64-pixel blocks; the outputs'
 * guard floats must not change */
enum { TMAX = 3 * 64 + 9 };
static int check_shade_terms(const char *isa, vs_shade_terms_fn fn, const shade_fixture *F)
{
    static float g[3 * (TMAX + PAD)], dr[TMAX + PAD], dn[TMAX + PAD], sr[TMAX + PAD], sn[TMAX + PAD];
    int cases = 0;
    for (int n = 0; n <= TMAX; n++)
        for (int off = 0; off < 3; off++)
            for (int rep = 0; rep < 2; rep++) {
                for (int i = 0; i < 3 * (TMAX + PAD); i++) g[i] = rep ? frand() * 5.0f : gcomp();
                for (int i = 0; i < TMAX + PAD; i++) dr[i] = dn[i] = sr[i] = sn[i] = frand();
                vs_shade_terms_scalar(dr + off, sr + off, g + 3 * off, n, &F->T);
                fn(dn + off, sn + off, g + 3 * off, n, &F->T);
                if (memcmp(dr, dn, sizeof dr) != 0 || memcmp(sr, sn, sizeof sr) != 0) {
                    if (isa) CHECK(0, "shade_terms %s differs from scalar at n=%d offset=%d rep %d", isa, n, off, rep);
                    return 0;
                }
                cases++;
            }
    if (isa) printf("%-13s %-7s bit-identical to scalar in %d cases\n", "shade_terms", isa, cases);
    return 1;
}

/* A pre-integration table filled with random entries over [-10, 10] and
 * over [0, 20]: segments whose ends lie inside, on the cells' edges, on
 * and past the table's ends, NaN and +-Inf (densities as above) */
enum { PN = 256 };
static float preint_tab[4 * PN * PN] __attribute__((aligned(64)));
static int check_preint_alpha(const char *isa, vs_preint_alpha_fn fn)
{
    for (int i = 0; i < 4 * PN * PN; i++) preint_tab[i] = frand() * 0.5f + 0.5f;
    static float f[TMAX + PAD], m[TMAX + PAD], b[TMAX + PAD], ar[TMAX + PAD], ao[TMAX + PAD];
    int cases = 0;
    /* two domains: [-10, 10], and [0, 20], where -0 and 0 give x = -0 and +0;
     * then [-10, 10] again with a transparent block up to entry ZB, whose
     * segments a kernel may skip (values mostly inside it and at its edge) */
    enum { ZB = 120 };
    for (int dom = 0; dom < 3; dom++) {
        if (dom == 2)
            for (int i = 0; i <= ZB; i++)
                for (int j = 0; j <= ZB; j++) preint_tab[4 * (i * PN + j)] = 0.0f;
        const vs_preint_tabs P = {preint_tab, dom == 1 ? 0.0f : -10.0f, (PN - 1) / 20.0f, PN, dom == 2 ? ZB : 0.0f};
        const float zv = P.vmin + (float)ZB / P.scale; /* x = ZB */
        for (int n = 0; n <= TMAX; n++)
            for (int off = 0; off < 3; off++) {
                for (int i = 0; i < TMAX + PAD; i++) {
                    f[i] = density();
                    m[i] = density();
                    b[i] = density();
                    ar[i] = ao[i] = frand();
                    if (dom < 2 && (i / 8) % 4 == 1) /* runs below the table: its first entry, not 0 */
                        f[i] = m[i] = b[i] = P.vmin - 1.0f - frand();
                    if (dom == 2 && (i / 8) % 4 != 3) { /* runs inside the block, one in four mixed */
                        f[i] = -10.0f + (zv + 10.0f) * frand();
                        m[i] = -10.0f + (zv + 10.0f) * frand();
                        b[i] = (i % 5 == 0) ? nextafterf(zv, i % 2 ? INFINITY : -INFINITY)
                                            : -10.0f + (zv + 10.0f) * frand();
                    }
                }
                /* the cells' edges: x = +-0, just below 0, and values at and
                 * next to x = n - 2 and n - 1, where the cell stops growing */
                const float top = P.vmin + (float)(PN - 2) / P.scale, end = P.vmin + (float)(PN - 1) / P.scale;
                const float edge[8] = {-0.0f, 0.0f, P.vmin, nextafterf(P.vmin, -INFINITY), top,
                                       nextafterf(top, INFINITY), nextafterf(top, -INFINITY), end};
                for (int i = 0; i < 8 && 3 * i + 2 + off < n; i++) {
                    f[3 * i + off] = edge[i];
                    m[3 * i + 1 + off] = edge[(i + 3) % 8];
                    b[3 * i + 2 + off] = edge[(i + 5) % 8];
                }
                vs_preint_alpha_scalar(ar + off, f + off, m + off, b + off, n, &P);
                fn(ao + off, f + off, m + off, b + off, n, &P);
                if (memcmp(ar, ao, sizeof ar) != 0) {
                    if (isa) CHECK(0, "preint_alpha %s differs from scalar at n=%d offset=%d domain %d", isa, n, off, dom);
                    return 0;
                }
                cases++;
            }
    }
    if (isa) printf("%-13s %-7s bit-identical to scalar in %d cases\n", "preint_alpha", isa, cases);
    return 1;
}

/* compositing: accumulators with opacity below, at and above the
 * threshold and at 1; alpha 0, -0, NaN, 1 and random; colours of hidden
 * pixels NaN (they must not leak); thresholds 0.5 and 1 */
static int check_composite(const char *isa, vs_composite_fn fn)
{
    float ar[4 * (MAXN + PAD)], ao[4 * (MAXN + PAD)], al[MAXN + PAD], rgb[3 * (MAXN + PAD) + 1];
    int cases = 0;
    for (int n = 0; n <= MAXN; n++)
        for (int off = 0; off < 4; off++)
            for (int rep = 0; rep < 4; rep++) {
                const float thr = rep & 1 ? 1.0f : 0.5f;
                for (int i = 0; i < MAXN + PAD; i++) {
                    rng_state = rng_state * 1664525u + 1013904223u;
                    unsigned c = (rng_state >> 24) % 8;
                    al[i] = c == 0 ? 0.0f : c == 1 ? -0.0f : c == 2 ? NAN : c == 3 ? 1.0f : frand() * 0.5f + 0.5f;
                    if (rep == 2) al[i] = 0.25f; /* every pixel visible */
                    for (int k = 0; k < 3; k++) rgb[3 * i + k] = al[i] > 0.0f ? frand() : NAN;
                    float o = frand() * 0.5f + 0.5f; /* opacity so far, [0, 1) */
                    if (c == 4) o = 0.5f;
                    if (c == 5) o = 1.0f;
                    for (int k = 0; k < 3; k++) ar[4 * i + k] = ao[4 * i + k] = frand();
                    ar[4 * i + 3] = ao[4 * i + 3] = o;
                }
                rgb[3 * (MAXN + PAD)] = 0.0f;
                int cr = vs_composite_scalar(ar + 4 * off, al + off, rgb + 3 * off, n, thr);
                int co = fn(ao + 4 * off, al + off, rgb + 3 * off, n, thr);
                if (cr != co || memcmp(ar, ao, sizeof ar) != 0) {
                    if (isa) CHECK(0, "composite %s differs from scalar at n=%d offset=%d rep %d (crossed %d vs %d)", isa, n, off, rep, cr, co);
                    return 0;
                }
                cases++;
            }
    if (isa) printf("%-13s %-7s bit-identical to scalar in %d cases\n", "composite", isa, cases);
    return 1;
}

static int composite_off(float *acc, const float *alpha, const float *rgb, int n, float thr)
{
    int c = vs_composite_scalar(acc, alpha, rgb, n, thr);
    return n > 5 ? c + (alpha[5] > 0.0f) : c;
}

/* The checks must be able to fail: versions off by one ulp in one pixel */
static void classify_off(float *alpha, float *g, const float *q, const float *qp, const float *qn, const float *qp2,
                         const float *qn2, ptrdiff_t stride, int n, const vs_shade_tabs *T)
{
    vs_classify_cd_scalar(alpha, g, q, qp, qn, qp2, qn2, stride, n, T);
    if (n > 5) g[3 * 5 + 2] = nextafterf(g[3 * 5 + 2], INFINITY);
}
static void classify_gs_off(float *alpha, float *g, const float *q4, int n, const vs_shade_tabs *T,
                            const vs_ripple_row *R)
{
    vs_classify_gs_scalar(alpha, g, q4, n, T, R);
    if (R && n > 11) g[3 * 11] = nextafterf(g[3 * 11], INFINITY);
    if (n > 5) alpha[5] = nextafterf(alpha[5], INFINITY);
}
static void shade_off(float *g, const float *alpha, const float *v, int vstride, int n, const vs_shade_tabs *T)
{
    vs_shade_lut_scalar(g, alpha, v, vstride, n, T);
    if (n > 5 && alpha[5] > 0.0f) g[3 * 5 + 1] = nextafterf(g[3 * 5 + 1], INFINITY);
}

static void shade_terms_off(float *d, float *sp, const float *g, int n, const vs_shade_tabs *T)
{
    vs_shade_terms_scalar(d, sp, g, n, T);
    if (n > 70) sp[70] = nextafterf(sp[70], INFINITY);
}
static void preint_alpha_off(float *alpha, const float *f, const float *m, const float *b, int n,
                             const vs_preint_tabs *P)
{
    vs_preint_alpha_scalar(alpha, f, m, b, n, P);
    if (n > 9) alpha[9] = nextafterf(alpha[9], INFINITY);
}

/* The dispatch honours the cap and never goes past the CPU. */
/* project_brick: random bricks (offsets in any order, counts 0..512),
 * random view matrices and tile windows, windows that keep everything
 * (+-INFINITY), and windows whose edges sit exactly on a voxel's x + px or
 * y - py, and one float past it (the comparisons are strict).  Kept indices,
 * positions and the count must equal the reference's bit for bit; outputs
 * past the count must be untouched.  Returns the number of mismatching cases. */
static int check_project(const char *isa, vs_project_brick_fn fn)
{
    enum { M = VS_PROJECT_MAX, G = 16 };
    static uint16_t vox[M], kr[M + G], ko[M + G];
    static float xr[3 * (M + G)], xo[3 * (M + G)];
    const int sizes[] = {0, 1, 2, 7, 8, 9, 15, 16, 17, 31, 33, 47, 48, 49, 63, 64, 65, 100, 255, 256, 511, 512};
    int bad = 0, cases = 0;
    for (int trial = 0; trial < 40; trial++)
        for (size_t si = 0; si < sizeof sizes / sizeof *sizes; si++) {
            const int n = sizes[si];
            for (int i = 0; i < n; i++) vox[i] = (uint16_t)((unsigned)((frand() + 1.0f) * 256.0f) & 511u);
            vs_project_in P;
            for (int r = 0; r < 3; r++) {
                P.base[r] = 300.0f * frand();
                for (int a = 0; a < 3; a++) P.m[r][a] = 3.0f * frand();
            }
            P.px = 2.0f + 4.0f * (frand() + 1.0f);
            P.py = 2.0f + 4.0f * (frand() + 1.0f);
            const int mode = trial % 4;
            if (mode == 0) { /* keep all */
                P.bx0 = P.by0 = -INFINITY;
                P.bx1 = P.by1 = INFINITY;
            } else {
                P.bx0 = P.base[0] + 40.0f * frand();
                P.bx1 = P.bx0 + 10.0f + 30.0f * (frand() + 1.0f);
                P.by0 = P.base[1] + 40.0f * frand();
                P.by1 = P.by0 + 10.0f + 30.0f * (frand() + 1.0f);
                if (mode >= 2 && n > 0) { /* an edge exactly on a voxel, or one float past it */
                    uint16_t v = vox[n / 2];
                    float di = (float)(v & 7), dj = (float)((v >> 3) & 7), dk = (float)(v >> 6);
                    float x = P.base[0] + P.m[0][0] * di + P.m[0][1] * dj + P.m[0][2] * dk;
                    float y = P.base[1] + P.m[1][0] * di + P.m[1][1] * dj + P.m[1][2] * dk;
                    P.bx0 = x + P.px;
                    P.by1 = y - P.py;
                    if (mode == 3) {
                        P.bx0 = nextafterf(P.bx0, INFINITY);
                        P.by1 = nextafterf(P.by1, -INFINITY);
                    }
                    P.bx1 = P.bx0 + 50.0f;
                    P.by0 = P.by1 - 50.0f;
                }
            }
            for (int i = 0; i < M + G; i++) kr[i] = ko[i] = 0xBEEF;
            for (int i = 0; i < 3 * (M + G); i++) xr[i] = xo[i] = -7.5f;
            int qr = vs_project_brick_scalar(vox, n, &P, kr, xr);
            int qo = fn(vox, n, &P, ko, xo);
            cases++;
            int same = qr == qo && !memcmp(kr, ko, sizeof kr) && !memcmp(xr, xo, sizeof xr);
            if (!same) {
                bad++;
                if (isa) CHECK(0, "project_brick %s: n %d trial %d: kept %d vs %d (reference)", isa, n, trial, qo, qr);
            }
        }
    if (isa) printf("project_brick %s: %d cases\n", isa, cases);
    return bad;
}

/* a deliberately wrong projection: the left window edge compared with <= */
static int project_off(const uint16_t *vox, int n, const vs_project_in *P, uint16_t *keep, float *xyz)
{
    int q = 0;
    for (int i = 0; i < n; i++) {
        const float di = (float)(vox[i] & 7), dj = (float)((vox[i] >> 3) & 7), dk = (float)(vox[i] >> 6);
        const float x = P->base[0] + P->m[0][0] * di + P->m[0][1] * dj + P->m[0][2] * dk;
        const float y = P->base[1] + P->m[1][0] * di + P->m[1][1] * dj + P->m[1][2] * dk;
        const float z = P->base[2] + P->m[2][0] * di + P->m[2][1] * dj + P->m[2][2] * dk;
        if (x + P->px <= P->bx0 || x - P->px > P->bx1 || y + P->py < P->by0 || y - P->py > P->by1) continue;
        keep[q] = (uint16_t)i;
        xyz[3 * q] = x;
        xyz[3 * q + 1] = y;
        xyz[3 * q + 2] = z;
        q++;
    }
    return q;
}

/* What the voxel kernels' checks share: column factors (random, a NaN, a
 * -0, and one exactly at the threshold times the row weight 1), row
 * factors (random, 1 and just above 1), a buffer of random floats in two
 * copies, and ns sheets at distinct unaligned places in each. */
static void voxel_case(float *cw, int npx, float *rw, int rows, float thr, float *ref, float *out, int nb, int ds, int ns,
                       float **dr, float **dout)
{
    for (int i = 0; i < VS_VOXEL1_MAX + 8; i++) cw[i] = (frand() + 1.0f) * 0.5f;
    cw[0] = NAN;
    if (npx > 2) cw[2] = -0.0f;
    cw[npx - 1] = thr; /* times rw = 1: exactly the threshold, dropped */
    for (int r = 0; r < rows; r++) rw[r] = (frand() + 1.0f) * 0.5f;
    if (rows > 1) rw[1] = 1.0f;
    if (rows > 2) rw[2] = nextafterf(1.0f, 2.0f);
    for (int i = 0; i < nb; i++) ref[i] = out[i] = frand();
    for (int sh = 0; sh < ns; sh++) {
        const int o = 3 + sh * (ds * 10 + 5) + (sh & 1) * 7;
        dr[sh] = ref + o;
        dout[sh] = out + o;
    }
}

/* splat_voxel1 (ch 1) and splat_voxel4 (ch 4): 0..9 rows, 1..8 vectors
 * (odd counts: the AVX-512 tail; for ch 4 fewer than four vectors of a
 * group), 0..6 sheets at distinct unaligned places in one buffer, row
 * weights across the threshold (products exactly at, just above and below
 * it), NaN and -0 column weights, per-channel sheet weights with a zero;
 * every float of the buffer, guards included, must equal the reference's.
 * Returns the number of mismatching cases. */
static int check_voxel(const char *isa, int ch, vs_splat_voxel1_fn ref_fn, vs_splat_voxel1_fn fn)
{
    enum { DS = 150, ROWS = 9, NB = 7 * DS * 10 + 200 };
    static float ref[NB], out[NB];
    float cw[VS_VOXEL1_MAX + 8], rw[ROWS], w[4 * 8];
    int bad = 0, cases = 0;
    for (int nvec = 1; nvec <= VS_VOXEL1_MAX / 8; nvec++)
        for (int rows = 0; rows <= ROWS; rows++)
            for (int ns = 0; ns <= 6; ns++) {
                const float thr = 0.01f;
                const int npx = 8 * nvec / ch; /* pixels a row */
                float *dr[8], *dout[8];
                voxel_case(cw, npx, rw, rows, thr, ref, out, NB, DS, ns, dr, dout);
                for (int sh = 0; sh < ns; sh++)
                    for (int c = 0; c < 4; c++) w[4 * sh + c] = c == 1 ? 0.0f : frand();
                if (ch == 1)
                    for (int sh = 0; sh < ns; sh++) w[sh] = w[4 * sh];
                ref_fn(dr, w, ns, DS, cw, rw, rows, nvec, thr);
                fn(dout, w, ns, DS, cw, rw, rows, nvec, thr);
                cases++;
                if (memcmp(ref, out, sizeof ref)) {
                    bad++;
                    if (isa)
                        CHECK(0, "splat_voxel%d %s: %d vectors, %d rows, %d sheets differ", ch, isa, nvec, rows, ns);
                }
            }
    if (isa) printf("splat_voxel%d  %s  bit-identical to scalar in %d cases\n", ch, isa, cases);
    return bad;
}

/* The gradient-splat layout (h, h dx, h dy, h) of rows x npx pixels
 * built into a block in memory, as src/block.c builds it: the route the
 * fused gradient kernels replace. */
static void gs_layout_block(float *blk, const float *cw, const float *rw, const float *dx, const float *dy, int rows,
                            int npx, float thr)
{
    for (int r = 0; r < rows; r++)
        for (int q = 0; q < npx; q++) {
            const float v = cw[q] * rw[r], h = v > thr ? v : 0.0f;
            float *b = blk + (size_t)r * 4 * npx + 4 * q;
            b[0] = h;
            b[1] = h * dx[q];
            b[2] = h * dy[r];
            b[3] = h;
        }
}

/* splat_voxel_gs: 0..9 rows, 1..9 vectors and 32 (four-vector groups and
 * their tails, the widest row), 0..6 sheets at distinct unaligned places,
 * products at and around the threshold, NaN and -0 column factors, offsets
 * of both signs and 0.  With `fn`, every float of the buffer, guards
 * included, must equal the scalar kernel's; without, the scalar kernel
 * must equal the block route it replaces: the gradient layout built into a
 * block (as vs_block_build does) and added by splat_block once a sheet.
 * Returns the number of mismatching cases. */
static int check_voxel_gs(const char *isa, vs_splat_voxel_gs_fn ref_fn, vs_splat_voxel_gs_fn fn)
{
    enum { DS = 300, ROWS = 9, NB = 7 * DS * 10 + 400 };
    static float ref[NB], out[NB], blk[ROWS * 4 * VS_VOXEL1_MAX];
    float cw[VS_VOXEL1_MAX + 8], dx[VS_VOXEL1_MAX + 8], rw[ROWS], dy[ROWS], w[4 * 8];
    int bad = 0, cases = 0;
    for (int nvec = 1; nvec <= 10; nvec++)
        for (int rows = 0; rows <= ROWS; rows++)
            for (int ns = 0; ns <= 6; ns++) {
                const int nv = nvec == 10 ? VS_VOXEL1_MAX / 2 : nvec, npx = 2 * nv;
                const float thr = 0.01f;
                float *dr[8], *dout[8];
                voxel_case(cw, npx, rw, rows, thr, ref, out, NB, DS, ns, dr, dout);
                for (int i = 0; i < VS_VOXEL1_MAX + 8; i++) dx[i] = 4.0f * frand(); /* offsets of both signs */
                if (npx > 3) dx[3] = 0.0f;
                for (int r = 0; r < rows; r++) dy[r] = 4.0f * frand();
                for (int sh = 0; sh < ns; sh++)
                    for (int c = 0; c < 4; c++) w[4 * sh + c] = c == 1 && sh == 1 ? 0.0f : frand();
                if (fn) {
                    ref_fn(dr, w, ns, DS, cw, rw, dx, dy, rows, nv, thr);
                    fn(dout, w, ns, DS, cw, rw, dx, dy, rows, nv, thr);
                } else {
                    gs_layout_block(blk, cw, rw, dx, dy, rows, npx, thr);
                    for (int sh = 0; sh < ns; sh++) {
                        const float w8[8] = {w[4 * sh],     w[4 * sh + 1], w[4 * sh + 2], w[4 * sh + 3],
                                             w[4 * sh],     w[4 * sh + 1], w[4 * sh + 2], w[4 * sh + 3]};
                        vs_splat_block_scalar(dr[sh], DS, blk, 4 * npx, rows, nv, w8);
                    }
                    ref_fn(dout, w, ns, DS, cw, rw, dx, dy, rows, nv, thr);
                }
                cases++;
                if (memcmp(ref, out, sizeof ref)) {
                    bad++;
                    if (isa)
                        CHECK(0, "splat_voxel_gs %s: %d vectors, %d rows, %d sheets differ", isa, nv, rows, ns);
                }
            }
    if (isa) printf("splat_voxel_gs %s  bit-identical to %s in %d cases\n", isa, fn ? "scalar" : "the block route", cases);
    return bad;
}

/* a deliberately wrong gradient splat: the row offset on channel 1 */
static void voxel_gs_off(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                         const float *dx, const float *dy, int rows, int nvec, float thr)
{
    (void)dx;
    for (int r = 0; r < rows; r++)
        for (int s = 0; s < ns; s++)
            for (int p = 0; p < 2 * nvec; p++) {
                const float v = cw[p] * rw[r], h = v > thr ? v : 0.0f;
                const float lay[4] = {h, h * dy[r], h * dy[r], h};
                for (int c = 0; c < 4; c++) dst[s][r * ds + 4 * p + c] += w[4 * s + c] * lay[c];
            }
}

/* splat_rows_mix: 0..9 rows, 1..9 vectors and 32, one destination at
 * unaligned places, products at and around the threshold, NaN and -0
 * column factors, offsets of both signs and 0, a matrix with zeros in
 * its gradient-splat places.  With `fn`, every float of the buffer must
 * equal the scalar kernel's; without, the scalar kernel must equal the
 * route it replaces: the gradient layout built into a block (as
 * vs_block_build_skewed does) and added by splat_block_mix.  Returns the
 * number of mismatching cases. */
static int check_rows_mix(const char *isa, vs_splat_rows_mix_fn ref_fn, vs_splat_rows_mix_fn fn)
{
    enum { DS = 300, ROWS = 9, NB = 7 * DS * 10 + 400 };
    static float ref[NB], out[NB], blk[ROWS * 4 * VS_VOXEL1_MAX];
    float cw[VS_VOXEL1_MAX + 8], dx[VS_VOXEL1_MAX + 8], rw[ROWS], dy[ROWS], m[12];
    int bad = 0, cases = 0;
    for (int nvec = 1; nvec <= 10; nvec++)
        for (int rows = 0; rows <= ROWS; rows++)
            for (int trial = 0; trial < 3; trial++) {
                const int nv = nvec == 10 ? VS_VOXEL1_MAX / 2 : nvec, npx = 2 * nv;
                const float thr = 0.01f;
                float *dr[1], *dout[1];
                voxel_case(cw, npx, rw, rows, thr, ref, out, NB, DS, 1, dr, dout);
                dr[0] += trial;
                dout[0] += trial;
                for (int i = 0; i < VS_VOXEL1_MAX + 8; i++) dx[i] = 4.0f * frand(); /* offsets of both signs */
                if (npx > 3) dx[3] = 0.0f;
                for (int r = 0; r < rows; r++) dy[r] = 4.0f * frand();
                for (int i = 0; i < 12; i++) m[i] = trial == 0 && (i == 1 || i == 2 || i == 3 || i == 6) ? 0.0f : frand();
                if (fn) {
                    ref_fn(dr[0], DS, cw, rw, dx, dy, rows, nv, thr, m);
                    fn(dout[0], DS, cw, rw, dx, dy, rows, nv, thr, m);
                } else {
                    gs_layout_block(blk, cw, rw, dx, dy, rows, npx, thr);
                    vs_splat_block_mix_scalar(dr[0], DS, blk, 4 * npx, rows, nv, m);
                    ref_fn(dout[0], DS, cw, rw, dx, dy, rows, nv, thr, m);
                }
                cases++;
                if (memcmp(ref, out, sizeof ref)) {
                    bad++;
                    if (isa) CHECK(0, "splat_rows_mix %s: %d vectors, %d rows, trial %d differ", isa, nv, rows, trial);
                }
            }
    if (isa) printf("splat_rows_mix %s  bit-identical to %s in %d cases\n", isa, fn ? "scalar" : "the block route", cases);
    return bad;
}

/* a deliberately wrong mixed splat: the terms summed in another order */
static void rows_mix_off(float *dst, ptrdiff_t ds, const float *cw, const float *rw, const float *dx, const float *dy,
                         int rows, int nvec, float thr, const float m[12])
{
    for (int r = 0; r < rows; r++)
        for (int p = 0; p < 2 * nvec; p++) {
            const float v = cw[p] * rw[r], h = v > thr ? v : 0.0f, hx = h * dx[p], hy = h * dy[r];
            for (int c = 0; c < 4; c++) dst[r * ds + 4 * p + c] += m[3 * c] * h + (m[3 * c + 1] * hx + m[3 * c + 2] * hy);
        }
}

/* a deliberately wrong voxel splat: keeps products equal to the threshold */
static void voxel1_off(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                       int rows, int nvec, float thr)
{
    for (int r = 0; r < rows; r++)
        for (int s = 0; s < ns; s++)
            for (int i = 0; i < 8 * nvec; i++) {
                const float v = cw[i] * rw[r];
                dst[s][r * ds + i] += w[s] * (v >= thr ? v : 0.0f);
            }
}

/* a deliberately wrong four-channel splat: channel 3 takes channel 2's weight */
static void voxel4_off(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                       int rows, int nvec, float thr)
{
    for (int r = 0; r < rows; r++)
        for (int s = 0; s < ns; s++)
            for (int p = 0; p < 2 * nvec; p++) {
                const float v = cw[p] * rw[r];
                const float h = v > thr ? v : 0.0f;
                for (int c = 0; c < 4; c++) dst[s][r * ds + 4 * p + c] += w[4 * s + (c == 3 ? 2 : c)] * h;
            }
}

/* place_voxels: random tiles and opacity maps (none, sparse, dense, all
 * opaque), voxel centres in and around the tile, some exactly on integer
 * pixel edges (ifloor/iceil ties) or with the footprint's reach ending on
 * one, depths before, inside and past the first slab, 0..16 voxels at
 * stride 9 (the pending-voxel record), with and without the occlusion
 * test.  The live mask and, for live lanes, every output must equal the
 * reference's bit for bit.  With `truth`, the reference itself is checked
 * against independent definitions: a brute-force count of opaque pixels,
 * vs_block_place_at and the slab tables' interpolation written out.
 * Returns the mismatching cases.  (check_slab_tables checks the tables a
 * footprint makes against the integrals in double.) */
enum { PL_TW = 70, PL_STRIDE = 9, PL_SN = 200, PL_SW = VS_MAX_SHEETS_VOXEL };
typedef struct place_fixture {
    unsigned char opaque[PL_TW * PL_TW];
    int sat[(PL_TW + 1) * (PL_TW + 1)];
    float sd[(PL_SN + 1) * PL_SW], se[(PL_SN + 1) * PL_SW];
    float colw[(VS_BLOCK_PHASES + 1) * VS_VOXEL1_MAX], roww[(VS_BLOCK_PHASES + 1) * VS_VOXEL1_MAX];
} place_fixture;

static int place_lane_same(const vs_placed *a, const vs_placed *b, int i, const vs_place_in *P)
{
    int same = a->bx[i] == b->bx[i] && a->by[i] == b->by[i] && a->qx[i] == b->qx[i] && a->qy[i] == b->qy[i] &&
               !memcmp(&a->fx[i], &b->fx[i], sizeof(float)) && !memcmp(&a->fy[i], &b->fy[i], sizeof(float));
    same &= !memcmp(a->D[i], b->D[i], (size_t)P->sw * sizeof(float));
    if (P->with_e) same &= !memcmp(a->E[i], b->E[i], (size_t)P->sw * sizeof(float));
    if (P->colw)
        same &= !memcmp(a->cw[i], b->cw[i], (size_t)(P->bx + 8) * sizeof(float)) &&
                !memcmp(a->rw[i], b->rw[i], (size_t)P->ny * sizeof(float));
    return same;
}

/* entry j of a slab table at depth z, by its definition (simd/kernels.h
 * vs_place_in): x = sscale (z - (opening slab + rz)) in [0, sn], the row
 * below x (the last but one at sn) and the next mixed by x's fraction
 * past it; in float, as the kernels must compute it */
static float slab_entry(const float *tab, const vs_place_in *P, float z, int j)
{
    const float start = (float)P->opening * P->slab + P->rz;
    float x = (z - start) * P->sscale;
    if (!(x >= 0.0f)) x = 0.0f;
    if (x > (float)P->sn) x = (float)P->sn;
    const int r = x >= (float)P->sn ? P->sn - 1 : (int)floorf(x);
    const float t0 = tab[r * P->sw + j], t1 = tab[(r + 1) * P->sw + j];
    return t0 + (x - (float)r) * (t1 - t0);
}

/* the reference against definitions that share none of its code */
static int place_truth(const place_fixture *X, const vs_place_in *P, const float *xyz, int n, unsigned live,
                       const vs_placed *o)
{
    vs_block_geom g;
    memset(&g, 0, sizeof g);
    g.rx0 = P->rx0;
    g.ry0 = P->ry0;
    g.colw = (float *)X->colw;
    g.roww = (float *)X->roww;
    g.bx = P->bx;
    g.ny = P->ny;
    int bad = 0;
    for (int i = 0; i < n; i++) {
        const float x = xyz[i * PL_STRIDE], y = xyz[i * PL_STRIDE + 1], z = xyz[i * PL_STRIDE + 2];
        int occluded = 0;
        if (P->sat) {
            int all = 1, any = 0;
            for (int py = 0; py < P->th; py++)
                for (int px = 0; px < P->tw; px++) {
                    const float cx = (float)(px + P->tx0), cy = (float)(py + P->ty0);
                    if (cx < floorf(x - P->pad_x) || cx > ceilf(x + P->pad_x) || cy < floorf(y - P->pad_y) ||
                        cy > ceilf(y + P->pad_y))
                        continue;
                    any = 1;
                    all &= X->opaque[py * P->tw + px];
                }
            occluded = !any || all;
        }
        if (occluded == !!(live >> i & 1u)) bad++;
        if (occluded) continue;
        vs_block_place pl;
        vs_block_place_at(&g, x, y, &pl);
        bad += pl.x - P->ox != o->bx[i] || pl.y - P->oy != o->by[i] || pl.qx != o->qx[i] || pl.qy != o->qy[i] ||
               pl.fx != o->fx[i] || pl.fy != o->fy[i];
        for (int j = 0; j < P->sw; j++) {
            bad += slab_entry(X->sd, P, z, j) != o->D[i][j];
            if (P->with_e) bad += slab_entry(X->se, P, z, j) != o->E[i][j];
        }
        if (P->colw) {
            float cw[VS_VOXEL1_MAX + 8], rw[VS_VOXEL1_MAX];
            vs_block_factors_ch(&g, &pl, 1, 0, P->ny, 0, P->bx / 8, cw, rw);
            bad += memcmp(cw, o->cw[i], (size_t)P->bx * sizeof(float)) != 0 ||
                   memcmp(rw, o->rw[i], (size_t)P->ny * sizeof(float)) != 0;
            for (int k = 0; k < 8; k++) bad += o->cw[i][P->bx + k] != 0.0f;
        }
    }
    return bad;
}

static int check_place(const char *isa, vs_place_voxels_fn fn, int truth)
{
    static place_fixture X;
    for (int i = 0; i < (PL_SN + 1) * PL_SW; i++) { /* in [-1, 1], uneven */
        X.sd[i] = frand();
        X.se[i] = frand();
    }
    for (size_t i = 0; i < sizeof X.colw / sizeof *X.colw; i++) {
        X.colw[i] = frand();
        X.roww[i] = frand();
    }
    float xyz[VS_PLACE_BATCH * PL_STRIDE + 4];
    int bad = 0, cases = 0;
    for (int trial = 0; trial < 400; trial++) {
        vs_place_in P;
        memset(&P, 0, sizeof P);
        P.tw = 1 + (int)((frand() + 1.0f) * 0.5f * (PL_TW - 1));
        P.th = 1 + (int)((frand() + 1.0f) * 0.5f * (PL_TW - 1));
        P.tx0 = (int)(200.0f * frand());
        P.ty0 = (int)(200.0f * frand());
        const int density = trial % 4; /* none, sparse, dense, all opaque */
        for (int i = 0; i < P.tw * P.th; i++)
            X.opaque[i] = density == 3 ? 1 : density == 0 ? 0 : (frand() + 1.0f) * 0.5f < (density == 1 ? 0.3f : 0.97f);
        const int w = P.tw + 1;
        for (int x = 0; x < w; x++) X.sat[x] = 0;
        for (int y = 0; y < P.th; y++) {
            int run = 0;
            X.sat[(y + 1) * w] = 0;
            for (int x = 0; x < P.tw; x++) {
                run += X.opaque[y * P.tw + x];
                X.sat[(y + 1) * w + x + 1] = X.sat[y * w + x + 1] + run;
            }
        }
        P.sat = trial % 5 == 4 ? NULL : X.sat;
        P.pad_x = trial % 3 == 0 ? 5.0f : 2.0f + 4.0f * (frand() + 1.0f);
        P.pad_y = trial % 3 == 0 ? 4.0f : 2.0f + 4.0f * (frand() + 1.0f);
        P.rx0 = 4.0f + 2.0f * frand();
        P.ry0 = trial % 3 == 0 ? 5.0f : 4.0f + 2.0f * frand();
        P.phases = (float)VS_BLOCK_PHASES;
        P.ox = P.tx0 - 1;
        P.oy = P.ty0 - 1;
        /* 3..64 slabs a kernel: rows of 8, 16, 24 and 64 floats */
        const float slabs[] = {1.0f, 0.5f, 0.37f, 1.7f, 0.22f, 0.064f};
        P.slab = slabs[trial % 6];
        P.rz = 2.0f;
        P.nd = (int)ceilf(2.0f * P.rz / P.slab) + 1;
        P.sw = (P.nd + 7) & ~7;
        P.sn = 1 + (int)((frand() + 1.0f) * 0.5f * (PL_SN - 1));
        P.sscale = (float)P.sn / P.slab;
        P.sd = X.sd;
        P.opening = (int)(40.0f * frand());
        if (trial % 3 != 2) { /* the derivative integrals */
            P.with_e = 1;
            P.se = X.se;
        }
        if (trial % 2) { /* and the block's factors, 1..8 vectors wide, 1..64 rows */
            P.colw = X.colw;
            P.roww = X.roww;
            P.bx = 8 * (1 + (int)((frand() + 1.0f) * 0.5f * 7.99f));
            P.ny = 1 + (int)((frand() + 1.0f) * 0.5f * (VS_VOXEL1_MAX - 1));
        }
        for (int i = 0; i < VS_PLACE_BATCH * PL_STRIDE + 4; i++) xyz[i] = 1e30f; /* guards between records */
        for (int i = 0; i < VS_PLACE_BATCH; i++) {
            float *c = xyz + i * PL_STRIDE;
            c[0] = (float)P.tx0 + (frand() + 1.0f) * 0.5f * ((float)P.tw + 2.0f * P.pad_x + 6.0f) - P.pad_x - 3.0f;
            c[1] = (float)P.ty0 + (frand() + 1.0f) * 0.5f * ((float)P.th + 2.0f * P.pad_y + 6.0f) - P.pad_y - 3.0f;
            if (i % 5 == 1) c[0] = floorf(c[0]); /* on a pixel edge */
            if (i % 5 == 2) c[1] = floorf(c[1]) + P.pad_y; /* reach ends on one */
            /* kernels that start before, inside and past the first slab,
             * some on a table row */
            c[2] = ((float)P.opening + 0.5f * (frand() + 1.0f)) * P.slab + P.rz + 0.7f * frand();
            if (i % 7 == 3) c[2] = (float)P.opening * P.slab + P.rz + (float)(i % 3) / P.sscale;
        }
        for (int n = 0; n <= VS_PLACE_BATCH; n++) {
            vs_placed ro, oo;
            memset(&ro, 0xA5, sizeof ro);
            memset(&oo, 0x5A, sizeof oo);
            const unsigned lr = vs_place_voxels_scalar(xyz, PL_STRIDE, n, &P, &ro);
            const unsigned lo = fn(xyz, PL_STRIDE, n, &P, &oo);
            int same = lr == lo && lr >> n == 0;
            for (int i = 0; same && i < n; i++)
                if (lr >> i & 1u) same = place_lane_same(&ro, &oo, i, &P);
            if (truth) same &= place_truth(&X, &P, xyz, n, lr, &ro) == 0;
            cases++;
            if (!same) {
                bad++;
                if (isa) CHECK(0, "place_voxels %s: trial %d, %d voxels: live %#x vs %#x (reference)", isa, trial, n, lo, lr);
            }
        }
    }
    if (isa) printf("place_voxels  %-7s bit-identical to scalar in %d cases\n", isa, cases);
    return bad;
}

/* a deliberately wrong activation: a voxel counts as occluded one pixel
 * short of its reach on the right */
static unsigned place_off(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out)
{
    vs_place_in Q = *P;
    unsigned live = vs_place_voxels_scalar(xyz, stride, n, P, out);
    if (!P->sat) return live;
    Q.pad_x -= 1.0f;
    vs_placed tmp;
    const unsigned short_reach = vs_place_voxels_scalar(xyz, stride, n, &Q, &tmp);
    return live & short_reach;
}

/* a kernel that leaves the kernel's depth radius out of where its first
 * slab starts */
static unsigned place_slab_off(const float *xyz, int stride, int n, const vs_place_in *P, vs_placed *out)
{
    vs_place_in Q = *P;
    Q.rz = 0.0f;
    return vs_place_voxels_scalar(xyz, stride, n, &Q, out);
}

static void check_dispatch(void)
{
    vs_isa best = vs_isa_detect();
    for (int cap = VS_ISA_SCALAR; cap <= VS_ISA_AVX512; cap++) {
        vs_kernels k;
        vs_kernels_init(&k, (vs_isa)cap);
        vs_isa want = (vs_isa)cap > best ? best : (vs_isa)cap;
        CHECK(k.isa == want, "cap %s gave %s, expected %s", vs_isa_name((vs_isa)cap), vs_isa_name(k.isa),
              vs_isa_name(want));
        CHECK(k.splat_row1 && k.splat_row4 && k.composite && k.splat_block && k.splat_block_mix &&
                  k.classify_cd && k.classify_gs && k.shade_lut && k.shade_terms && k.preint_alpha &&
                  k.splat_voxel1 && k.splat_voxel4 &&
                  k.splat_voxel_gs && k.splat_rows_mix && k.project_brick && k.place_voxels,
              "cap %s: empty entry",
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
    static shade_fixture fx;
    fixture_init(&fx);
    check_cd_reference(&fx);
    CHECK(!check_classify(NULL, classify_off, &fx), "check_classify cannot tell a wrong kernel from the reference");
    CHECK(!check_classify_gs(NULL, classify_gs_off, &fx),
          "check_classify_gs cannot tell a wrong kernel from the reference");
    check_ripple_reference(&fx);
    CHECK(!check_shade(NULL, shade_off, &fx), "check_shade cannot tell a wrong kernel from the reference");
    CHECK(!check_shade_terms(NULL, shade_terms_off, &fx),
          "check_shade_terms cannot tell a wrong kernel from the reference");
    CHECK(!check_preint_alpha(NULL, preint_alpha_off),
          "check_preint_alpha cannot tell a wrong kernel from the reference");
    CHECK(!check_composite(NULL, composite_off), "check_composite cannot tell a wrong kernel from the reference");
    CHECK(check_block_mix(NULL, block_mix_off), "check_block_mix cannot tell a wrong kernel from the reference");
    CHECK(check_project(NULL, project_off), "check_project cannot tell a wrong kernel from the reference");
    CHECK(check_voxel(NULL, 1, vs_splat_voxel1_scalar, voxel1_off),
          "check_voxel cannot tell a wrong kernel from the reference");
    CHECK(check_voxel(NULL, 4, vs_splat_voxel4_scalar, voxel4_off),
          "check_voxel (4 channels) cannot tell a wrong kernel from the reference");
    check_voxel_gs("scalar", vs_splat_voxel_gs_scalar, NULL);
    CHECK(check_voxel_gs(NULL, vs_splat_voxel_gs_scalar, voxel_gs_off),
          "check_voxel_gs cannot tell a wrong kernel from the reference");
    check_rows_mix("scalar", vs_splat_rows_mix_scalar, NULL);
    CHECK(check_rows_mix(NULL, vs_splat_rows_mix_scalar, rows_mix_off),
          "check_rows_mix cannot tell a wrong kernel from the reference");
    CHECK(check_place(NULL, vs_place_voxels_scalar, 1) == 0,
          "place_voxels scalar reference disagrees with the brute-force occlusion, vs_block_place_at or the slab tables");
    CHECK(check_place(NULL, place_off, 0) > 0, "check_place cannot tell a wrong kernel from the reference");
    CHECK(check_place(NULL, place_slab_off, 0) > 0, "check_place cannot tell wrong depth integrals from the reference");
    if (best >= VS_ISA_SSE4) {
        check_row4("sse4", vs_splat_row4_sse4);
        check_block("sse4", vs_splat_block_sse4);
        check_block_mix("sse4", vs_splat_block_mix_sse4);
    } else {
        printf("SKIP: sse4 kernels: this CPU has no SSE4.1\n");
    }
    if (best >= VS_ISA_AVX2) {
        check_row4("avx2", vs_splat_row4_avx2);
        check_block("avx2", vs_splat_block_avx2);
        check_block_mix("avx2", vs_splat_block_mix_avx2);
        check_classify("avx2", vs_classify_cd_avx2, &fx);
        check_classify_gs("avx2", vs_classify_gs_avx2, &fx);
        check_shade("avx2", vs_shade_lut_avx2, &fx);
        check_shade_terms("avx2", vs_shade_terms_avx2, &fx);
        check_preint_alpha("avx2", vs_preint_alpha_avx2);
        check_composite("avx2", vs_composite_avx2);
        check_project("avx2", vs_project_brick_avx2);
        check_voxel("avx2", 1, vs_splat_voxel1_scalar, vs_splat_voxel1_avx2);
        check_voxel("avx2", 4, vs_splat_voxel4_scalar, vs_splat_voxel4_avx2);
        check_voxel_gs("avx2", vs_splat_voxel_gs_scalar, vs_splat_voxel_gs_avx2);
        check_rows_mix("avx2", vs_splat_rows_mix_scalar, vs_splat_rows_mix_avx2);
        check_place("avx2", vs_place_voxels_avx2, 0);
    } else {
        printf("SKIP: avx2 kernels: this CPU has no AVX2\n");
    }
    if (best >= VS_ISA_AVX512) {
        check_row4("avx512", vs_splat_row4_avx512);
        check_block("avx512", vs_splat_block_avx512);
        check_project("avx512", vs_project_brick_avx512);
        check_voxel("avx512", 1, vs_splat_voxel1_scalar, vs_splat_voxel1_avx512);
        check_place("avx512", vs_place_voxels_avx512, 0);
    } else {
        printf("SKIP: avx512 kernels: this CPU has no AVX-512\n");
    }
    TEST_DONE();
}
