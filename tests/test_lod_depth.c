/* Levels of detail by depth (src/lod_depth.c): a perspective view down a
 * row of balls, whose far balls are seen several times smaller than its
 * near ones.
 *  - the view is split into bands whose levels grow with depth, each
 *    starting where vs_lod_choose_at allows the next level;
 *  - the band mechanics are exact: the frame split into two bands of the
 *    same level, the back one composited behind the front one's picture,
 *    is the unsplit frame (to float rounding and occlusion culling);
 *  - against the reference (full resolution at 4x the size, box-filtered)
 *    the banded frame is within 1 dB of full resolution or better, and
 *    splats fewer voxels than the frame of one level chosen at the nearest
 *    corner;
 *  - a translucent block seen through its depth has the alpha of the
 *    full-resolution frame: no sheet lost or doubled where bands meet;
 *  - 1 and 2 threads give the same image, every pipeline. */
#include "context.h"
#include "lod_depth.h"
#include "render.h"
#include "testutil.h"

/* balls of radius 9 every 32 voxels along z, 40 x 40 x 320, u8 with a
 * smooth edge two voxels wide */
static vs_volume *make_row(vs_context *ctx)
{
    const int d[3] = {40, 40, 320};
    vs_volume *v = NULL;
    if (vs_volume_create(ctx, VS_U8, d, NULL, &v) != VS_OK) return NULL;
    uint8_t *p = vs_volume_data(v);
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++) {
                const double x = i - 19.5, y = j - 19.5, z = fmod(k, 32.0) - 15.5;
                const double t = (9.0 - sqrt(x * x + y * y + z * z)) / 2.0 + 0.5;
                p[((size_t)k * d[1] + j) * d[0] + i] = (uint8_t)lrint(255.0 * (t < 0 ? 0 : t > 1 ? 1 : t));
            }
    vs_volume_update_range(v);
    return v;
}

/* Looking down the row from in front of its first ball. */
static vs_settings row_view(int size)
{
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = size;
    s.has_iso = 1, s.iso_lo = 128, s.iso_hi = INFINITY, s.ramp = 20;
    s.azimuth = 10, s.elevation = 80;
    s.perspective_fov = 60;
    s.zoom = 2.0;
    return s;
}

static int bands_of(vs_context *ctx, const vs_volume *v, const vs_settings *s, vs_lod_band *band)
{
    vs_camera cam;
    if (vs_camera_setup(ctx, v, s, &cam) != VS_OK) return 0;
    return vs_lod_bands(v, s, &cam, band);
}

static void test_bands(vs_context *ctx, const vs_volume *v)
{
    vs_settings s = row_view(64);
    vs_lod_band band[VS_LOD_MAX + 1];
    const int n = bands_of(ctx, v, &s, band);
    int grows = n >= 2;
    for (int b = 1; b < n; b++) grows &= band[b].level > band[b - 1].level && band[b].z0 == band[b - 1].z1;
    CHECK(grows, "%d bands, levels not growing with depth", n);
    printf("  64x64: %d bands:", n);
    for (int b = 0; b < n; b++) printf(" level %d from %.1f mm;", band[b].level, band[b].z0);
    printf("\n");
    s.perspective_fov = 0;
    CHECK(bands_of(ctx, v, &s, band) == 1, "orthographic: more than one band");
}

/* Two bands of level 0 split at depths through the row (every 8 mm, so
 * that splits cut balls: pixels half covered in front and more opaque
 * behind), the back band composited behind the front one's picture,
 * against the unsplit frame: float rounding apart (above 100 dB), the
 * same; a band one sheet short gives 47 dB. */
static void test_exact_split(vs_context *ctx, const vs_volume *v)
{
    static const vs_pipeline pipes[] = {VS_PIPELINE_POST_CD, VS_PIPELINE_POST_ALPHA};
    for (int p = 0; p < 2; p++) {
        vs_settings s = row_view(64);
        s.pipeline = pipes[p];
        s.background[0] = 0.2f, s.background[1] = 0.3f, s.background[2] = 0.4f, s.background[3] = 1.0f;
        vs_settings clear = s;
        for (int c = 0; c < 4; c++) clear.background[c] = 0.0f;
        struct vs_relevant_cache *rel = NULL;
        double worst = INFINITY;
        int cut = 0; /* splits with pixels seen on both sides */
        for (int t = 0; t < 21; t++) {
            const double zs = -160.0 + 8.0 * t;
            vs_image whole = {0, 0, NULL}, front = {0, 0, NULL}, back = {0, 0, NULL};
            const vs_lod_band fb = {0, -INFINITY, zs}, bb = {0, zs, INFINITY};
            vs_classify *c[3];
            int ok = 1;
            for (int i = 0; i < 3; i++) {
                c[i] = malloc(sizeof *c[i]);
                if (!c[i] || vs_classify_setup(ctx, v, &s, c[i]) != VS_OK) ok = 0;
            }
            if (!ok)
                for (int i = 0; i < 3; i++) free(c[i]);
            /* each frame takes its classification, whatever happens */
            ok = ok && vs_render_splat(ctx, v, v, c[0], &rel, &s, NULL, NULL, &whole, NULL, NULL) == VS_OK;
            ok = ok && vs_render_splat(ctx, v, v, c[1], &rel, &clear, &fb, NULL, &front, NULL, NULL) == VS_OK;
            ok = ok && vs_render_splat(ctx, v, v, c[2], &rel, &clear, &bb, front.rgba, &back, NULL, NULL) == VS_OK;
            CHECK(ok, "split frames: %s", vs_last_error(ctx));
            if (ok) {
                int both = 0; /* pixels half covered in front, more behind */
                for (size_t i = 0; i < (size_t)64 * 64; i++)
                    both += front.rgba[4 * i + 3] > 0.05f && front.rgba[4 * i + 3] < 0.95f &&
                            back.rgba[4 * i + 3] > front.rgba[4 * i + 3] + 0.05f;
                cut += both > 0;
                vs_image_background(back.rgba, (size_t)64 * 64, s.background);
                const double db = tu_psnr(ctx, &whole, &back);
                worst = db < worst ? db : worst;
            }
            vs_image_free(&whole);
            vs_image_free(&front);
            vs_image_free(&back);
        }
        CHECK(worst > 100.0 && cut >= 5, "pipeline %d: split frames %.1f dB from the unsplit one at worst, %d of 21 "
              "splits through a ball", pipes[p], worst, cut);
        printf("  pipeline %d, 21 splits (%d through a ball): at worst %.1f dB from the unsplit frame\n", pipes[p],
               cut, worst);
        vs_relevant_cache_free(rel);
    }
}

static void test_quality(vs_context *ctx, const vs_volume *v)
{
    vs_settings s = row_view(64);
    vs_settings big = row_view(256);
    big.lod_pixels = 0;
    vs_image ref4 = tu_render(ctx, v, &big, NULL), ref = tu_shrink(&ref4, 4);
    vs_stats a, f, one;
    vs_image lod = tu_render(ctx, v, &s, &a);
    s.lod_pixels = 0;
    vs_image full = tu_render(ctx, v, &s, &f);
    const double dl = tu_psnr(ctx, &ref, &lod), df = tu_psnr(ctx, &ref, &full);
    /* the level the nearest corner allows, for the whole view: how the
     * bands' frame would be without them */
    vs_lod_band band[VS_LOD_MAX + 1];
    s.lod_pixels = 1;
    bands_of(ctx, v, &s, band);
    s.lod_pixels = band[0].level > 0 ? 1 : 0;
    vs_image near = tu_render(ctx, v, &s, &one);
    CHECK(dl > df - 1.0, "bands %.2f dB against the reference, full resolution %.2f", dl, df);
    CHECK(a.voxels_splatted < one.voxels_splatted * 0.8, "bands splatted %llu, one level %llu",
          (unsigned long long)a.voxels_splatted, (unsigned long long)one.voxels_splatted);
    printf("  64x64 against the reference: bands %.2f dB (%llu voxels splatted), full resolution %.2f dB (%llu)\n", dl,
           (unsigned long long)a.voxels_splatted, df, (unsigned long long)f.voxels_splatted);
    vs_image_free(&ref4);
    vs_image_free(&ref);
    vs_image_free(&lod);
    vs_image_free(&full);
    vs_image_free(&near);
}

/* A translucent block seen through its whole depth: every sheet adds the
 * same opacity, so a band boundary that lost or doubled a sheet shows as a
 * change of the alpha through the block's middle, where the levels hold
 * the same constant value. */
static void test_no_gap(vs_context *ctx)
{
    const int d[3] = {40, 40, 320};
    vs_volume *v = NULL;
    if (vs_volume_create(ctx, VS_U8, d, NULL, &v) != VS_OK) {
        CHECK(0, "block: %s", vs_last_error(ctx));
        return;
    }
    uint8_t *p = vs_volume_data(v);
    for (int k = 6; k < d[2] - 6; k++)
        for (int j = 6; j < d[1] - 6; j++)
            for (int i = 6; i < d[0] - 6; i++) p[((size_t)k * d[1] + j) * d[0] + i] = 200;
    vs_volume_update_range(v);
    vs_settings s = row_view(64);
    s.azimuth = 0, s.elevation = 90; /* straight down the block, from outside it */
    s.zoom = 1.0;
    s.iso_lo = 100, s.ramp = 10, s.iso_opacity = 0.004f;
    vs_lod_band band[VS_LOD_MAX + 1];
    const int n = bands_of(ctx, v, &s, band);
    /* plain sheets own [k, k + 1) slabs and meet exactly; pre-integrated
     * ones own the segment from their middle to the next's, which on a
     * coarser level's grid is half a finer sheet off: allowed that */
    for (int pre = 0; pre < 2; pre++) {
        s.preintegration = pre ? -1 : 0;
        s.lod_pixels = 1;
        vs_image lod = tu_render(ctx, v, &s, NULL);
        s.lod_pixels = 0;
        vs_image full = tu_render(ctx, v, &s, NULL);
        double worst = 0.0, mid = 0.0;
        if (lod.rgba && full.rgba)
            for (int y = 31; y < 33; y++) /* through the block's middle, away from its sides */
                for (int x = 31; x < 33; x++) {
                    const size_t o = 4 * ((size_t)y * 64 + x) + 3;
                    const double e = fabs(lod.rgba[o] - full.rgba[o]);
                    worst = e > worst ? e : worst;
                    mid = full.rgba[o];
                }
        const double tol = pre ? 3e-3 : 3e-4;
        CHECK(n >= 2 && mid > 0.3 && mid < 0.9 && worst < tol,
              "translucent block, %d bands, %s: alpha %.4f, banded off by %.5f", n, pre ? "pre-integrated" : "plain",
              mid, worst);
        printf("  translucent block, %d bands, %s sheets: alpha through the middle %.4f, banded off by at most "
               "%.5f\n", n, pre ? "pre-integrated" : "plain", mid, worst);
        vs_image_free(&lod);
        vs_image_free(&full);
    }
    vs_volume_release(v);
}

/* A cancel answered once, at the first call at or past the first band's
 * end: that call is the band's closing one, which a single frame ignores;
 * between bands it must cancel the view (it was dropped, and the view
 * rendered on). */
typedef struct once {
    double at;
    int answered;
} once;

static int cancel_once(void *user, double fraction)
{
    once *o = user;
    if (o->answered || fraction < o->at) return 0;
    o->answered = 1;
    return 1;
}

static void test_cancel(vs_context *ctx, const vs_volume *v)
{
    vs_settings s = row_view(48);
    vs_lod_band band[VS_LOD_MAX + 1];
    const int n = bands_of(ctx, v, &s, band);
    if (n < 2) {
        CHECK(0, "the row's view has %d band", n);
        return;
    }
    for (int threads = 1; threads <= 2; threads++) {
        once o = {1.0 / n - 1e-9, 0};
        s.threads = threads;
        s.progress = cancel_once;
        s.progress_user = &o;
        vs_image img = {0, 0, NULL};
        const vs_status st = vs_render(ctx, v, &s, &img, NULL);
        CHECK(st == VS_ERR_CANCELLED, "%d threads: cancel at %.3f of %d bands: %s", threads, o.at, n,
              vs_status_string(st));
        CHECK(img.rgba == NULL, "a cancelled view left an image");
        vs_image_free(&img);
    }
    printf("  a cancel answered once at the first band's end: cancelled\n");
}

static void test_threads(vs_context *ctx, const vs_volume *v)
{
    static const vs_pipeline pipes[] = {VS_PIPELINE_PRE, VS_PIPELINE_POST_CD, VS_PIPELINE_POST_GS,
                                        VS_PIPELINE_POST_ALPHA};
    for (int p = 0; p < 4; p++) {
        vs_settings s = row_view(48);
        s.pipeline = pipes[p];
        s.threads = 1;
        vs_image a = tu_render(ctx, v, &s, NULL);
        s.threads = 2;
        vs_image b = tu_render(ctx, v, &s, NULL);
        CHECK(a.rgba && b.rgba && !memcmp(a.rgba, b.rgba, (size_t)48 * 48 * 4 * sizeof(float)),
              "pipeline %d: 1 and 2 threads differ", pipes[p]);
        vs_image_free(&a);
        vs_image_free(&b);
    }
}

int main(void)
{
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return 1;
    vs_volume *v = make_row(ctx);
    CHECK(v != NULL, "volume");
    if (v) {
        test_bands(ctx, v);
        test_exact_split(ctx, v);
        test_quality(ctx, v);
        test_threads(ctx, v);
        test_cancel(ctx, v);
        vs_volume_release(v);
    }
    test_no_gap(ctx);
    vs_context_release(ctx);
    TEST_DONE();
}
