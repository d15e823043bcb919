/* Pre-integrated shading reuses, at sheet k + 1, the Phong terms of sheet
 * k + 1's gradient it took while shading sheet k (shade_buf.term).  Here
 * the shading stage runs on random sheets, post-cd and post-gs, with
 * exact normals and with the normal LUT: sheet k + 1 shaded after sheet k
 * must give bit for bit the colours it gives shaded alone, also for a
 * pixel that was not live at sheet k (its stored terms are older and must
 * not be taken), and sheet k must have stored terms at its live pixels. */
#include "testutil.h"
#include "classify.h"
#include "frame.h"
#include "light.h"
#include "preintegrate.h"
#include "shade.h"
#include "shade_lut.h"
#include "tile.h"

#include <limits.h>

enum { TW = 21, TH = 13, SW = TW + 2, SH = TH + 2, NS = 6 };

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

/* sheet k's classification as the classify stage leaves it: the gradient
 * (central differences, or the splatted one), and an opacity that is 0 at
 * the pixels `dead` names for this k */
static void classify(rig *R, int k, int dead_pixel, int dead_k)
{
    for (int y = 1; y <= TH; y++) {
        const int o = (y - 1) * TW;
        const size_t b = (size_t)y * SW + 1;
        if (R->ch == 1)
            vs_classify_cd_scalar(NULL, R->g + 3 * o, R->sheet[k] + b, R->sheet[k - 1] + b, R->sheet[k + 1] + b, SW, TW,
                                  &R->tabs);
        else
            vs_classify_gs_scalar(NULL, R->g + 3 * o, R->sheet[k] + 4 * b, TW, &R->tabs);
        for (int x = 0; x < TW; x++) R->alpha[o + x] = 0.25f + 0.5f * (float)tu_urand(&rng);
    }
    if (k == dead_k) R->alpha[dead_pixel] = 0.0f;
}

static void shade(rig *R, int k)
{
    const sheet_view sv = {.k = k, .q = R->sheet[k], .prev = R->sheet[k - 1], .next = R->sheet[k + 1],
                           .next2 = R->ch == 1 ? R->sheet[k + 2] : NULL, .sp = &R->sp, .tabs = &R->tabs};
    const shade_buf sb = {R->alpha, R->g, R->term, R->term_k};
    vs_shade_post_preint(&R->t, &sv, sb);
}

static void run(const vs_preint *P, int gs, int exact)
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
    F->stages = vs_pipeline_stages(gs ? VS_PIPELINE_POST_GS : VS_PIPELINE_POST_CD, exact, 1);
    F->fp.slab = 0.5;
    F->cam.px_per_mm = 1.3;
    F->cam.z_per_mm = 0.7;
    /* a light off the view axis, so that the terms depend on every component */
    F->light = (vs_light){{0.48, -0.36, -0.8}, {0.0, 0.0, -1.0}, 0.1, 0.6, 0.3, 20.0};
    const double h[3] = {0.48, -0.36, -1.8}, hn = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (int i = 0; i < 3; i++) F->light.H[i] = h[i] / hn;
    vs_kernels_init(&F->kern, VS_ISA_SCALAR);
    vs_shade_lut lut;
    memset(&lut, 0, sizeof lut);
    if (vs_shade_lut_setup(ctx, R->s.normal_lut_size, &F->light, &lut) != VS_OK) {
        CHECK(0, "normal LUT");
        free(R);
        return;
    }
    R->tabs = (vs_shade_tabs){.slab = 0.5f, .two_slab = 1.0f, .ppm = 1.3f, .zpm = 0.7f, .nl = lut.nl,
                              .lambda_bin = lut.lambda_bin, .radius = lut.radius, .phi_bin = lut.phi_bin,
                              .diffuse = lut.diffuse, .specular = lut.specular};
    R->t = (tile_ctx){.F = F, .tw = TW, .th = TH, .bw = SW, .bh = SH, .stride = SW};
    R->sp = (spans){1, TH + 1, R->xa, R->xb};
    for (int y = 1; y <= TH; y++) {
        R->xa[y] = 1;
        R->xb[y] = TW + 1;
    }
    for (int k = 0; k < NS; k++) {
        R->sheet[k] = malloc((size_t)SW * SH * R->ch * sizeof(float));
        if (!R->sheet[k]) {
            CHECK(0, "out of memory");
            goto done;
        }
        for (int i = 0; i < SW * SH * R->ch; i++) /* densities over the classification's domain, gradients +-1 */
            R->sheet[k][i] = (i % R->ch) ? (float)(2.0 * tu_urand(&rng) - 1.0) : (float)tu_urand(&rng);
    }
    const int dead = 5 * TW + 7;
    for (int i = 0; i < TW * TH; i++) R->term_k[i] = INT_MIN;
    /* sheets 1, 2, 3 in order, the pixel `dead` not live at sheet 2 */
    float after[TW * TH * 3];
    for (int k = 1; k <= 3; k++) {
        const uint64_t keep = rng;
        classify(R, k, dead, 2);
        if (k == 3) rng = keep; /* the same opacities below */
        shade(R, k);
        if (k == 2) CHECK(R->term_k[dead] == 2, "the pixel not live at sheet 2 holds terms for sheet 2");
        if (k < 3) {
            int stored = 1;
            for (int i = 0; i < TW * TH; i++)
                if (R->alpha[i] > 0.0f) stored &= R->term_k[i] == k + 1;
            CHECK(stored, "sheet %d's live pixels keep sheet %d's terms (%s, %s)", k, k + 1, gs ? "post-gs" : "post-cd",
                  exact ? "exact" : "LUT");
        }
    }
    memcpy(after, R->g, sizeof after);
    /* sheet 3 alone */
    for (int i = 0; i < TW * TH; i++) R->term_k[i] = INT_MIN;
    classify(R, 3, dead, 2);
    shade(R, 3);
    int same = 1;
    for (int i = 0; i < TW * TH; i++)
        if (R->alpha[i] > 0.0f) same &= memcmp(after + 3 * i, R->g + 3 * i, 3 * sizeof(float)) == 0;
    CHECK(same, "sheet 3 after sheet 2 differs from sheet 3 alone (%s, %s)", gs ? "post-gs" : "post-cd",
          exact ? "exact" : "LUT");
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
            for (int exact = 0; exact < 2; exact++) run(p, gs, exact);
    } else
        CHECK(0, "set-up");
    vs_preint_free(p);
    free(c);
    vs_volume_release(v);
    vs_context_release(ctx);
    TEST_DONE();
}
