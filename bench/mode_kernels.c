/* vsplat-bench kernels: one function at a time (like zstd's fullbench).
 * Every SIMD kernel of simd/kernels.h against the scalar reference, on each
 * ISA this CPU has, at footprint-row lengths that occur in practice (a
 * footprint of radius 2 voxels spans ~9 pixels at 512^2 on a 181^3 head) and
 * longer ones; then the machine's measured peak FMA rate for scale; then the
 * rasterize stage of a real frame per ISA (interleaved runs, medians). */
#include "bench.h"
#include "kernels.h"
#include "roof.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>


typedef struct kernel_entry {
    const char *kernel;
    vs_isa isa;
    int kind; /* 0 row1, 1 row4, 3 composite, 4 footprint block, 5 classify_cd, 6 shade_lut, 7 classify_gs,
                 8 gradient-splat block (mixing), 9 project_brick (8n voxels),
                 10 splat_voxel1, 11 splat_voxel4 (8 rows of 8/64 floats into 4 sheets),
                 12 place_voxels (n voxels in batches of 16),
                 13 splat_voxel_gs (as splat_voxel4, with the gradient layout),
                 14 splat_rows_mix (8 rows of the gradient layout, mixed, into one sheet),
                 15 shade_terms (n dense gradients), 16 preint_alpha (n segments in two halves),
                 17 classify_cd with the four-point stencils within and across sheets (1/12) */
    void *fn;
} kernel_entry;

/* Footprint blocks: 8 rows of n floats (n rounded down to whole 8-float
 * vectors, at least one) into a sheet row stride of 200 floats. */
enum { BLOCK_ROWS = 8, BLOCK_DS = 200, SHEET_STEP = BLOCK_ROWS * BLOCK_DS + 64 /* splat_voxel1: 4 sheets */ };
static int block_nvec(int n) { return n < 8 ? 1 : n / 8; }

/* Post-shaded sheet kernels: a density sheet of 5 rows of SHEET_S floats
 * (and the sheets before and after) with values across the opacity ramp,
 * gradients of random direction (pessimistic for the table gathers: on a
 * real sheet neighbours have similar normals), a third of the pixels
 * visible, and synthetic tables of the real sizes (nl = 64). */
enum { SHEET_S = 256, SHADE_NL = 64, SHADE_NP = SHADE_NL / 2 + 1 };
typedef struct shade_bench {
    float q[5 * SHEET_S], qp[3 * SHEET_S], qn[3 * SHEET_S], alpha[SHEET_S], g[3 * SHEET_S], g0[3 * SHEET_S];
    float atab[VS_KTAB], color[3 * VS_KTAB], diffuse[SHADE_NP * SHADE_NL], specular[SHADE_NP * SHADE_NL];
    uint16_t lambda_bin[255 * 255 + 2], phi_bin[255 * 181 + 2];
    uint8_t radius[255 * 255 + 4];
    vs_shade_tabs T, T4; /* T4: T with the four-point stencil */
    /* project_brick: a brick's offsets in the order the list stores them,
     * a 45-degree view, a window that keeps about a third of the voxels */
    uint16_t vox[VS_PROJECT_MAX], keep[VS_PROJECT_MAX];
    float xyz[3 * VS_PROJECT_MAX];
    vs_project_in P;
    /* place_voxels: a 64 x 64 tile whose left half is opaque, voxels
     * across it (a third culled), five slabs from a 257-row slab table */
    int sat[65 * 65];
    float pend[VS_PLACE_BATCH * 9], depth[257 * 8];
    vs_place_in PL;
    vs_placed placed;
    /* preint_alpha: a random 256 x 256 table over the sheets' values */
    vs_preint_tabs PT;
} shade_bench;

static float preint_table[4 * 256 * 256] __attribute__((aligned(64)));

static void shade_bench_init(shade_bench *B)
{
    unsigned st = 12345u;
#define RND() (st = st * 1664525u + 1013904223u, (float)(st >> 8) / 16777216.0f)
    for (int i = 0; i < 3 * SHEET_S; i++) {
        B->q[i] = 40.0f + 20.0f * RND();
        B->qp[i] = 40.0f + 20.0f * RND();
        B->qn[i] = 40.0f + 20.0f * RND();
    }
    /* a third visible, in runs of 8 (on the head ~26 % of the pixels of a shaded span are) */
    for (int i = 0; i < SHEET_S; i++) B->alpha[i] = (i % 24) < 8 ? 0.05f : 0.0f;
    for (int i = 0; i < 3 * SHEET_S; i++) B->g0[i] = RND() * 2.0f - 1.0f;
    for (int i = 0; i < VS_KTAB; i++) B->atab[i] = i < 2000 ? 0.0f : (float)(i - 2000) / 2095.0f;
    for (int i = 0; i < 3 * VS_KTAB; i++) B->color[i] = RND();
    for (int i = 0; i < SHADE_NP * SHADE_NL; i++) {
        B->diffuse[i] = RND();
        B->specular[i] = RND();
    }
    memset(B->lambda_bin, 0, sizeof B->lambda_bin);
    memset(B->radius, 0, sizeof B->radius);
    memset(B->phi_bin, 0, sizeof B->phi_bin);
    for (int i = 0; i < 255 * 255; i++) {
        B->lambda_bin[i] = (uint16_t)(RND() * SHADE_NL);
        B->radius[i] = (uint8_t)(RND() * 181);
    }
    for (int i = 0; i < 255 * 181; i++) B->phi_bin[i] = (uint16_t)(RND() * SHADE_NP);
    for (int i = 0; i < 4 * 256 * 256; i++) preint_table[i] = RND();
#undef RND
    B->PT = (vs_preint_tabs){preint_table, 0.0f, 255.0f / 100.0f, 256, 0.0f};
    for (int i = 0; i < VS_PROJECT_MAX; i++) B->vox[i] = (uint16_t)i;
    const float c = 1.6f, sn = 1.6f; /* 2.26 px per voxel, turned 45 degrees */
    B->P = (vs_project_in){.base = {100.0f, 100.0f, 50.0f},
                           .m = {{c, 0.0f, sn}, {0.0f, 2.26f, 0.0f}, {-sn, 0.0f, c}},
                           .px = 5.5f, .py = 5.5f, .bx0 = 90.0f, .bx1 = 113.0f, .by0 = 80.0f, .by1 = 100.0f};
    for (int y = 0; y <= 64; y++)
        for (int x = 0; x <= 64; x++) B->sat[y * 65 + x] = y * (x < 32 ? x : 32);
    for (int i = 0; i < 257 * 8; i++) B->depth[i] = (float)(i % 8 < 5) * (float)(i / 8) / 256.0f;
    for (int i = 0; i < VS_PLACE_BATCH; i++) {
        B->pend[9 * i] = 100.0f + 4.1f * (float)i;
        B->pend[9 * i + 1] = 120.0f + 2.3f * (float)(i % 7);
        B->pend[9 * i + 2] = 12.5f + 0.13f * (float)i;
    }
    B->PL = (vs_place_in){.sat = B->sat, .tx0 = 96, .ty0 = 96, .tw = 64, .th = 64, .pad_x = 5.5f, .pad_y = 5.5f,
                          .rx0 = 4.8f, .ry0 = 4.8f, .phases = 256.0f, .ox = 95, .oy = 95, .slab = 1.0f, .rz = 2.0f,
                          .sd = B->depth, .sscale = 256.0f, .sn = 256, .sw = 8, .opening = 10, .nd = 5};
    B->T = (vs_shade_tabs){.vmin = 0.0, .scale = 4095.0 / 100.0, .alpha = B->atab, .color = B->color,
                           .slab = 0.5f, .two_slab = 1.0f, .ppm = 1.0f, .zpm = 1.0f, .nl = SHADE_NL,
                           .lambda_bin = B->lambda_bin, .radius = B->radius, .phi_bin = B->phi_bin,
                           .diffuse = B->diffuse, .specular = B->specular};
    B->T4 = B->T;
    B->T4.cd_wide = B->T4.cd_wide_z = 1.0f / 12.0f;
    for (int i = 3 * SHEET_S; i < 5 * SHEET_S; i++) B->q[i] = B->q[i - 3 * SHEET_S]; /* the stencil's rows */
}

/* Time `reps` calls over a buffer of rows; returns ns per element. */
static double time_kernel(const kernel_entry *k, int n, float *buf, float *ex, float *alpha, float *rgb,
                          shade_bench *B, long reps)
{
    const float w4[4] = {0.25f, 0.5f, 0.75f, 1.0f};
    const float w8[8] = {0.25f, 0.5f, 0.75f, 1.0f, 0.25f, 0.5f, 0.75f, 1.0f};
    double best = 1e30;
    for (int trial = 0; trial < 5; trial++) {
        double t0 = bench_now_ms();
        for (long r = 0; r < reps; r++) {
            int off = (int)(r & 63); /* unaligned, moving starts like real rows */
            switch (k->kind) {
            case 0: ((void (*)(float *, const float *, float, int))k->fn)(buf + off, ex + off, 1e-3f, n); break;
            case 1:
                ((void (*)(float *, const float *, const float *, int))k->fn)(buf + 4 * off, ex + off, w4, n);
                break;
            case 4:
                ((vs_splat_block_fn)k->fn)(buf + off, BLOCK_DS, ex, 8 * block_nvec(n), BLOCK_ROWS, block_nvec(n), w8);
                break;
            case 8: {
                const float m[12] = {0.5f, 0, 0, 0, -0.3f, 0.1f, 0, 0.2f, -0.4f, 0.25f, 0.1f, 0.05f};
                ((void (*)(float *, ptrdiff_t, const float *, ptrdiff_t, int, int, const float *))k->fn)(
                    buf + off, BLOCK_DS, ex, 8 * block_nvec(n), BLOCK_ROWS, block_nvec(n), m);
            } break;
            case 5:
                ((vs_classify_cd_fn)k->fn)(B->alpha + off, B->g + 3 * off, B->q + SHEET_S + 1 + off,
                                           B->qp + SHEET_S + 1 + off, B->qn + SHEET_S + 1 + off, NULL, NULL, SHEET_S,
                                           n, &B->T);
                break;
            case 17: /* two rows and two pixels each side, and two sheets (qp, qn read again) */
                ((vs_classify_cd_fn)k->fn)(B->alpha + off, B->g + 3 * off, B->q + 2 * SHEET_S + 2 + off,
                                           B->qp + SHEET_S + 1 + off, B->qn + SHEET_S + 1 + off,
                                           B->qn + 2 * SHEET_S + off, B->qp + 2 * SHEET_S + off, SHEET_S, n, &B->T4);
                break;
            case 6:
                /* shading overwrites the gradients: restore them now and then (a copy per call would
                 * dominate); the values stay in range either way */
                if ((r & 1023) == 0) memcpy(B->g, B->g0, sizeof B->g);
                ((vs_shade_lut_fn)k->fn)(B->g + 3 * off, B->alpha + off, B->q + off, 1, n, &B->T);
                break;
            case 10: {
                float *d4[4] = {buf + off, buf + off + SHEET_STEP, buf + off + 2 * SHEET_STEP, buf + off + 3 * SHEET_STEP};
                const float w4s[4] = {0.25f, 0.5f, 0.75f, 1.0f};
                ((vs_splat_voxel1_fn)k->fn)(d4, w4s, 4, BLOCK_DS, ex, ex + 64, BLOCK_ROWS, block_nvec(n), 1e-6f);
            } break;
            case 11: {
                float *d4[4] = {buf + off, buf + off + SHEET_STEP, buf + off + 2 * SHEET_STEP, buf + off + 3 * SHEET_STEP};
                const float w16[16] = {0.25f, 0.5f, 0.75f, 1.0f, 0.2f, 0.4f, 0.6f, 0.8f,
                                       0.1f,  0.3f, 0.5f,  0.7f, 0.9f, 0.8f, 0.7f, 0.6f};
                ((vs_splat_voxel1_fn)k->fn)(d4, w16, 4, BLOCK_DS, ex, ex + 64, BLOCK_ROWS, block_nvec(n), 1e-6f);
            } break;
            case 13: {
                float *d4[4] = {buf + off, buf + off + SHEET_STEP, buf + off + 2 * SHEET_STEP, buf + off + 3 * SHEET_STEP};
                const float w16[16] = {0.25f, -0.5f, 0.75f, 0.1f, 0.2f, -0.4f, 0.6f, 0.08f,
                                       0.1f,  -0.3f, 0.5f, 0.07f, 0.9f, -0.8f, 0.7f, 0.06f};
                static const float dxy[32] = {-3.5f, -2.5f, -1.5f, -0.5f, 0.5f, 1.5f, 2.5f, 3.5f, 4.5f, 5.5f, 6.5f,
                                              7.5f,  8.5f,  9.5f,  10.5f, 11.5f, 0, 0, 0, 0, 0, 0, 0, 0,
                                              -3.2f, -2.2f, -1.2f, -0.2f, 0.8f, 1.8f, 2.8f, 3.8f};
                ((vs_splat_voxel_gs_fn)k->fn)(d4, w16, 4, BLOCK_DS, ex, ex + 64, dxy, dxy + 24, BLOCK_ROWS,
                                              block_nvec(n), 1e-6f);
            } break;
            case 14: {
                static const float dxy[32] = {-3.5f, -2.5f, -1.5f, -0.5f, 0.5f, 1.5f, 2.5f, 3.5f, 4.5f, 5.5f, 6.5f,
                                              7.5f,  8.5f,  9.5f,  10.5f, 11.5f, 0, 0, 0, 0, 0, 0, 0, 0,
                                              -3.2f, -2.2f, -1.2f, -0.2f, 0.8f, 1.8f, 2.8f, 3.8f};
                static const float m[12] = {0.5f, 0, 0, 0, -0.3f, 0.01f, 0, 0.02f, -0.3f, 0.1f, -0.05f, 0.04f};
                ((vs_splat_rows_mix_fn)k->fn)(buf + off, BLOCK_DS, ex, ex + 64, dxy, dxy + 24, BLOCK_ROWS,
                                              block_nvec(n), 1e-6f, m);
            } break;
            case 15:
                ((vs_shade_terms_fn)k->fn)(buf + off, buf + 256 + off, B->g0 + 3 * off, n, &B->T);
                break;
            case 16:
                ((vs_preint_alpha_fn)k->fn)(buf + off, B->q + off, B->qp + off, B->qn + off, n, &B->PT);
                break;
            case 12:
                for (int b = 0; b < n; b += VS_PLACE_BATCH) {
                    volatile unsigned live = ((vs_place_voxels_fn)k->fn)(
                        B->pend, 9, n - b < VS_PLACE_BATCH ? n - b : VS_PLACE_BATCH, &B->PL, &B->placed);
                    (void)live;
                }
                break;
            case 9: {
                volatile int kept = ((vs_project_brick_fn)k->fn)(B->vox, 8 * n, &B->P, B->keep, B->xyz);
                (void)kept;
            } break;
            case 7:
                /* the sheet rows as (density, gx, gy, gz) pixels */
                ((vs_classify_gs_fn)k->fn)(B->alpha + off, B->g + 3 * off, B->q + 4 * off, n, &B->T, NULL);
                break;
            default:
                if ((r & 1023) == 0) memset(buf, 0, (size_t)(4 * (64 + n)) * sizeof(float));
                ((int (*)(float *, const float *, const float *, int, float))k->fn)(buf + 4 * off, alpha + off,
                                                                                  rgb + 3 * off, n, 0.99f);
            }
        }
        double ms = bench_now_ms() - t0;
        if (ms < best) best = ms;
    }
    double elems = k->kind == 4 || k->kind == 8 || k->kind == 14 ? 8.0 * block_nvec(n) * BLOCK_ROWS : k->kind == 9 ? 8.0 * n : k->kind == 10 || k->kind == 11 || k->kind == 13 ? 4.0 * 8.0 * block_nvec(n) * BLOCK_ROWS
                                                                               : n;
    return best * 1e6 / ((double)reps * elems);
}

int bench_kernels(const bench_opts *o)
{
    const vs_isa best = vs_isa_detect();
    const kernel_entry all[] = {
        {"splat_row1", VS_ISA_SCALAR, 0, (void *)vs_splat_row1_scalar},
        {"splat_row4", VS_ISA_SCALAR, 1, (void *)vs_splat_row4_scalar},
        {"splat_row4", VS_ISA_SSE4, 1, (void *)vs_splat_row4_sse4},
        {"splat_row4", VS_ISA_AVX2, 1, (void *)vs_splat_row4_avx2},
        {"splat_row4", VS_ISA_AVX512, 1, (void *)vs_splat_row4_avx512},
        {"composite", VS_ISA_SCALAR, 3, (void *)vs_composite_scalar},
        {"composite", VS_ISA_AVX2, 3, (void *)vs_composite_avx2},
        {"splat_block", VS_ISA_SCALAR, 4, (void *)vs_splat_block_scalar},
        {"splat_block", VS_ISA_SSE4, 4, (void *)vs_splat_block_sse4},
        {"splat_block", VS_ISA_AVX2, 4, (void *)vs_splat_block_avx2},
        {"splat_block", VS_ISA_AVX512, 4, (void *)vs_splat_block_avx512},
        {"splat_block_mix", VS_ISA_SCALAR, 8, (void *)vs_splat_block_mix_scalar},
        {"splat_block_mix", VS_ISA_SSE4, 8, (void *)vs_splat_block_mix_sse4},
        {"splat_block_mix", VS_ISA_AVX2, 8, (void *)vs_splat_block_mix_avx2},
        {"classify_cd", VS_ISA_SCALAR, 5, (void *)vs_classify_cd_scalar},
        {"classify_cd", VS_ISA_AVX2, 5, (void *)vs_classify_cd_avx2},
        {"classify_cd4", VS_ISA_SCALAR, 17, (void *)vs_classify_cd_scalar},
        {"classify_cd4", VS_ISA_AVX2, 17, (void *)vs_classify_cd_avx2},
        {"classify_gs", VS_ISA_SCALAR, 7, (void *)vs_classify_gs_scalar},
        {"classify_gs", VS_ISA_AVX2, 7, (void *)vs_classify_gs_avx2},
        {"shade_lut", VS_ISA_SCALAR, 6, (void *)vs_shade_lut_scalar},
        {"shade_lut", VS_ISA_AVX2, 6, (void *)vs_shade_lut_avx2},
        {"shade_terms", VS_ISA_SCALAR, 15, (void *)vs_shade_terms_scalar},
        {"shade_terms", VS_ISA_AVX2, 15, (void *)vs_shade_terms_avx2},
        {"preint_alpha", VS_ISA_SCALAR, 16, (void *)vs_preint_alpha_scalar},
        {"preint_alpha", VS_ISA_AVX2, 16, (void *)vs_preint_alpha_avx2},
        {"splat_voxel1", VS_ISA_SCALAR, 10, (void *)vs_splat_voxel1_scalar},
        {"splat_voxel1", VS_ISA_AVX2, 10, (void *)vs_splat_voxel1_avx2},
        {"splat_voxel1", VS_ISA_AVX512, 10, (void *)vs_splat_voxel1_avx512},
        {"splat_voxel4", VS_ISA_SCALAR, 11, (void *)vs_splat_voxel4_scalar},
        {"splat_voxel4", VS_ISA_AVX2, 11, (void *)vs_splat_voxel4_avx2},
        {"splat_voxel_gs", VS_ISA_SCALAR, 13, (void *)vs_splat_voxel_gs_scalar},
        {"splat_voxel_gs", VS_ISA_AVX2, 13, (void *)vs_splat_voxel_gs_avx2},
        {"splat_rows_mix", VS_ISA_SCALAR, 14, (void *)vs_splat_rows_mix_scalar},
        {"splat_rows_mix", VS_ISA_AVX2, 14, (void *)vs_splat_rows_mix_avx2},
        {"project_brick", VS_ISA_SCALAR, 9, (void *)vs_project_brick_scalar},
        {"project_brick", VS_ISA_AVX2, 9, (void *)vs_project_brick_avx2},
        {"project_brick", VS_ISA_AVX512, 9, (void *)vs_project_brick_avx512},
        {"place_voxels", VS_ISA_SCALAR, 12, (void *)vs_place_voxels_scalar},
        {"place_voxels", VS_ISA_AVX2, 12, (void *)vs_place_voxels_avx2},
        {"place_voxels", VS_ISA_AVX512, 12, (void *)vs_place_voxels_avx512},
    };
    const int lengths[] = {9, 64};
    const int nmax = 64 + 64 + 8;
    /* rows of 4 channels, or BLOCK_ROWS sheet rows of a block */
    const size_t nbuf = (size_t)4 * SHEET_STEP + 64 > (size_t)nmax * 4 ? (size_t)4 * SHEET_STEP + 64 : (size_t)nmax * 4;
    float *buf = calloc(nbuf, sizeof(float)), *ex = malloc((size_t)8 * nmax * sizeof(float));
    float *alpha = malloc((size_t)nmax * sizeof(float));
    float *rgb = malloc(((size_t)nmax * 3 + 1) * sizeof(float));
    shade_bench *B = malloc(sizeof *B);
    if (!buf || !ex || !alpha || !rgb || !B) {
        fprintf(stderr, "kernels: out of memory\n");
        return 1;
    }
    for (int i = 0; i < 8 * nmax; i++) ex[i] = expf(-0.05f * (float)(i % 9)); /* also the blocks */
    for (int i = 0; i < nmax; i++) {
        ex[i] = expf(-0.05f * (float)(i % 9));
        alpha[i] = (i % 3) ? 0.05f : 0.0f;
    }
    for (int i = 0; i < 3 * nmax + 1; i++) rgb[i] = 0.5f;
    shade_bench_init(B);
    long reps = o->quick ? 200000 : 2000000;
    FILE *csv = bench_results_dir(o) == 0 ? bench_result_open(o, "kernels.csv") : NULL;
    if (csv) fprintf(csv, "kernel,isa,n,ns_per_element,speedup_vs_scalar\n");
    printf("kernel           isa      n=9 ns/elem  x scalar   n=64 ns/elem  x scalar"
           "   (splat_block, splat_block_mix, splat_rows_mix: 8 rows of 8 / 64 floats)\n");
    double scalar_ns[2] = {0, 0};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) {
        const kernel_entry *k = &all[i];
        if (k->isa > best) {
            printf("%-16s %-8s skipped: this CPU has no %s\n", k->kernel, vs_isa_name(k->isa), vs_isa_name(k->isa));
            continue;
        }
        printf("%-16s %-8s", k->kernel, vs_isa_name(k->isa));
        for (int l = 0; l < 2; l++) {
            double ns = time_kernel(k, lengths[l], buf, ex, alpha, rgb, B, reps);
            if (k->isa == VS_ISA_SCALAR) scalar_ns[l] = ns;
            double sp = scalar_ns[l] > 0 ? scalar_ns[l] / ns : 0;
            printf("   %8.3f    %5.2fx", ns, sp);
            if (csv) fprintf(csv, "%s,%s,%d,%.4f,%.3f\n", k->kernel, vs_isa_name(k->isa), lengths[l], ns, sp);
        }
        printf("\n");
    }
    if (best >= VS_ISA_AVX2) {
        double gf = bench_peak_gflops(VS_ISA_AVX2, 1, o->quick);
        printf("peak FMA rate (AVX2, %d chains): %.1f GFLOP/s per core; a row1 element is 2 flops\n", ROOF_CHAINS, gf);
        if (csv) fprintf(csv, "peak_fma_gflops,avx2,0,%.2f,0\n", gf);
    }
    if (csv) fclose(csv);
    free(buf);
    free(ex);
    free(alpha);
    free(rgb);
    free(B);

    /* the rasterize stage of a real frame per ISA */
    vs_volume *vol = NULL;
    const char *key = "colin27";
    int lr = bench_load(o, key, &vol);
    if (lr != 0) {
        key = "scene:sphere:128";
        if (bench_load(o, key, &vol) != 0) return lr < 0 ? 1 : 0;
    }
    bench_case cases[4];
    int nc = 0;
    for (vs_isa isa = VS_ISA_SCALAR; isa <= best && nc < 4; isa = (vs_isa)(isa + 1)) {
        vs_settings s;
        vs_settings_init(&s);
        s.lod_pixels = 0;
        s.width = s.height = o->quick ? 256 : 512;
        s.azimuth = 180;
        s.threads = 1;
        s.isa = isa;
        if (!strcmp(key, "colin27")) {
            s.has_iso = 1;
            s.iso_lo = 45;
            s.ramp = 10;
        }
        char name[64];
        snprintf(name, sizeof name, "%s post-cd %s", key, vs_isa_name(isa));
        bench_case_set(&cases[nc++], name, vol, &s);
    }
    int runs = bench_runs(o, 7, 3);
    int failed = bench_run("kernels", cases, nc, runs);
    printf("\n%-32s %12s %12s %12s\n", "frame (1 thread)", "rasterize", "x scalar", "total");
    bench_summary base = bench_summarize(&cases[0], bench_m_raster);
    for (int c = 0; c < nc; c++) {
        if (cases[c].failed) continue;
        bench_summary r = bench_summarize(&cases[c], bench_m_raster), t = bench_summarize(&cases[c], bench_m_total);
        printf("%-32s %9.1f ms %11.2fx %9.1f ms\n", cases[c].name, r.median, base.median / r.median, t.median);
    }
    bench_cases_free(cases, nc);
    bench_contexts_release();
    vs_volume_release(vol);
    return failed ? 1 : 0;
}
