/* Anisotropic grids splatted from a copy on cubic voxels (src/resample.c,
 * vs_settings.resample):
 *  - the copy: a constant stays constant inside and falls to the value
 *    outside the volume past its ends (as the grid's own kernels do), its
 *    size is the grid's extent in finest voxels plus the padding, its
 *    centre lands on the volume's, NaN reads as the outside value;
 *  - who gets it: thick axes of 1.25x and more, orthogonal grids, no crop
 *    box, no ray caster, resample 0 never, auto only within the volume's
 *    size plus 64 MB, 1 whatever the size;
 *  - the picture: an off-centre ball sampled on a 1 x 1 x 2.5 grid, seen
 *    obliquely (where every section of the thick kernel is placed on its
 *    own), against the ray caster on the same grid: the copy is within
 *    0.5 dB of the grid as stored for every splatting pipeline (2 dB in
 *    perspective, about an off-centre point), above 45 dB and within 40 dB of the stored grid's
 *    image for the post-classified ones; orthographic and perspective;
 *  - seen small, the levels of detail are made from the copy (cubic) and
 *    draw the ball as the stored grid's levels do;
 *  - bit-identical for 1 and 2 threads; the copy is kept across frames and
 *    across a new range, and made anew for new voxels and for a range that
 *    moves the value outside the volume;
 *  - with the outside value visible (CT air) and the thick axis oriented
 *    into the world's -x, the volume ends where the stored grid ends; a
 *    new transform places the kept copy anew, as a fresh one draws. */
#include "context.h"
#include "lod.h"
#include "resample.h"
#include "testutil.h"

/* A ball of radius 11 mm about (24, 22, 26) mm, smooth edge, sampled on a
 * grid of spacing sp (index i at i * sp mm). */
static vs_volume *ball(vs_context *ctx, const int d[3], const double sp[3], vs_type type)
{
    vs_volume *v = NULL;
    CHECK(vs_volume_create(ctx, type, d, sp, &v) == VS_OK, "create: %s", vs_last_error(ctx));
    if (!v) return NULL;
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++) {
                const double x = i * sp[0] - 24, y = j * sp[1] - 22, z = k * sp[2] - 26;
                const double r = sqrt(x * x + y * y + z * z);
                const double f = 200.0 / (1.0 + exp((r - 11.0) / 1.2));
                const size_t at = ((size_t)k * d[1] + j) * d[0] + i;
                if (type == VS_U8)
                    ((unsigned char *)vs_volume_data(v))[at] = (unsigned char)lround(f);
                else
                    ((float *)vs_volume_data(v))[at] = (float)f;
            }
    vs_volume_update_range(v);
    return v;
}

static void test_copy(vs_context *ctx)
{
    const int d[3] = {9, 7, 11};
    const double sp[3] = {0.5, 0.5, 1.5};
    vs_volume *v = NULL;
    CHECK(vs_volume_create(ctx, VS_F32, d, sp, &v) == VS_OK, "create");
    if (!v) return;
    float *f = vs_volume_data(v);
    for (size_t i = 0; i < (size_t)d[0] * d[1] * d[2]; i++) f[i] = 7.0f;
    f[d[0] * d[1] * 5 + 3] = NAN; /* reads as the outside value, 0 here */
    f[0] = -3.0f;                 /* base: the minimum, below 0 */
    vs_volume_update_range(v);
    vs_resample_cache *c = NULL;
    const struct vs_volume *cv = NULL;
    double ms = -1;
    CHECK(vs_resample_get(ctx, NULL, &c, v, &cv, &ms) == VS_OK && cv, "copy: %s", vs_last_error(ctx));
    if (cv) {
        /* (11 - 1) * 3 + 1 voxels, and ceil(4 sigma) each side, sigma =
         * 0.6 sqrt(1.5^2 - 0.5^2) / 0.5 finest voxels */
        const int pad = (int)ceil(4.0 * sqrt(1.5 * 1.5 - 0.25) / 0.5 / sqrt(4.0 * log(2.0)));
        CHECK(cv->dims[0] == 9 && cv->dims[1] == 7 && cv->dims[2] == 31 + 2 * pad, "dims %dx%dx%d, pad %d",
              cv->dims[0], cv->dims[1], cv->dims[2], pad);
        CHECK(cv->spacing[2] == 0.5 && cv->vmin == v->vmin && cv->vmax == v->vmax, "spacing %g, range", cv->spacing[2]);
        /* the centres at the same world point */
        double wc[3], wv[3];
        for (int r = 0; r < 3; r++) {
            wc[r] = cv->affine[r][3], wv[r] = v->affine[r][3];
            for (int a = 0; a < 3; a++) {
                wc[r] += cv->affine[r][a] * 0.5 * (cv->dims[a] - 1);
                wv[r] += v->affine[r][a] * 0.5 * (v->dims[a] - 1);
            }
            CHECK(fabs(wc[r] - wv[r]) < 1e-9, "centre axis %d: %g vs %g", r, wc[r], wv[r]);
        }
        const float *q = cv->data;
        const size_t np = (size_t)cv->dims[0] * cv->dims[1];
        int nan = 0;
        double worst = 0;
        for (size_t i = 0; i < np * cv->dims[2]; i++) nan += !isfinite(q[i]);
        /* column x = 5 (away from the NaN and the -3) well inside: 7 */
        for (int k = pad + 8; k < cv->dims[2] - pad - 8; k++) {
            for (int j = 0; j < cv->dims[1]; j++) {
                const double e = fabs(q[k * np + (size_t)j * cv->dims[0] + 5] - 7.0);
                if (e > worst) worst = e;
            }
        }
        CHECK(nan == 0, "%d non-finite voxels in the copy", nan);
        CHECK(worst < 1e-5, "a constant is not kept inside: off by %g", worst);
        /* past the ends the thick kernel's fall to the outside value (-3),
         * not the face's value: at the first voxel's plane a little of
         * the weight lies outside, at the outermost none inside */
        const double end = q[pad * np + 5 + 3 * cv->dims[0]], out = q[5 + 3 * cv->dims[0]];
        CHECK(end > 4.0 && end < 6.5, "the end plane %g: not pulled a little to the outside -3 from 7", end);
        CHECK(out < -2.9, "the outermost plane %g: not the outside value -3", out);
        CHECK(ms >= 0, "build time %g", ms);
        /* kept, and made anew for new voxels */
        const struct vs_volume *again = NULL;
        vs_resample_get(ctx, NULL, &c, v, &again, &ms);
        CHECK(again == cv && ms == 0.0, "not kept (%g ms)", ms);
        vs_volume_update_range(v);
        vs_resample_get(ctx, NULL, &c, v, &again, &ms);
        CHECK(c && c->from.data_serial == v->data_serial, "not made anew for new voxels");
    }
    vs_resample_cache_free(c);
    vs_volume_release(v);
}

static void test_who(vs_context *ctx)
{
    vs_settings s;
    vs_settings_init(&s);
    struct {
        int d[3];
        double sp[3];
        int want_auto, want_on;
    } cases[] = {
        {{64, 64, 64}, {1, 1, 1}, 0, 0},          /* cubic */
        {{64, 64, 64}, {1, 1, 1.2}, 0, 0},        /* too little: aliasing */
        {{64, 64, 64}, {1, 1, 1.25}, 1, 1},       /* from 1.25 on */
        {{64, 64, 64}, {2, 2, 1}, 1, 1},          /* thick in-plane axes */
        {{64, 64, 64}, {1, 1.1, 2}, 0, 0},        /* one axis only a little thicker */
        {{512, 512, 40}, {1, 1, 8}, 0, 1},        /* 82 MB copy of 10 MB: auto says no */
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        struct vs_volume *v = NULL;
        CHECK(vs_volume_alloc_shell(ctx, VS_U8, cases[i].d, cases[i].sp, &v) == VS_OK, "shell");
        if (!v) continue;
        s.resample = -1;
        CHECK(vs_resample_wanted(v, &s) == cases[i].want_auto, "case %zu auto", i);
        s.resample = 1;
        CHECK(vs_resample_wanted(v, &s) == cases[i].want_on, "case %zu on", i);
        s.resample = 0;
        CHECK(!vs_resample_wanted(v, &s), "case %zu off", i);
        s.resample = 1;
        s.has_crop = 1;
        CHECK(!vs_resample_wanted(v, &s), "case %zu crop", i);
        s.has_crop = 0;
        s.pipeline = VS_PIPELINE_RAYCAST;
        CHECK(!vs_resample_wanted(v, &s), "case %zu ray caster", i);
        s.pipeline = VS_PIPELINE_POST_CD;
        if (i == 2) { /* a sheared grid stays as it is */
            const double m[12] = {1, 0.3, 0, 0, 0, 1, 0, 0, 0, 0, 1.25, 0};
            CHECK(vs_volume_set_transform(ctx, v, m) == VS_OK, "shear");
            CHECK(!vs_resample_wanted(v, &s), "sheared grid");
        }
        vs_volume_release(v);
    }
}

static void test_picture(vs_context *ctx)
{
    const int d[3] = {48, 44, 21};
    const double sp[3] = {1, 1, 2.5};
    vs_volume *v = ball(ctx, d, sp, VS_U8);
    if (!v) return;
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 128;
    s.azimuth = 35;
    s.elevation = 30;
    s.has_iso = 1;
    s.iso_lo = 100;
    s.iso_hi = INFINITY;
    s.ramp = 20;
    s.threads = 2;
    s.lod_pixels = 0;
    const vs_pipeline pipes[] = {VS_PIPELINE_POST_CD, VS_PIPELINE_POST_GS, VS_PIPELINE_PRE, VS_PIPELINE_POST_ALPHA};
    for (int persp = 0; persp < 2; persp++) {
        s.perspective_fov = persp ? 40 : 0;
        /* perspective also off the centre: the copy's centre is another index */
        s.has_center = persp;
        s.center[0] = 22, s.center[1] = 20, s.center[2] = 11;
        s.pipeline = VS_PIPELINE_RAYCAST;
        vs_image ref = tu_render(ctx, v, &s, NULL);
        for (int p = 0; p < 4; p++) {
            vs_stats st_off, st_on;
            s.pipeline = pipes[p];
            s.resample = 0;
            vs_image off = tu_render(ctx, v, &s, &st_off);
            s.resample = -1;
            vs_image on = tu_render(ctx, v, &s, &st_on);
            const double p_off = tu_psnr(ctx, &ref, &off), p_on = tu_psnr(ctx, &ref, &on), p_x = tu_psnr(ctx, &off, &on);
            printf("  %-10s %s: against the ray caster %.2f dB stored, %.2f dB resampled; to each other %.2f dB\n",
                   vs_pipeline_name(pipes[p]), persp ? "perspective" : "orthographic", p_off, p_on, p_x);
            CHECK(st_on.resampled == 1 && st_off.resampled == 0, "resampled %d / %d", st_on.resampled, st_off.resampled);
            /* perspective 128x128, post-cd: 49.95 against 51.79 dB (at 256x256
             * 49.48 against 49.39); orthographic 52.50 against 53.02 dB (with
             * the two-point differences across sheets 51.37 against 51.71) */
            CHECK(p_on >= p_off - (persp ? 2.0 : 0.6), "%s: resampled %.2f dB, stored %.2f dB",
                  vs_pipeline_name(pipes[p]), p_on, p_off);
            /* pre classifies voxels: finer ones draw a sharper, other picture */
            if (pipes[p] != VS_PIPELINE_PRE) {
                CHECK(p_on >= 45.0, "%s: resampled %.2f dB against the ray caster", vs_pipeline_name(pipes[p]), p_on);
                CHECK(p_x >= 40.0, "%s: resampled against stored %.2f dB", vs_pipeline_name(pipes[p]), p_x);
            }
            if (p == 0 && !persp) {
                s.threads = 1;
                vs_image one = tu_render(ctx, v, &s, NULL);
                CHECK(one.rgba && on.rgba && tu_max_diff(&one, &on) == 0.0, "1 and 2 threads differ");
                vs_image_free(&one);
                s.threads = 2;
            }
            vs_image_free(&off);
            vs_image_free(&on);
        }
        vs_image_free(&ref);
    }
    /* seen small: a level of detail made from the copy, cubic too, drawn
     * as the level of the stored grid draws it */
    {
        vs_stats sl, so;
        s.width = s.height = 24;
        s.lod_pixels = 1;
        s.pipeline = VS_PIPELINE_POST_CD;
        s.perspective_fov = 0;
        s.has_center = 0;
        s.resample = -1;
        vs_image on = tu_render(ctx, v, &s, &sl);
        const struct vs_volume *l1 = ctx->lod && sl.lod_level >= 1 ? ctx->lod->level[1] : NULL;
        CHECK(sl.resampled == 1 && sl.lod_level >= 1 && l1, "24x24: level %d, resampled %d", sl.lod_level,
              sl.resampled);
        if (l1)
            CHECK(l1->spacing[0] == l1->spacing[2] && l1->spacing[1] == l1->spacing[2], "level 1 not cubic: %g %g %g",
                  l1->spacing[0], l1->spacing[1], l1->spacing[2]);
        s.resample = 0;
        vs_image off = tu_render(ctx, v, &s, &so);
        const double p = tu_psnr(ctx, &on, &off);
        printf("  post-cd 24x24, level %d from the copy against level %d of the stored grid: %.2f dB\n", sl.lod_level,
               so.lod_level, p);
        CHECK(p >= 35.0, "level from the copy against the stored grid's: %.2f dB", p);
        vs_image_free(&on);
        vs_image_free(&off);
        s.width = s.height = 128;
        s.lod_pixels = 0;
        s.resample = -1;
    }
    /* the copy is kept across frames and a new range, made anew for new voxels */
    vs_stats st;
    s.pipeline = VS_PIPELINE_POST_CD;
    s.perspective_fov = 0;
    s.has_center = 0;
    vs_image a = tu_render(ctx, v, &s, &st);
    CHECK(st.resampled == 1 && st.ms_resample == 0.0, "second frame made a copy (%g ms)", st.ms_resample);
    vs_image_free(&a);
    CHECK(vs_volume_set_range(v, 0, 400) == VS_OK, "range");
    a = tu_render(ctx, v, &s, &st);
    CHECK(st.resampled == 1 && st.ms_resample == 0.0, "a new range made a copy (%g ms)", st.ms_resample);
    vs_image_free(&a);
    vs_volume_update_range(v);
    a = tu_render(ctx, v, &s, &st);
    CHECK(st.resampled == 1 && st.ms_resample > 0.0, "new voxels kept the old copy");
    vs_image_free(&a);
    vs_volume_release(v);
}

/* The alpha channel's box (first and last row and column above 0.01). */
static void alpha_box(const vs_image *im, int box[4])
{
    box[0] = box[2] = 1 << 30;
    box[1] = box[3] = -1;
    for (int j = 0; j < im->height; j++)
        for (int i = 0; i < im->width; i++)
            if (im->rgba[4 * ((size_t)j * im->width + i) + 3] > 0.01f) {
                if (i < box[0]) box[0] = i;
                if (i > box[1]) box[1] = i;
                if (j < box[2]) box[2] = j;
                if (j > box[3]) box[3] = j;
            }
}

/* The frame a context that kept the copy draws equals a fresh context's
 * after `what` changed the volume; returns the kept frame's ms_resample. */
static double same_as_fresh(vs_context *ctx, const vs_volume *v, const vs_settings *s, const char *what)
{
    vs_stats st;
    st.ms_resample = -1.0;
    vs_image kept = tu_render(ctx, v, s, &st);
    vs_context *fresh = NULL;
    CHECK(vs_context_create(&fresh) == VS_OK, "context");
    if (fresh) {
        vs_image anew = tu_render(fresh, v, s, NULL);
        const double diff = kept.rgba && anew.rgba ? tu_max_diff(&kept, &anew) : -1.0;
        CHECK(diff == 0.0, "after %s: the kept copy draws another image than a new one (%g)", what, diff);
        vs_image_free(&anew);
        vs_context_release(fresh);
    }
    vs_image_free(&kept);
    return st.ms_resample;
}

/* A CT-like volume (air -1000, a ball of 300) with its thick axis turned
 * into the world's -x (an oriented, permuted grid): where the volume ends
 * is where the visible air ends, with and without the copy; a new range
 * that moves the value outside the volume makes a new copy (the same
 * image as a fresh context's). */
static void test_faces(vs_context *ctx)
{
    const int d[3] = {30, 36, 16};
    const double sp[3] = {1, 1, 2.25};
    vs_volume *v = NULL;
    CHECK(vs_volume_create(ctx, VS_I16, d, sp, &v) == VS_OK, "create");
    if (!v) return;
    short *f = vs_volume_data(v);
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++) {
                const double x = i - 14.5, y = j - 17.5, z = 2.25 * (k - 7.5);
                f[((size_t)k * d[1] + j) * d[0] + i] = (short)(x * x + y * y + z * z < 100 ? 300 : -1000);
            }
    vs_volume_update_range(v);
    /* index z (thick) -> world -x, index x -> world y, index y -> world z */
    const double m[12] = {0, 0, -2.25, 40, 1, 0, 0, -5, 0, 1, 0, 3};
    CHECK(vs_volume_set_transform(ctx, v, m) == VS_OK, "transform: %s", vs_last_error(ctx));
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 96;
    s.azimuth = 0; /* the thick axis across the image, its two ends visible */
    s.elevation = 20;
    s.has_iso = 1;
    s.iso_lo = -1200;
    s.iso_hi = -500;
    s.ramp = 50;
    s.iso_opacity = 0.05f;
    s.lod_pixels = 0;
    s.threads = 2;
    vs_stats so, sn;
    s.resample = 0;
    vs_image off = tu_render(ctx, v, &s, &so);
    s.resample = -1;
    vs_image on = tu_render(ctx, v, &s, &sn);
    int bo[4], bn[4];
    alpha_box(&off, bo);
    alpha_box(&on, bn);
    printf("  visible air, oriented thick axis: box %d..%d x %d..%d stored, %d..%d x %d..%d copy\n", bo[0], bo[1],
           bo[2], bo[3], bn[0], bn[1], bn[2], bn[3]);
    CHECK(sn.resampled == 1 && so.resampled == 0, "resampled %d / %d", sn.resampled, so.resampled);
    for (int e = 0; e < 4; e++) CHECK(abs(bo[e] - bn[e]) <= 1, "box edge %d: stored %d, copy %d", e, bo[e], bn[e]);
    vs_image_free(&off);
    vs_image_free(&on);

    /* a range whose minimum (the outside value) moves: the copy follows */
    CHECK(vs_volume_set_range(v, -2000, 400) == VS_OK, "range");
    s.iso_lo = -1500;
    s.iso_hi = -900;
    same_as_fresh(ctx, v, &s, "a new range");
    /* a new transform: the same copy, placed anew (not made again) */
    const double m2[12] = {0, 0, 2.25, -30, 0, 1, 0, 4, 1, 0, 0, -2};
    CHECK(vs_volume_set_transform(ctx, v, m2) == VS_OK, "transform: %s", vs_last_error(ctx));
    const double ms = same_as_fresh(ctx, v, &s, "a new transform");
    CHECK(ms == 0.0, "a new transform made the copy again (%g ms)", ms);
    vs_volume_release(v);
}

int main(void)
{
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return 1;
    test_copy(ctx);
    test_who(ctx);
    test_picture(ctx);
    test_faces(ctx);
    vs_context_release(ctx);
    TEST_DONE();
}
