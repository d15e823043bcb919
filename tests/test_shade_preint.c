/* Pre-integrated shading (src/shade_preint.c) on random sheets, post-cd
 * and post-gs, exact normals and the normal LUT, orthographic and
 * perspective, in a tile laid out as the renderer lays it (apron, rows
 * longer than a chunk of 64 pixels, uneven spans, a slab that is not a
 * power of two, a frame base):
 * - each live pixel's colour equals the formula of a segment in two halves
 *   (preintegrate.h) evaluated one pixel at a time with the scalar
 *   references (vs_preint_cell, vs_preint_bilerp, the light model or the
 *   scalar LUT kernel), bit for bit;
 * - the terms it keeps for sheet k + 1 (shade_buf.term) are exact: sheet
 *   k + 1 shaded after sheet k gives bit for bit what it gives shaded
 *   alone, also at a pixel not live at sheet k, whose stored terms are
 *   older and must not be taken.
 * Post-cd also with the four-point in-sheet stencil (weights 1/12 and a
 * mix) and the two-pixel tile seam it takes. */
#include "testutil.h"
#include "classify.h"
#include "frame.h"
#include "light.h"
#include "preintegrate.h"
#include "shade.h"
#include "shade_lut.h"
#include "sheet_classify.h"
#include "tile.h"

#include <float.h>
#include <limits.h>

/* buffers sized for the widest seam (2) */
enum { TW = 150, TH = 9, SW = TW + 4, SH = TH + 4, STRIDE = SW + 2 * VS_APRON, NS = 6 };

static vs_context *ctx;
static uint64_t rng = 0x9E3779B97F4A7C15ull;

typedef struct rig {
    vs_frame F;
    vs_settings s;
    tile_ctx t;
    vs_shade_tabs tabs;
    int xa[SH], xb[SH];
    spans sp;
    float *sheet[NS]; /* ch floats a buffer pixel */
    float alpha[TW * TH], g[TW * TH * 3 + 1], term[TW * TH * 2];
    int term_k[TW * TH];
    int ch;
} rig;

static const float *at(const rig *R, int k)
{
    return R->sheet[k] + VS_APRON * R->ch;
}

static sheet_view view(rig *R, int k)
{
    return (sheet_view){.k = k, .q = at(R, k), .prev = at(R, k - 1), .next = at(R, k + 1),
                        .next2 = R->ch == 1 ? at(R, k + 2) : NULL, .sp = &R->sp, .tabs = &R->tabs};
}

static void terms(const rig *R, int exact, const float g[3], float *d, float *s)
{
    if (exact) {
        const float ppm = (float)R->F.cam.px_per_mm, zpm = (float)R->F.cam.z_per_mm;
        const double n[3] = {g[0] * ppm, g[1] * ppm, g[2] * zpm};
        double dd, ss;
        vs_light_eval(&R->F.light, n, &dd, &ss);
        *d = (float)dd;
        *s = (float)ss;
    } else
        vs_shade_terms_scalar(d, s, g, 1, &R->tabs);
}

/* one bilinear look-up, a channel at a time */
static void lookup(const vs_preint *P, float f, float b, float e[4])
{
    float fx, fy;
    const int i = vs_preint_cell(&P->tabs, f, &fx), j = vs_preint_cell(&P->tabs, b, &fy);
    for (int c = 0; c < 4; c++) e[c] = vs_preint_bilerp(&P->tabs, (size_t)i * VS_PREINT_N + (size_t)j, fx, fy, c);
}

/* Pixel o = (x, y)'s colour at sheet k by the formula, from its sheet k
 * gradient g0 as classification left it. */
static void expected(const rig *R, int k, int exact, int x, int y, const float g0[3], float c[3])
{
    const vs_frame *F = &R->F;
    const int gs = R->ch == 4;
    const float slab = (float)F->fp.slab, base = (float)F->base;
    const size_t b = (size_t)y * STRIDE + x;
    float f, m, bk, g1[3], gm[3];
    if (gs) {
        const float *q = at(R, k) + 4 * b, *n = at(R, k + 1) + 4 * b;
        f = q[0];
        bk = n[0];
        m = vs_preint_mid_gs(q, n);
        for (int i = 0; i < 3; i++) g1[i] = n[1 + i] / slab;
        for (int i = 0; i < 3; i++) gm[i] = 0.5f * (g0[i] + g1[i]);
    } else {
        const float *q = at(R, k) + b, *n = at(R, k + 1) + b;
        f = q[0];
        bk = n[0];
        m = vs_preint_mid_cd(at(R, k - 1)[b], f, bk);
        const float w = R->tabs.cd_wide, c1 = 0.5f + 2.0f * w; /* simd/scalar.c's formula */
        if (w > 0.0f) {
            g1[0] = c1 * (n[1] - n[-1]) - w * (n[2] - n[-2]);
            g1[1] = c1 * (n[STRIDE] - n[-STRIDE]) - w * (n[2 * STRIDE] - n[-2 * STRIDE]);
        } else {
            g1[0] = 0.5f * (n[1] - n[-1]);
            g1[1] = 0.5f * (n[STRIDE] - n[-STRIDE]);
        }
        g1[2] = (at(R, k + 2)[b] - f) / (2.0f * slab);
        const vs_camera *cam = &F->cam;
        const float u = (float)((x + R->t.ox) - cam->cx), v = (float)((y + R->t.oy) - cam->cy);
        const float cz = (float)(cam->px_per_mm / (cam->focal_px * cam->z_per_mm));
        if (cam->persp) vs_perspective_gradient(g1, (float)vs_camera_sheet_scale(cam, k + 1, F->fp.slab), u, v, cz);
        gm[0] = 0.5f * (g0[0] + g1[0]);
        gm[1] = 0.5f * (g0[1] + g1[1]);
        gm[2] = (bk - f) / slab;
        if (cam->persp) gm[2] -= (gm[0] * u + gm[1] * v) * cz;
    }
    float e1[4], e2[4], d[3], s[3];
    lookup(F->preint, f + base, m + base, e1);
    lookup(F->preint, m + base, bk + base, e2);
    terms(R, exact, g0, &d[0], &s[0]);
    terms(R, exact, gm, &d[1], &s[1]);
    terms(R, exact, g1, &d[2], &s[2]);
    const float d1 = 0.5f * (d[0] + d[1]), s1 = 0.5f * (s[0] + s[1]), d2 = 0.5f * (d[1] + d[2]),
                s2 = 0.5f * (s[1] + s[2]);
    const float a1 = e1[0], a2 = e2[0], A = a1 + (1.0f - a1) * a2;
    float inv = A > 0.0f ? 1.0f / A : 0.0f;
    if (!(inv <= FLT_MAX)) inv = 0.0f;
    for (int i = 0; i < 3; i++) c[i] = ((e1[1 + i] * d1 + a1 * s1) + (1.0f - a1) * (e2[1 + i] * d2 + a2 * s2)) * inv;
}

/* sheet k classified by the classification stage itself (the segment's
 * opacity, the gradient: central differences, perspective-corrected, or
 * the splatted one), the pixel `dead` then made transparent at sheet
 * dead_k */
static void classify(rig *R, int k, int dead, int dead_k)
{
    const sheet_view sv = view(R, k);
    const shade_buf sb = {R->alpha, R->g, R->term, R->term_k};
    R->F.stages->classify(&R->t, &sv, sb);
    if (k == dead_k) R->alpha[dead] = 0.0f;
    /* row 3: a chunk without a live pixel, the next live from its ninth */
    for (int x = 1; x < 80; x++) R->alpha[2 * TW + (x - 1)] = 0.0f;
}

static void shade(rig *R, int k)
{
    const sheet_view sv = view(R, k);
    const shade_buf sb = {R->alpha, R->g, R->term, R->term_k};
    vs_shade_post_preint(&R->t, &sv, sb);
}

static void run(const vs_preint *P, int gs, int exact, int persp, float cd_wide)
{
    rig *R = calloc(1, sizeof *R);
    if (!R) {
        CHECK(0, "out of memory");
        return;
    }
    R->ch = gs ? 4 : 1;
    vs_settings_init(&R->s);
    R->s.headlight = 0;
    R->s.exact_normals = exact;
    vs_frame *F = &R->F;
    F->s = &R->s;
    F->preint = P;
    F->stages = vs_pipeline_stages(gs ? VS_PIPELINE_POST_GS : VS_PIPELINE_POST_CD, exact, 1, 0);
    F->fp.slab = 0.37;
    F->base = 0.125;
    F->cam.px_per_mm = 1.3;
    F->cam.z_per_mm = 0.7;
    if (persp) { /* the eye 40 view units before z = 0, the image centre inside the tile */
        F->cam.persp = 1;
        F->cam.persp_dz = 40.0;
        F->cam.focal_px = 30.0;
        F->cam.near_z = -30.0;
        F->cam.cx = 9.3;
        F->cam.cy = 4.6;
    } else
        F->cam.near_z = -INFINITY;
    R->s.occlusion = 0;
    /* a light off the view axis, so that the terms depend on every component */
    F->light = (vs_light){{0.48, -0.36, -0.8}, {0.0, 0.0, -1.0}, 0.1, 0.6, 0.3, 20.0};
    const double h[3] = {0.48, -0.36, -1.8}, hn = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (int i = 0; i < 3; i++) F->light.H[i] = h[i] / hn;
    vs_kernels_init(&F->kern, VS_ISA_AUTO);
    vs_shade_lut lut;
    memset(&lut, 0, sizeof lut);
    if (vs_shade_lut_setup(ctx, R->s.normal_lut_size, &F->light, &lut) != VS_OK) {
        CHECK(0, "normal LUT");
        free(R);
        return;
    }
    R->tabs = (vs_shade_tabs){.slab = 0.37f, .two_slab = 2.0f * 0.37f, .ppm = 1.3f, .zpm = 0.7f, .nl = lut.nl,
                              .lambda_bin = lut.lambda_bin, .radius = lut.radius, .phi_bin = lut.phi_bin,
                              .diffuse = lut.diffuse, .specular = lut.specular, .cd_wide = cd_wide};
    const int seam = cd_wide > 0.0f ? 2 : 1; /* as render.c sets it */
    R->t = (tile_ctx){.F = F, .seam = seam, .tw = TW, .th = TH, .bw = TW + 2 * seam, .bh = TH + 2 * seam,
                      .stride = STRIDE, .ox = 3, .oy = -2};
    R->sp = (spans){seam, TH + seam, R->xa, R->xb};
    for (int y = seam; y < TH + seam; y++) { /* uneven spans, one row empty */
        R->xa[y] = seam + (y % 3) * 5;
        R->xb[y] = y == 3 + seam ? R->xa[y] : TW + seam - (y % 4) * 7;
    }
    for (int k = 0; k < NS; k++) {
        const int nf = STRIDE * SH * R->ch;
        R->sheet[k] = malloc((size_t)nf * sizeof(float));
        if (!R->sheet[k]) {
            CHECK(0, "out of memory");
            goto done;
        }
        /* densities over the classification's domain less the base, gradients +-1 */
        for (int i = 0; i < nf; i++)
            R->sheet[k][i] = (i % R->ch) ? (float)(2.0 * tu_urand(&rng) - 1.0) : (float)tu_urand(&rng) - 0.125f;
    }
    const int dead = 5 * TW + 7;
    for (int i = 0; i < TW * TH; i++) R->term_k[i] = INT_MIN;
    /* sheets 1, 2, 3 in order, the pixel `dead` not live at sheet 2 */
    float after[TW * TH * 3];
    for (int k = 1; k <= 3; k++) {
        classify(R, k, dead, 2);
        shade(R, k);
        if (k == 2) CHECK(R->term_k[dead] == 2, "the pixel not live at sheet 2 holds terms for sheet 2");
        if (k < 3) {
            int stored = 1;
            for (int i = 0; i < TW * TH; i++)
                if (R->alpha[i] > 0.0f) stored &= R->term_k[i] == k + 1;
            CHECK(stored, "sheet %d's live pixels keep sheet %d's terms (%s, %s, %s)", k, k + 1,
                  gs ? "post-gs" : "post-cd", exact ? "exact" : "LUT", persp ? "perspective" : "orthographic");
        }
    }
    memcpy(after, R->g, sizeof after);
    /* sheet 3 alone */
    for (int i = 0; i < TW * TH; i++) R->term_k[i] = INT_MIN;
    classify(R, 3, dead, 2);
    float *g0 = malloc(sizeof R->g);
    if (!g0) {
        CHECK(0, "out of memory");
        goto done;
    }
    memcpy(g0, R->g, sizeof R->g);
    shade(R, 3);
    int formula = 1, live = 0;
    for (int y = seam; y < TH + seam; y++)
        for (int x = R->xa[y]; x < R->xb[y]; x++) {
            const int o = vs_own(&R->t, x, y);
            if (!(R->alpha[o] > 0.0f)) continue;
            float c[3];
            expected(R, 3, exact, x, y, g0 + 3 * o, c);
            formula &= memcmp(c, R->g + 3 * o, sizeof c) == 0;
            live++;
        }
    free(g0);
    CHECK(formula && live > TW * TH / 2, "colours differ from the formula (%d live pixels; %s, %s, %s, stencil %g)",
          live, gs ? "post-gs" : "post-cd", exact ? "exact" : "LUT", persp ? "perspective" : "orthographic",
          (double)cd_wide);
    int same = 1;
    for (int i = 0; i < TW * TH; i++)
        if (R->alpha[i] > 0.0f) same &= memcmp(after + 3 * i, R->g + 3 * i, 3 * sizeof(float)) == 0;
    CHECK(same, "sheet 3 after sheet 2 differs from sheet 3 alone (%s, %s, %s, stencil %g)", gs ? "post-gs" : "post-cd",
          exact ? "exact" : "LUT", persp ? "perspective" : "orthographic", (double)cd_wide);
    int lit = 0;
    for (int i = 0; i < TW * TH * 3; i++) lit += R->g[i] > 0.0f && isfinite(R->g[i]);
    CHECK(lit > TW * TH, "sheet 3 emits light");
done:
    vs_shade_lut_free(&lut);
    for (int k = 0; k < NS; k++) free(R->sheet[k]);
    free(R);
}

int main(void)
{
    if (vs_context_create(&ctx) != VS_OK) return 2;
    vs_volume *v = tu_scene(ctx, "sphere:16");
    if (!v) return 1;
    const vs_tf_point tf[] = {{0.0, 1.0f, 0.6f, 0.4f, 0.0f}, {0.3, 1.0f, 0.6f, 0.4f, 0.4f},
                              {0.6, 0.5f, 0.8f, 1.0f, 0.1f}, {1.0, 0.9f, 0.9f, 0.9f, 0.9f}};
    vs_settings s;
    vs_settings_init(&s);
    s.tf = tf;
    s.tf_count = 4;
    vs_classify *c = malloc(sizeof *c);
    vs_preint *p = calloc(1, sizeof *p);
    if (c && p && vs_classify_setup(ctx, v, &s, c) == VS_OK && vs_preint_update(p, c, 0.25, NULL)) {
        for (int gs = 0; gs < 2; gs++)
            for (int exact = 0; exact < 2; exact++)
                for (int persp = 0; persp < 2; persp++) {
                    run(p, gs, exact, persp, 0.0f);
                    if (!gs) { /* the four-point stencil, alone and mixed */
                        run(p, gs, exact, persp, 1.0f / 12.0f);
                        run(p, gs, exact, persp, 1.0f / 32.0f);
                    }
                }
    } else
        CHECK(0, "set-up");
    vs_preint_free(p);
    free(c);
    vs_volume_release(v);
    vs_context_release(ctx);
    TEST_DONE();
}
