/* Levels of detail (src/lod.c, vs_settings.lod_pixels):
 *  - the filter is its definition (odd sizes, faces clamped, NaN read as
 *    the value outside the volume: 0, or the minimum when negative), halves only axes that keep 8 voxels, and conserves: a level's mean is its volume's (even sizes, where
 *    every voxel has the same total weight), a constant stays constant;
 *  - the level follows the picture: small images splat a coarser level and
 *    a surface's voxels 4x fewer a level, large ones the full volume, lod_pixels 0
 *    always, pre and post-alpha one level finer than post-cd;
 *  - the coarser volume lands where the full one does: the image centroid
 *    of an off-centre sphere agrees to 0.1 pixel, orthographic and
 *    perspective;
 *  - against the analytic sphere (the ray caster on the true function)
 *    the coarser frame stays within 5 dB of the full one and above 42 dB;
 *  - a shell one voxel thick beside a smooth ball stays in the picture at
 *    level 1 (lod_keep.c): within 1 dB of full resolution against the 4x
 *    reference, its coverage within 25 % of the reference's, the ball's
 *    level untouched, the same for 1 and 2 threads and across iso changes;
 *  - patching never raises a voxel above the finer values beneath it;
 *  - bit-identical for 1 and 2 threads; the levels and their relevant
 *    voxels are kept across frames (also across a full-resolution frame)
 *    and rebuilt when the volume changes; bad lod_pixels is refused. */
#include "context.h"
#include "lod.h"
#include "testutil.h"

static void centroid(const vs_image *im, double c[2])
{
    double m = 0, x = 0, y = 0;
    for (int j = 0; j < im->height; j++)
        for (int i = 0; i < im->width; i++) {
            const double a = im->rgba[4 * ((size_t)j * im->width + i) + 3];
            m += a, x += a * i, y += a * j;
        }
    c[0] = m > 0 ? x / m : NAN;
    c[1] = m > 0 ? y / m : NAN;
}

/* Level 1 of an isotropic f32 volume by the definition: per axis taps
 * 1 3 3 1 (/8) on voxels 2i-1 .. 2i+2, clamped to the volume. */
static double direct_level1(const float *f, const int d[3], int i, int j, int k)
{
    static const double w[4] = {0.125, 0.375, 0.375, 0.125};
    double acc = 0;
    for (int c = 0; c < 4; c++)
        for (int b = 0; b < 4; b++)
            for (int a = 0; a < 4; a++) {
                int x = 2 * i - 1 + a, y = 2 * j - 1 + b, z = 2 * k - 1 + c;
                x = x < 0 ? 0 : x >= d[0] ? d[0] - 1 : x;
                y = y < 0 ? 0 : y >= d[1] ? d[1] - 1 : y;
                z = z < 0 ? 0 : z >= d[2] ? d[2] - 1 : z;
                acc += w[a] * w[b] * w[c] * f[((size_t)z * d[1] + y) * d[0] + x];
            }
    return acc;
}

static void test_filter_definition(vs_context *ctx)
{
    static const int sizes[][3] = {{17, 15, 19}, {16, 16, 16}, {41, 15, 15}};
    for (int s = 0; s < 3; s++) {
        const int *d = sizes[s];
        vs_volume *v = NULL;
        CHECK(vs_volume_create(ctx, VS_F32, d, NULL, &v) == VS_OK, "create");
        if (!v) continue;
        float *f = vs_volume_data(v);
        unsigned r = 99u + (unsigned)s;
        const float shift = s == 2 ? -50.0f : 0.0f; /* CT-like: empty space is the minimum */
        for (size_t i = 0; i < (size_t)d[0] * d[1] * d[2]; i++) {
            r = r * 1103515245u + 12345u;
            f[i] = (float)((r >> 8) % 1000) / 10.0f + shift;
        }
        f[0] = NAN; /* counts as empty space: the base in the definition below */
        vs_volume_update_range(v);
        double lo;
        vs_volume_range(v, &lo, NULL);
        vs_lod_cache *cache = NULL;
        const struct vs_volume *l1 = NULL;
        double ms, worst = 0;
        if (vs_lod_get(ctx, NULL, &cache, v, 1, &l1, &ms) == VS_OK && l1) {
            f[0] = lo < 0.0 ? (float)lo : 0.0f;
            for (int k = 0; k < l1->dims[2]; k++)
                for (int j = 0; j < l1->dims[1]; j++)
                    for (int i = 0; i < l1->dims[0]; i++) {
                        const double e = fabs(((const float *)l1->data)[((size_t)k * l1->dims[1] + j) * l1->dims[0] + i] -
                                              direct_level1(f, d, i, j, k));
                        if (!(e <= worst)) worst = e;
                    }
        } else {
            CHECK(0, "level 1 of %dx%dx%d: %s", d[0], d[1], d[2], vs_last_error(ctx));
        }
        CHECK(worst < 1e-3, "%dx%dx%d: level 1 differs from the filter's definition by %g", d[0], d[1], d[2], worst);
        vs_lod_cache_free(cache);
        vs_volume_release(v);
    }
}

static void test_filter(vs_context *ctx)
{
    const int d[3] = {32, 18, 16};
    vs_volume *v = NULL;
    CHECK(vs_volume_create(ctx, VS_F32, d, NULL, &v) == VS_OK, "create");
    if (!v) return;
    float *f = vs_volume_data(v);
    unsigned r = 12345;
    double sum = 0;
    const size_t n = (size_t)d[0] * d[1] * d[2];
    for (size_t i = 0; i < n; i++) {
        r = r * 1103515245u + 12345u;
        f[i] = (float)((r >> 8) % 1000);
        sum += f[i];
    }
    vs_volume_update_range(v);
    vs_lod_cache *cache = NULL;
    const struct vs_volume *l1 = NULL, *l2 = NULL, *l3 = NULL;
    double ms;
    CHECK(vs_lod_get(ctx, NULL, &cache, v, 1, &l1, &ms) == VS_OK && l1, "level 1: %s", vs_last_error(ctx));
    CHECK(vs_lod_get(ctx, NULL, &cache, v, 2, &l2, &ms) == VS_OK && l2, "level 2: %s", vs_last_error(ctx));
    /* then only x can halve (9 and 8 voxels would become 5 and 4), then none */
    CHECK(vs_lod_get(ctx, NULL, &cache, v, 3, &l3, &ms) != VS_OK && !l3, "level 3 of 8x9x8 was built");
    if (l1 && l2) {
        CHECK(l1->dims[0] == 16 && l1->dims[1] == 9 && l1->dims[2] == 8 && l2->dims[0] == 8 && l2->dims[1] == 9 &&
                  l2->dims[2] == 8,
              "dims %dx%dx%d, %dx%dx%d", l1->dims[0], l1->dims[1], l1->dims[2], l2->dims[0], l2->dims[1],
              l2->dims[2]);
        CHECK(l1->spacing[0] == 2.0 && l2->spacing[0] == 4.0 && l2->spacing[2] == 2.0, "spacing %g %g %g",
              l1->spacing[0], l2->spacing[0], l2->spacing[2]);
        /* level voxel 0 sits between voxels 0 and 1 of the level before */
        CHECK(l1->affine[0][3] == 0.5 && l2->affine[0][3] == 1.5 && l2->affine[1][3] == 0.5, "origin %g %g %g",
              l1->affine[0][3], l2->affine[0][3], l2->affine[1][3]);
        double s1 = 0;
        const float *g = l1->data;
        for (size_t i = 0; i < (size_t)16 * 9 * 8; i++) s1 += g[i];
        const double m0 = sum / n, m1 = s1 / (16 * 9 * 8);
        CHECK(fabs(m1 - m0) < 1e-4 * m0, "mean %.6f, level 1 %.6f", m0, m1);
        printf("  filter: mean %.4f, level 1 %.4f (32x18x16 -> 16x9x8 -> 8x9x8)\n", m0, m1);
    }
    vs_lod_cache_free(cache);
    /* anisotropic: only axes within 1.5x of the finest spacing halve */
    const double sp[3] = {1, 1, 3};
    vs_volume *w = NULL;
    CHECK(vs_volume_create(ctx, VS_U8, d, sp, &w) == VS_OK, "create anisotropic");
    if (w) {
        const struct vs_volume *a3 = NULL;
        cache = NULL;
        CHECK(vs_lod_get(ctx, NULL, &cache, w, 3, &a3, &ms) == VS_OK, "anisotropic level 3");
        if (cache && a3) {
            const struct vs_volume *a1 = cache->level[1], *a2 = cache->level[2];
            /* 32x18x16 (1,1,3) -> 16x9x16 (2,2,3) -> 8x9x16 (4,2,3) -> 8x9x8 (4,2,6) */
            CHECK(a1->dims[0] == 16 && a1->dims[2] == 16 && a1->spacing[2] == 3 && a2->dims[0] == 8 &&
                      a2->spacing[0] == 4 && a2->spacing[2] == 3 && a3->spacing[0] == 4 && a3->spacing[2] == 6 &&
                      a3->dims[2] == 8,
                  "anisotropic levels: %gx%gx%g, %gx%gx%g, %gx%gx%g", a1->spacing[0], a1->spacing[1],
                  a1->spacing[2], a2->spacing[0], a2->spacing[1], a2->spacing[2], a3->spacing[0], a3->spacing[1],
                  a3->spacing[2]);
            /* an unhalved axis keeps its origin */
            CHECK(a1->affine[2][3] == 0.0 && a1->affine[0][3] == 0.5, "anisotropic origin %g %g", a1->affine[0][3],
                  a1->affine[2][3]);
        }
        vs_lod_cache_free(cache);
        vs_volume_release(w);
    }
    /* a constant stays constant, odd sizes and integer voxels too; a
     * single slice is never halved */
    const int e[3] = {17, 31, 1};
    vs_volume *u = NULL;
    CHECK(vs_volume_create(ctx, VS_U8, e, NULL, &u) == VS_OK, "create u8");
    if (u) {
        memset(vs_volume_data(u), 77, 17 * 31);
        vs_volume_update_range(u);
        cache = NULL;
        const struct vs_volume *c1 = NULL;
        if (vs_lod_get(ctx, NULL, &cache, u, 1, &c1, &ms) == VS_OK && c1) {
            int bad = 0;
            for (int i = 0; i < c1->dims[0] * c1->dims[1] * c1->dims[2]; i++)
                bad += ((const uint8_t *)c1->data)[i] != 77;
            CHECK(bad == 0 && c1->dims[0] == 9 && c1->dims[1] == 16 && c1->dims[2] == 1 && c1->spacing[2] == 1.0,
                  "constant 17x31x1: %d voxels changed, level %dx%dx%d", bad, c1->dims[0], c1->dims[1], c1->dims[2]);
        } else {
            CHECK(0, "u8 level 1: %s", vs_last_error(ctx));
        }
        vs_lod_cache_free(cache);
        vs_volume_release(u);
    }
    vs_volume_release(v);
}

static int level_of(vs_context *ctx, const vs_volume *v, vs_settings s, vs_stats *st)
{
    vs_image im = tu_render(ctx, v, &s, st);
    vs_image_free(&im);
    return st->lod_level;
}

static void test_choice(vs_context *ctx, const vs_volume *v)
{
    vs_settings s;
    vs_settings_init(&s);
    s.pipeline = VS_PIPELINE_POST_CD;
    vs_stats a, b;
    s.width = s.height = 32; /* 128 voxels across 32 pixels */
    const int l32 = level_of(ctx, v, s, &a);
    s.lod_pixels = 0;
    const int l0 = level_of(ctx, v, s, &b);
    CHECK(l32 == 2 && l0 == 0, "post-cd 32x32: level %d, with lod_pixels 0 %d", l32, l0);
    /* a surface's voxels: 4x fewer a level */
    CHECK(a.voxels_splatted * 12 < b.voxels_splatted, "level 2 splatted %llu, full %llu",
          (unsigned long long)a.voxels_splatted, (unsigned long long)b.voxels_splatted);
    CHECK(a.voxels_total == b.voxels_total, "voxels_total is the volume's");
    printf("  32x32 post-cd: level %d splats %llu, full %llu; frame %.1f vs %.1f ms\n", l32,
           (unsigned long long)a.voxels_splatted, (unsigned long long)b.voxels_splatted, a.ms_total, b.ms_total);
    s.lod_pixels = 1;
    s.pipeline = VS_PIPELINE_PRE;
    CHECK(level_of(ctx, v, s, &a) == 1, "pre 32x32: level %d (one finer)", a.lod_level);
    s.pipeline = VS_PIPELINE_POST_ALPHA;
    CHECK(level_of(ctx, v, s, &a) == 1, "post-alpha 32x32: level %d (one finer)", a.lod_level);
    s.pipeline = VS_PIPELINE_POST_CD;
    s.width = s.height = 160;
    CHECK(level_of(ctx, v, s, &a) == 0, "160x160: level %d", a.lod_level);
    s.width = s.height = 32;
    s.lod_pixels = 4;
    CHECK(level_of(ctx, v, s, &a) == 4, "lod_pixels 4: level %d", a.lod_level);
    s.lod_pixels = -1;
    vs_image im = {0, 0, NULL};
    CHECK(vs_render(ctx, v, &s, &im, NULL) == VS_ERR_INVALID_ARGUMENT && strstr(vs_last_error(ctx), "lod_pixels"),
          "lod_pixels -1: %s", vs_last_error(ctx));
}

static void test_registration(vs_context *ctx, const vs_volume *v)
{
    static const vs_pipeline pipes[] = {VS_PIPELINE_PRE, VS_PIPELINE_POST_CD, VS_PIPELINE_POST_GS,
                                        VS_PIPELINE_POST_ALPHA};
    for (int persp = 0; persp < 2; persp++)
        for (int p = 0; p < 4; p++) {
            vs_settings s;
            vs_settings_init(&s);
            s.pipeline = pipes[p];
            s.width = s.height = persp ? 28 : 36; /* the nearest corner is seen larger */
            s.azimuth = 30, s.elevation = 20;
            /* off-centre: a wrong level origin moves the picture */
            s.has_center = 1;
            s.center[0] = 80, s.center[1] = 50, s.center[2] = 70;
            s.perspective_fov = persp ? 30 : 0;
            vs_stats a, b;
            vs_image lod = tu_render(ctx, v, &s, &a);
            s.lod_pixels = 0;
            vs_image full = tu_render(ctx, v, &s, &b);
            double c0[2], c1[2];
            centroid(&lod, c1);
            centroid(&full, c0);
            const double dx = c1[0] - c0[0], dy = c1[1] - c0[1];
            CHECK(a.lod_level >= 1 && hypot(dx, dy) < 0.1, "pipeline %d persp %d: level %d, centroid moved %.3f,%.3f",
                  p, persp, a.lod_level, dx, dy);
            printf("  centroid, pipeline %d%s: level %d, moved %.3f,%.3f px\n", p, persp ? " perspective" : "",
                   a.lod_level, dx, dy);
            vs_image_free(&lod);
            vs_image_free(&full);
        }
}

/* Settings for a size x size image of the iso-surface at lo with a ramp. */
static vs_settings iso_settings(int size, double lo, double ramp)
{
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = size;
    s.has_iso = 1, s.iso_lo = lo, s.iso_hi = INFINITY, s.ramp = ramp;
    return s;
}

/* A ball in millimetres on a grid with slices 2 mm apart (a CT series'
 * shape): its levels halve x and y first. */
static void test_anisotropic(vs_context *ctx)
{
    const int d[3] = {128, 128, 64};
    const double sp[3] = {1, 1, 2};
    vs_volume *v = NULL;
    CHECK(vs_volume_create(ctx, VS_U8, d, sp, &v) == VS_OK, "create");
    if (!v) return;
    uint8_t *u = vs_volume_data(v);
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++) {
                const double r = sqrt((i - 70.0) * (i - 70.0) + (j - 55.0) * (j - 55.0) + (2 * k - 60.0) * (2 * k - 60.0));
                const double t = (40.0 - r) / 4.0 + 0.5;
                u[((size_t)k * d[1] + j) * d[0] + i] = (uint8_t)lrint(255 * (t < 0 ? 0 : t > 1 ? 1 : t));
            }
    vs_volume_update_range(v);
    vs_settings s = iso_settings(40, 128, 20);
    s.azimuth = 50, s.elevation = 25;
    vs_stats a, b;
    vs_image lod = tu_render(ctx, v, &s, &a);
    s.lod_pixels = 0;
    vs_image full = tu_render(ctx, v, &s, &b);
    double c0[2], c1[2];
    centroid(&lod, c1);
    centroid(&full, c0);
    const double pf = tu_psnr(ctx, &lod, &full);
    CHECK(a.lod_level >= 2 && hypot(c1[0] - c0[0], c1[1] - c0[1]) < 0.1 && pf > 30,
          "anisotropic ball: level %d, centroid moved %.3f,%.3f, %.1f dB", a.lod_level, c1[0] - c0[0],
          c1[1] - c0[1], pf);
    printf("  anisotropic ball (1x1x2 mm): level %d, centroid moved %.3f,%.3f px, %.1f dB against full resolution\n",
           a.lod_level, c1[0] - c0[0], c1[1] - c0[1], pf);
    vs_image_free(&lod);
    vs_image_free(&full);
    vs_volume_release(v);
}

static double alpha_sum(const vs_image *im)
{
    double m = 0;
    for (size_t p = 0; p < (size_t)im->width * im->height; p++) m += im->rgba[4 * p + 3];
    return m;
}

/* Opacity is per unit of the full volume: a level's longer slabs must not
 * thin a translucent ball (centre alpha 0.64 at full resolution, 0.24 at
 * level 2 when slabs counted in level units). */
static void test_translucent(vs_context *ctx, const vs_volume *v)
{
    static const vs_pipeline pipes[] = {VS_PIPELINE_PRE, VS_PIPELINE_POST_CD, VS_PIPELINE_POST_ALPHA};
    for (int p = 0; p < 3; p++) {
        vs_settings s;
        vs_settings_init(&s);
        s.pipeline = pipes[p];
        s.width = s.height = 33;
        s.iso_opacity = 0.01f;
        vs_stats a;
        vs_image lod = tu_render(ctx, v, &s, &a);
        s.lod_pixels = 0;
        vs_image full = tu_render(ctx, v, &s, NULL);
        const size_t c = 4 * ((size_t)16 * 33 + 16) + 3;
        CHECK(a.lod_level >= 1 && fabs(lod.rgba[c] - full.rgba[c]) < 0.03,
              "translucent pipeline %d: level %d centre alpha %.3f, full %.3f", p, a.lod_level, lod.rgba[c],
              full.rgba[c]);
        printf("  translucent ball, pipeline %d: level %d centre alpha %.3f, full resolution %.3f\n", p,
               a.lod_level, lod.rgba[c], full.rgba[c]);
        vs_image_free(&lod);
        vs_image_free(&full);
    }
}

/* A transform set after the levels were built moves them with the volume:
 * the frame equals a fresh context's. */
static void test_transform_change(void)
{
    vs_context *a = NULL, *b = NULL;
    if (vs_context_create(&a) != VS_OK || vs_context_create(&b) != VS_OK) return;
    vs_volume *v = tu_scene(a, "sphere:128");
    if (v) {
        vs_settings s;
        vs_settings_init(&s);
        s.width = s.height = 32;
        s.view = VS_VIEW_ANGLES;
        s.azimuth = 30, s.elevation = 20;
        s.has_center = 1;
        s.center[0] = 80, s.center[1] = 50, s.center[2] = 70;
        vs_image im = tu_render(a, v, &s, NULL);
        vs_image_free(&im);
        /* x flipped and the axes moved: a patient frame */
        const double m[12] = {-1, 0, 0, 127, 0, 0, 1, 10, 0, 1, 0, -5};
        CHECK(vs_volume_set_transform(a, v, m) == VS_OK, "set_transform: %s", vs_last_error(a));
        vs_stats sa;
        vs_image moved = tu_render(a, v, &s, &sa), fresh = tu_render(b, v, &s, NULL);
        CHECK(sa.lod_level >= 1 && tu_max_diff(&moved, &fresh) == 0.0,
              "after a new transform, level %d: the kept levels' frame differs from a fresh one by %g", sa.lod_level,
              tu_max_diff(&moved, &fresh));
        vs_image_free(&moved);
        vs_image_free(&fresh);
        vs_volume_release(v);
    }
    vs_context_release(a);
    vs_context_release(b);
}

/* A single slice is never halved (its plane would move against the
 * sheets), and with empty space visible the clip box stays at the full
 * volume's faces on odd sizes. */
static void test_thin_and_clip(vs_context *ctx)
{
    const int d[3] = {161, 161, 1};
    vs_volume *v = NULL;
    CHECK(vs_volume_create(ctx, VS_U8, d, NULL, &v) == VS_OK, "create");
    if (v) {
        uint8_t *u = vs_volume_data(v);
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++) u[j * d[0] + i] = hypot(i - 80.0, j - 80.0) < 60 ? 200 : 0;
        vs_volume_update_range(v);
        vs_settings s = iso_settings(40, 100, 20);
        s.iso_opacity = 0.5f;
        s.elevation = 80; /* nearly face-on */
        vs_stats a;
        vs_image lod = tu_render(ctx, v, &s, &a);
        s.lod_pixels = 0;
        vs_image full = tu_render(ctx, v, &s, NULL);
        const double ml = alpha_sum(&lod), mf = alpha_sum(&full);
        /* filtering the disc's edge moves some 8 %; a halved slice once
         * nearly doubled it */
        CHECK(a.lod_level >= 1 && fabs(ml - mf) < 0.15 * mf, "disc 161x161x1: level %d alpha %.1f, full %.1f",
              a.lod_level, ml, mf);
        printf("  disc 161x161x1 nearly face-on: level %d alpha sum %.1f, full resolution %.1f\n", a.lod_level, ml,
               mf);
        vs_image_free(&lod);
        vs_image_free(&full);
        vs_volume_release(v);
    }
    /* empty space visible: the whole 129^3 box is drawn; its image extent
     * must not grow with the level */
    const int e[3] = {129, 129, 129};
    CHECK(vs_volume_create(ctx, VS_U8, e, NULL, &v) == VS_OK, "create");
    if (!v) return;
    memset(vs_volume_data(v), 10, (size_t)129 * 129 * 129);
    vs_volume_update_range(v);
    vs_settings s = iso_settings(40, -50, 20);
    s.azimuth = 0, s.elevation = 0;
    s.iso_opacity = 0.02f;
    vs_stats a;
    vs_image lod = tu_render(ctx, v, &s, &a);
    s.lod_pixels = 0;
    vs_image full = tu_render(ctx, v, &s, NULL);
    int wl = 0, wf = 0;
    for (int x = 0; x < 40; x++) {
        wl += lod.rgba[4 * (20 * 40 + x) + 3] > 0.01f;
        wf += full.rgba[4 * (20 * 40 + x) + 3] > 0.01f;
    }
    CHECK(a.lod_level >= 1 && abs(wl - wf) <= 1, "box 129^3 with empty space visible: level %d %d px wide, full %d",
          a.lod_level, wl, wf);
    printf("  129^3 box, empty space visible: level %d %d px wide, full resolution %d\n", a.lod_level, wl, wf);
    vs_image_free(&lod);
    vs_image_free(&full);
    vs_volume_release(v);
}

static void test_accuracy(vs_context *ctx)
{
    vs_volume *v = tu_scene(ctx, "sphere:256");
    if (!v) return;
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 64;
    s.pipeline = VS_PIPELINE_RAYCAST;
    vs_image truth = tu_render(ctx, v, &s, NULL);
    s.pipeline = VS_PIPELINE_POST_CD;
    vs_stats a, b;
    s.threads = 2;
    vs_image lod = tu_render(ctx, v, &s, &a);
    /* one thread in a context of its own: the levels built on one thread */
    vs_context *c1 = NULL;
    vs_image one = {0, 0, NULL};
    s.threads = 1;
    if (vs_context_create(&c1) == VS_OK) one = tu_render(c1, v, &s, NULL);
    vs_context_release(c1);
    s.threads = 2;
    s.lod_pixels = 0;
    vs_image full = tu_render(ctx, v, &s, &b);
    const double pl = tu_psnr(ctx, &lod, &truth), pf = tu_psnr(ctx, &full, &truth);
    CHECK(a.lod_level == 2 && pl >= 42.0 && pl >= pf - 5.0, "sphere 256 at 64x64: level %d %.1f dB, full %.1f dB",
          a.lod_level, pl, pf);
    CHECK(tu_max_diff(&lod, &one) == 0.0, "1 and 2 threads differ by %g", tu_max_diff(&lod, &one));
    printf("  sphere:256 at 64x64 against the analytic ray caster: level %d %.1f dB in %.1f ms, full %.1f dB in "
           "%.1f ms\n",
           a.lod_level, pl, a.ms_total, pf, b.ms_total);
    vs_image_free(&truth);
    vs_image_free(&lod);
    vs_image_free(&one);
    vs_image_free(&full);
    vs_volume_release(v);
}

/* A shell one voxel thick (a cap of a sphere, like a CT headrest: air
 * -1000, the shell 2000) beside a smooth ball, at a size that splats level
 * 1: the filtered level averages the shell below the iso-value, so unless
 * the level keeps what the classification shows (lod_keep.c) the shell
 * leaves the picture.  Against the reference (full resolution at 4x the
 * size, box-filtered), the level must be within 1 dB of full resolution,
 * and the shell's coverage (alpha beside the ball) within 25 % of the
 * reference's; the ball, a smooth surface, must come out as the plain
 * level draws it (nothing raised there). */
static void test_thin_shell(vs_context *ctx)
{
    const int d[3] = {96, 96, 96};
    vs_volume *v = NULL, *ball = NULL;
    CHECK(vs_volume_create(ctx, VS_I16, d, NULL, &v) == VS_OK && vs_volume_create(ctx, VS_I16, d, NULL, &ball) == VS_OK,
          "create");
    if (!v || !ball) {
        vs_volume_release(v);
        vs_volume_release(ball);
        return;
    }
    int16_t *u = vs_volume_data(v), *b = vs_volume_data(ball);
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++) {
                const size_t at = ((size_t)k * d[1] + j) * d[0] + i;
                /* the ball: radius 14 at (40, 48, 48), a ramp 3 voxels wide */
                double t = (14.0 - sqrt((i - 40.0) * (i - 40.0) + (j - 48.0) * (j - 48.0) + (k - 48.0) * (k - 48.0))) / 3.0 + 0.5;
                t = t < 0 ? 0 : t > 1 ? 1 : t;
                b[at] = (int16_t)lrint(-1000.0 + 2000.0 * t);
                /* the shell: radius 40 about (20, 48, 48), one voxel thick, where x > 44 */
                const double r = sqrt((i - 20.0) * (i - 20.0) + (j - 48.0) * (j - 48.0) + (k - 48.0) * (k - 48.0));
                u[at] = fabs(r - 40.0) < 0.5 && i > 44 ? 2000 : b[at];
            }
    vs_volume_update_range(v);
    vs_volume_update_range(ball);
    vs_settings s = iso_settings(48, 300, 100);
    s.azimuth = 60, s.elevation = 20;
    s.threads = 2;
    vs_stats a;
    vs_image lod = tu_render(ctx, v, &s, &a), lod_ball = tu_render(ctx, ball, &s, NULL);
    /* the ball alone, a smooth surface, loses nothing: the plain level */
    CHECK(ctx->lod && ctx->lod->kept_done[1] && !ctx->lod->kept[1], "the smooth ball's level was patched");
    s.lod_pixels = 0;
    vs_image full = tu_render(ctx, v, &s, NULL);
    s.width = s.height = 4 * 48;
    vs_image big = tu_render(ctx, v, &s, NULL), big_ball = tu_render(ctx, ball, &s, NULL);
    vs_image ref = tu_shrink(&big, 4), ref_ball = tu_shrink(&big_ball, 4);
    const double pl = tu_psnr(ctx, &lod, &ref), pf = tu_psnr(ctx, &full, &ref);
    const double shell_lod = alpha_sum(&lod) - alpha_sum(&lod_ball), shell_ref = alpha_sum(&ref) - alpha_sum(&ref_ball);
    CHECK(a.lod_level == 1, "the thin shell at 48x48 splats level %d, not 1", a.lod_level);
    CHECK(pl >= pf - 1.0, "thin shell at level %d: %.1f dB against the reference, full resolution %.1f", a.lod_level,
          pl, pf);
    CHECK(shell_ref > 20.0 && fabs(shell_lod - shell_ref) < 0.25 * shell_ref,
          "thin shell's coverage (alpha sum): level %.1f, reference %.1f", shell_lod, shell_ref);
    printf("  shell one voxel thick by a ball, 48x48: level %d %.1f dB against the reference, full resolution %.1f; "
           "the shell's alpha sum %.1f, reference %.1f\n",
           a.lod_level, pl, pf, shell_lod, shell_ref);
    /* the patched level is the same for any thread count, and follows the
     * classification: another iso-value and back, in the same context,
     * draws what a fresh context draws */
    s.lod_pixels = 1;
    s.width = s.height = 48;
    s.threads = 1;
    vs_context *fresh = NULL;
    CHECK(vs_context_create(&fresh) == VS_OK, "context");
    vs_image one = tu_render(fresh, v, &s, NULL);
    CHECK(tu_max_diff(&one, &lod) == 0.0, "thin shell: 1 and 2 threads differ by %g", tu_max_diff(&one, &lod));
    s.threads = 2;
    s.iso_lo = 600;
    vs_image other = tu_render(ctx, v, &s, NULL), other_fresh = tu_render(fresh, v, &s, NULL);
    CHECK(tu_max_diff(&other, &lod) > 0.0 && tu_max_diff(&other, &other_fresh) == 0.0,
          "thin shell at iso 600: kept context and fresh one differ by %g", tu_max_diff(&other, &other_fresh));
    s.iso_lo = 300;
    vs_image back = tu_render(ctx, v, &s, NULL);
    CHECK(tu_max_diff(&back, &lod) == 0.0, "thin shell back at iso 300 differs by %g", tu_max_diff(&back, &lod));
    vs_context_release(fresh);
    vs_image *im[] = {&lod, &lod_ball, &full, &big, &big_ball, &ref, &ref_ball, &one, &other, &other_fresh, &back};
    for (size_t i = 0; i < sizeof im / sizeof im[0]; i++) vs_image_free(im[i]);
    vs_volume_release(v);
    vs_volume_release(ball);
}

/* Patching never invents a value: a raised level voxel stays at or under
 * the largest finer value beneath it (lod_keep.c), so the patched level
 * holds nothing above the volume's maximum.  A shell two voxels thick
 * whose value lies just over the iso band (u8: air 0, shell SHELL, iso
 * 100 ramp 40) is visible at full resolution; at level 1 reaching its
 * opacity would need more than SHELL, where the ceiling holds it. */
/* n^3 u8: `in` within half of radius r about c (where x > x_min), else
 * `out` */
static vs_volume *u8_shell(vs_context *ctx, int n, const double c[3], double r, double half, double x_min, int in,
                           int out)
{
    const int d[3] = {n, n, n};
    vs_volume *v = NULL;
    CHECK(vs_volume_create(ctx, VS_U8, d, NULL, &v) == VS_OK, "create");
    if (!v) return NULL;
    uint8_t *u = vs_volume_data(v);
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                const double q = sqrt((i - c[0]) * (i - c[0]) + (j - c[1]) * (j - c[1]) + (k - c[2]) * (k - c[2]));
                u[((size_t)k * n + j) * n + i] = (uint8_t)(fabs(q - r) < half && i > x_min ? in : out);
            }
    vs_volume_update_range(v);
    return v;
}

static void test_keep_ceiling(vs_context *ctx)
{
    enum { SHELL = 150 };
    static const double c[3] = {31.5, 31.5, 31.5};
    vs_volume *v = u8_shell(ctx, 64, c, 24.0, 1.0, -1.0, SHELL, 0);
    if (!v) return;
    vs_settings s = iso_settings(32, 100, 40);
    s.threads = 2;
    vs_stats a;
    vs_image im = tu_render(ctx, v, &s, &a);
    const vs_volume *kept = ctx->lod ? ctx->lod->kept[a.lod_level] : NULL;
    CHECK(a.lod_level >= 1 && kept, "the shell at 32x32: level %d, patched %d", a.lod_level, kept != NULL);
    if (kept) {
        const uint8_t *q = vs_volume_data((vs_volume *)kept);
        const size_t n = (size_t)kept->dims[0] * kept->dims[1] * kept->dims[2];
        int top = 0;
        for (size_t i = 0; i < n; i++) top = q[i] > top ? q[i] : top;
        CHECK(top <= SHELL, "a patched level voxel holds %d, above the volume's maximum %d", top, SHELL);
        printf("  shell of %d at level %d: the patched level's largest value %d\n", SHELL, a.lod_level, top);
    }
    vs_image_free(&im);
    vs_volume_release(v);
}

/* The same for a dark sheet in bright tissue under an iso-range with an
 * upper end (EM membranes at --iso 0:60): a shell one voxel thick of value
 * DARK in tissue of 200, range [10, 100] (the sheet reconstructs to about
 * 87 at its voxels), is averaged above the range at level 1, and patching
 * lowers it back, never under the least finer value beneath (so nothing
 * under DARK). */
static void test_dark_sheet(vs_context *ctx)
{
    enum { DARK = 30 };
    static const double c[3] = {20.0, 48.0, 48.0};
    vs_volume *v = u8_shell(ctx, 96, c, 40.0, 0.5, 44.0, DARK, 200);
    if (!v) return;
    vs_settings s = iso_settings(48, 10, 10);
    s.iso_hi = 100;
    s.iso_opacity = 0.6f;
    s.azimuth = 60, s.elevation = 20;
    s.threads = 2;
    vs_stats a;
    vs_image lod = tu_render(ctx, v, &s, &a);
    const vs_volume *kept = ctx->lod ? ctx->lod->kept[a.lod_level] : NULL;
    s.lod_pixels = 0;
    s.width = s.height = 4 * 48;
    vs_image big = tu_render(ctx, v, &s, NULL);
    vs_image ref = tu_shrink(&big, 4);
    const double al = alpha_sum(&lod), ar = alpha_sum(&ref);
    CHECK(a.lod_level == 1 && kept, "the dark sheet at 48x48: level %d, patched %d", a.lod_level, kept != NULL);
    /* unpatched the level shows none of it.  Under a range with an upper
     * end patching over-covers such a sheet in either direction (a bright
     * sheet in dark tissue, the range mirrored: 2.7x), as A is the opacity
     * at the finer voxels, where the sheet's reconstruction is in range
     * over less than a voxel */
    CHECK(ar > 20.0 && al > 0.5 * ar && al < 2.0 * ar, "dark sheet's coverage (alpha sum): level %.1f, reference %.1f",
          al, ar);
    int low = -1;
    if (kept) {
        const uint8_t *q = vs_volume_data((vs_volume *)kept);
        const size_t n = (size_t)kept->dims[0] * kept->dims[1] * kept->dims[2];
        low = 255;
        for (size_t i = 0; i < n; i++) low = q[i] < low ? q[i] : low;
        CHECK(low >= DARK, "a patched level voxel holds %d, under the volume's minimum %d", low, DARK);
    }
    printf("  dark sheet one voxel thick, 48x48: level %d alpha sum %.1f, reference %.1f; the patched level's least "
           "value %d\n",
           a.lod_level, al, ar, low);
    vs_image_free(&lod);
    vs_image_free(&big);
    vs_image_free(&ref);
    vs_volume_release(v);
}

static void test_cache(vs_context *ctx, vs_volume *v)
{
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 32;
    s.pipeline = VS_PIPELINE_POST_CD;
    vs_stats a;
    level_of(ctx, v, s, &a); /* built earlier by test_choice: kept */
    CHECK(a.lod_level == 2 && a.ms_lod == 0.0, "level %d: second frame rebuilt the levels (%.3f ms)", a.lod_level,
          a.ms_lod);
    /* full resolution in between keeps the level's relevant voxels */
    s.lod_pixels = 0;
    level_of(ctx, v, s, &a);
    s.lod_pixels = 1;
    level_of(ctx, v, s, &a);
    CHECK(a.lod_level == 2 && a.ms_relevant == 0.0, "back at level 2 the relevant voxels were rebuilt (%.3f ms)",
          a.ms_relevant);
    /* a new range keeps the levels (their voxels do not depend on it) but
     * classifies them anew: the frame a fresh context renders, bit for bit */
    double lo, hi;
    vs_volume_range(v, &lo, &hi);
    vs_image before = tu_render(ctx, v, &s, &a);
    const vs_volume *built[2] = {ctx->lod->level[1], ctx->lod->level[2]};
    const uint64_t built_serial[2] = {built[0]->data_serial, built[1]->data_serial};
    CHECK(vs_volume_set_range(v, lo, lo + 2.0 * (hi - lo)) == VS_OK, "set_range");
    vs_image kept = tu_render(ctx, v, &s, &a);
    CHECK(tu_max_diff(&before, &kept) > 0.0, "the range changed nothing in the frame: the test below is vacuous");
    vs_image_free(&before);
    /* (only what the new classification needs of them is worked out anew,
     * lod_keep.h: ms_lod may count that) */
    CHECK(a.lod_level == 2 && ctx->lod->level[1] == built[0] && ctx->lod->level[2] == built[1] &&
              built[0]->data_serial == built_serial[0] && built[1]->data_serial == built_serial[1],
          "a new range rebuilt the levels");
    vs_context *fresh = NULL;
    CHECK(vs_context_create(&fresh) == VS_OK, "context");
    vs_stats f;
    vs_image ref = tu_render(fresh, v, &s, &f);
    CHECK(f.lod_level == 2 && tu_max_diff(&kept, &ref) == 0.0,
          "after a new range the kept levels' frame differs from a fresh context's by %g", tu_max_diff(&kept, &ref));
    vs_image_free(&kept);
    vs_image_free(&ref);
    vs_context_release(fresh);
    CHECK(vs_volume_set_range(v, lo, hi) == VS_OK, "set_range back");
    /* vs_volume_update_range says the voxels may have changed: rebuilt */
    vs_volume_update_range((vs_volume *)v);
    level_of(ctx, v, s, &a);
    CHECK(a.ms_lod > 0.0, "a changed volume kept its old levels");
}

int main(void)
{
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return 1;
    test_filter(ctx);
    test_filter_definition(ctx);
    vs_volume *v = tu_scene(ctx, "sphere:128");
    if (v) {
        test_choice(ctx, v);
        test_cache(ctx, v);
        test_registration(ctx, v);
        test_translucent(ctx, v);
        vs_volume_release(v);
    }
    test_anisotropic(ctx);
    test_transform_change();
    test_thin_and_clip(ctx);
    test_thin_shell(ctx);
    test_keep_ceiling(ctx);
    test_dark_sheet(ctx);
    test_accuracy(ctx);
    vs_context_release(ctx);
    TEST_DONE();
}
