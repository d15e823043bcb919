/* Hostile input (issue 7, part 2), at the C API level:
 *  - every public function of vsplat.h with NULL pointers and nonsense
 *    values returns the matching status (or, for void functions, does
 *    nothing) instead of crashing, and leaves outputs cleared;
 *  - malformed transfer functions (NaN, out of order, alpha > 1, colours
 *    outside [0,1], a negative count);
 *  - the NaN/Inf voxel policy: non-finite voxels are accepted, ignored for
 *    the value range and the default iso-value, and rendered as 0 by every
 *    pipeline and the ray caster: the image is finite and (nearly) the image
 *    of the same volume with those voxels set to 0;
 *  - loaders fed truncated, oversized and malformed NIfTI / NRRD / TIFF /
 *    PNG / .den / raw / tar files beyond tests/test_load.c: a status, a
 *    message naming the file, and quickly;
 *  - unwritable output paths leave nothing behind;
 *  - the shading table with NaN, infinite and tiny gradients.
 * Memory bounds (ulimit -v) are checked by tests/cli_hostile.sh. */
#include "internal.h"
#include "shade_lut.h"
#include "oiio_adapter.h"
#include "testutil.h"

#include <bzlib.h>
#include <dirent.h>
#include <float.h>
#include <math.h>
#include <time.h>
#include <unistd.h>
#include <zlib.h>

static vs_context *ctx;
static char tmp[1024];

static void path_of(char *buf, size_t cap, const char *name) { snprintf(buf, cap, "%s/%s", tmp, name); }

static int image_finite(const vs_image *img)
{
    if (!img->rgba) return 0;
    for (size_t i = 0; i < (size_t)img->width * img->height * 4; i++)
        if (!isfinite(img->rgba[i])) return 0;
    return 1;
}

/* ------------------------------------------------------------ the API */

static void test_context_and_names(void)
{
    CHECK(vs_context_create(NULL) == VS_ERR_INVALID_ARGUMENT, "context_create(NULL)");
    vs_context_release(NULL);
    CHECK(vs_last_error(NULL) && *vs_last_error(NULL), "last_error(NULL)");
    CHECK(vs_status_string((vs_status)999) != NULL, "status_string(999)");
    CHECK(vs_status_string((vs_status)-1) != NULL, "status_string(-1)");
    CHECK(vs_version() && *vs_version(), "version");
    vs_settings_init(NULL);
    CHECK(!strcmp(vs_pipeline_name((vs_pipeline)-1), "unknown"), "pipeline_name(-1)");
    CHECK(!strcmp(vs_pipeline_name((vs_pipeline)99), "unknown"), "pipeline_name(99)");
    vs_pipeline p = VS_PIPELINE_PRE;
    CHECK(vs_pipeline_parse(NULL, &p) == VS_ERR_INVALID_ARGUMENT, "pipeline_parse(NULL)");
    CHECK(vs_pipeline_parse("pre", NULL) == VS_ERR_INVALID_ARGUMENT, "pipeline_parse(out NULL)");
    CHECK(vs_pipeline_parse("", &p) == VS_ERR_INVALID_ARGUMENT, "pipeline_parse('')");
    CHECK(vs_pipeline_parse("post-cdX", &p) == VS_ERR_INVALID_ARGUMENT, "pipeline_parse(post-cdX)");
    CHECK(!strcmp(vs_isa_name((vs_isa)-3), "unknown"), "isa_name(-3)");
    CHECK(!strcmp(vs_isa_name((vs_isa)42), "unknown"), "isa_name(42)");
    vs_isa isa;
    CHECK(vs_isa_parse(NULL, &isa) == VS_ERR_INVALID_ARGUMENT, "isa_parse(NULL)");
    CHECK(vs_isa_parse("avx2", NULL) == VS_ERR_INVALID_ARGUMENT, "isa_parse(out NULL)");
    CHECK(vs_isa_parse("mmx", &isa) == VS_ERR_INVALID_ARGUMENT, "isa_parse(mmx)");
    vs_isa d = vs_isa_detect();
    CHECK((int)d >= VS_ISA_SCALAR && (int)d <= VS_ISA_AVX512, "isa_detect %d", (int)d);
    vs_load_options_init(NULL);
    CHECK(!strcmp(vs_type_name((vs_type)77), "unknown"), "type_name(77)");
    /* stats JSON: NULL stats, NULL buffer, tiny buffers stay terminated */
    size_t need = vs_stats_to_json(NULL, NULL, 0);
    CHECK(need > 10, "stats_to_json(NULL) needs %zu", need);
    char small[8];
    memset(small, 'x', sizeof small);
    vs_stats_to_json(NULL, small, sizeof small);
    CHECK(memchr(small, '\0', sizeof small) != NULL, "stats_to_json truncation not terminated");
    vs_stats st;
    memset(&st, 0, sizeof st); /* NULL pipeline/isa strings */
    st.struct_size = sizeof st;
    char *buf = malloc(need + 1);
    CHECK(vs_stats_to_json(&st, buf, need + 1) == need, "stats_to_json sizes");
    free(buf);
}

/* The default iso-value (Otsu, a pass over the whole volume) is kept in the
 * context per volume, not recomputed each frame: data rewritten in place
 * (vs_volume_update_range) must give the new volume's value. */
static void test_default_iso_follows_data(void)
{
    const int dims[3] = {16, 16, 16};
    vs_volume *v = NULL;
    if (vs_volume_create(ctx, VS_F32, dims, NULL, &v) != VS_OK) {
        CHECK(0, "create: %s", vs_last_error(ctx));
        return;
    }
    float *f = vs_volume_data(v);
    for (int i = 0; i < 16 * 16 * 16; i++) f[i] = (i % 16) < 8 ? 10.0f : 90.0f + (float)(i % 3);
    vs_volume_update_range(v);
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 16;
    vs_image img = {0, 0, NULL};
    vs_stats st;
    for (int round = 0; round < 2; round++) {
        double want = vs_volume_default_iso(v);
        CHECK(vs_render(ctx, v, &s, &img, &st) == VS_OK, "render: %s", vs_last_error(ctx));
        vs_image_free(&img);
        CHECK(st.iso_lo == want, "round %d: default iso %g, the volume's is %g", round, st.iso_lo, want);
        for (int i = 0; i < 16 * 16 * 16; i++) f[i] = 4.0f * f[i] + 1000.0f; /* the next round's data */
        vs_volume_update_range(v);
    }
    vs_volume_release(v);
}

static void test_volume_api(void)
{
    vs_volume *v = (vs_volume *)1;
    int dims[3] = {4, 4, 4};
    CHECK(vs_volume_create(ctx, VS_U8, NULL, NULL, &v) == VS_ERR_INVALID_ARGUMENT, "create(dims NULL)");
    CHECK(vs_volume_create(ctx, VS_U8, dims, NULL, NULL) == VS_ERR_INVALID_ARGUMENT, "create(out NULL)");
    CHECK(vs_volume_create(NULL, VS_U8, dims, NULL, NULL) == VS_ERR_INVALID_ARGUMENT, "create(ctx NULL)");
    v = (vs_volume *)1;
    CHECK(vs_volume_create(ctx, (vs_type)9, dims, NULL, &v) == VS_ERR_INVALID_ARGUMENT && v == NULL,
          "create(type 9)");
    const int bad_dims[][3] = {{0, 4, 4}, {4, -1, 4}, {4, 4, VS_MAX_DIM + 1}, {INT32_MIN, 1, 1},
                               {VS_MAX_DIM, VS_MAX_DIM, VS_MAX_DIM}};
    for (int i = 0; i < 5; i++) {
        v = (vs_volume *)1;
        vs_status st = vs_volume_create(ctx, VS_F32, bad_dims[i], NULL, &v);
        CHECK(st == VS_ERR_TOO_LARGE && v == NULL, "create(dims %d,%d,%d): %s", bad_dims[i][0], bad_dims[i][1],
              bad_dims[i][2], vs_status_string(st));
    }
    const double bad_sp[][3] = {{0, 1, 1}, {1, -1, 1}, {1, 1, NAN}, {INFINITY, 1, 1}, {1e-300, 1, 1}};
    for (int i = 0; i < 5; i++) {
        v = (vs_volume *)1;
        vs_status st = vs_volume_create(ctx, VS_F32, dims, bad_sp[i], &v);
        CHECK(st == VS_ERR_INVALID_ARGUMENT && v == NULL, "create(spacing %g,%g,%g): %s", bad_sp[i][0],
              bad_sp[i][1], bad_sp[i][2], vs_status_string(st));
    }
    /* accessors of NULL volumes and NULL outputs */
    vs_volume_release(NULL);
    CHECK(vs_volume_data(NULL) == NULL, "data(NULL)");
    int d[3] = {7, 7, 7};
    double sp[3] = {7, 7, 7}, lo = 7, hi = 7;
    vs_volume_dims(NULL, d);
    CHECK(d[0] == 0 && d[1] == 0 && d[2] == 0, "dims(NULL)");
    vs_volume_spacing(NULL, sp);
    CHECK(sp[0] == 0, "spacing(NULL)");
    vs_volume_range(NULL, &lo, &hi);
    CHECK(lo == 0 && hi == 0, "range(NULL)");
    vs_volume_update_range(NULL);
    (void)vs_volume_type(NULL);
    CHECK(isfinite(vs_volume_default_iso(NULL)), "default_iso(NULL)");
    CHECK(vs_volume_has_analytic(NULL) == 0, "has_analytic(NULL)");
    CHECK(vs_volume_create(ctx, VS_U8, dims, NULL, &v) == VS_OK, "create 4^3");
    vs_volume_dims(v, NULL);
    vs_volume_spacing(v, NULL);
    vs_volume_range(v, NULL, NULL);
    vs_volume_release(v);

    /* scenes */
    const char *bad_scenes[] = {"", "sphere:", "sphere:0", "sphere:1", "sphere:-5", "sphere:abc", "sphere:5x",
                                "sphere:99999999999999999999", "nope", ":4", "cube:7",
                                "a-very-long-scene-name-that-does-not-fit-the-buffer:4"};
    for (size_t i = 0; i < sizeof bad_scenes / sizeof bad_scenes[0]; i++) {
        v = (vs_volume *)1;
        vs_status st = vs_volume_scene(ctx, bad_scenes[i], &v);
        CHECK(st == VS_ERR_INVALID_ARGUMENT && v == NULL, "scene '%s': %s", bad_scenes[i], vs_status_string(st));
    }
    v = (vs_volume *)1;
    CHECK(vs_volume_scene(ctx, NULL, &v) == VS_ERR_INVALID_ARGUMENT && v == NULL, "scene(NULL)");
    CHECK(vs_volume_scene(ctx, "sphere", NULL) == VS_ERR_INVALID_ARGUMENT, "scene(out NULL)");
    CHECK(vs_volume_scene(NULL, "nope", &v) == VS_ERR_INVALID_ARGUMENT, "scene(ctx NULL)");

    /* loading: NULL and nonsense options */
    v = (vs_volume *)1;
    CHECK(vs_volume_load(ctx, NULL, NULL, &v) == VS_ERR_INVALID_ARGUMENT && v == NULL, "load(path NULL)");
    CHECK(vs_volume_load(ctx, "x.nii", NULL, NULL) == VS_ERR_INVALID_ARGUMENT, "load(out NULL)");
    CHECK(vs_volume_load(ctx, "", NULL, &v) == VS_ERR_INVALID_ARGUMENT, "load('')");
    CHECK(vs_volume_load(NULL, "/nonexistent/x.nii", NULL, &v) != VS_OK && v == NULL, "load(ctx NULL)");
    char path[1100];
    path_of(path, sizeof path, "opts.raw");
    unsigned char bytes[64] = {0};
    tu_write_file(path, bytes, sizeof bytes);
    vs_load_options o;
    struct {
        int dims[3];
        int type, endian;
        double sp;
        vs_status want;
    } oc[] = {
        {{4, 4, 4}, 99, 0, 1, VS_ERR_INVALID_ARGUMENT},  {{4, 4, 4}, VS_U8, 7, 1, VS_ERR_INVALID_ARGUMENT},
        {{4, 4, -4}, VS_U8, 0, 1, VS_ERR_FORMAT},         {{4, 4, 4}, VS_U8, 0, NAN, VS_ERR_INVALID_ARGUMENT},
        {{4, 4, 4}, VS_U8, 0, -1, VS_ERR_INVALID_ARGUMENT}, {{4, 4, 4}, VS_U8, 0, 0, VS_ERR_INVALID_ARGUMENT},
        {{4, 4, 4}, VS_U8, 0, INFINITY, VS_ERR_INVALID_ARGUMENT},
        {{16384, 16384, 16384}, VS_I16, 0, 1, VS_ERR_TOO_LARGE},
        {{65536, 65536, 1}, VS_U8, 0, 1, VS_ERR_TOO_LARGE},
    };
    for (size_t i = 0; i < sizeof oc / sizeof oc[0]; i++) {
        vs_load_options_init(&o);
        o.raw = 1;
        memcpy(o.dims, oc[i].dims, sizeof o.dims);
        o.type = (vs_type)oc[i].type;
        o.endian = (vs_endian)oc[i].endian;
        if (oc[i].sp != 1) {
            o.has_spacing = 1;
            o.spacing[2] = oc[i].sp;
        }
        v = (vs_volume *)1;
        vs_status st = vs_volume_load(ctx, path, &o, &v);
        CHECK(st == oc[i].want && v == NULL, "raw option case %zu: %s (%s), want %s", i, vs_status_string(st),
              vs_last_error(ctx), vs_status_string(oc[i].want));
        CHECK(strstr(vs_last_error(ctx), "opts.raw") != NULL, "raw option case %zu: message '%s'", i,
              vs_last_error(ctx));
    }
}

static int cancel_now(void *user, double f)
{
    (void)f;
    (*(int *)user)++;
    return 1;
}

static void test_render_api(void)
{
    vs_volume *v = tu_scene(ctx, "sphere:16");
    if (!v) return;
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 24;
    vs_image img = {5, 5, (float *)1};
    vs_stats st;
    CHECK(vs_render(NULL, v, &s, &img, &st) == VS_ERR_INVALID_ARGUMENT, "render(ctx NULL)");
    CHECK(vs_render(ctx, NULL, &s, &img, &st) == VS_ERR_INVALID_ARGUMENT, "render(vol NULL)");
    CHECK(vs_render(ctx, v, NULL, &img, &st) == VS_ERR_INVALID_ARGUMENT, "render(settings NULL)");
    CHECK(vs_render(ctx, v, &s, NULL, &st) == VS_ERR_INVALID_ARGUMENT, "render(out NULL)");
    CHECK(vs_render(ctx, v, &s, &img, NULL) == VS_OK, "render(stats NULL): %s", vs_last_error(ctx));
    vs_image_free(&img);
    vs_image_free(NULL);

    /* nonsense settings: each must give the status, a message, a cleared
     * image, for every pipeline */
    static vs_tf_point tf_nan[2] = {{0.0, 1, 1, 1, 0}, {NAN, 1, 1, 1, 1}};
    static vs_tf_point tf_order[3] = {{0.0, 1, 1, 1, 0}, {0.8, 1, 1, 1, 1}, {0.4, 1, 1, 1, 1}};
    static vs_tf_point tf_alpha[2] = {{0.0, 1, 1, 1, 0}, {1.0, 1, 1, 1, 1.5f}};
    static vs_tf_point tf_color[2] = {{0.0, 1, 1, 1, 0}, {1.0, -0.1f, 1, 1, 1}};
    static vs_tf_point tf_inf[2] = {{-INFINITY, 1, 1, 1, 0}, {1.0, 1, 1, 1, 1}};
    static vs_tf_point tf_nan_a[2] = {{0.0, 1, 1, 1, 0}, {1.0, 1, 1, 1, NAN}};
    struct {
        const char *what;
        vs_status want;
        vs_settings s;
    } cases[64];
    int nc = 0;
#define ADD(desc, status, stmt)                                                                                   \
    do {                                                                                                          \
        cases[nc].what = desc;                                                                                    \
        cases[nc].want = status;                                                                                  \
        vs_settings_init(&cases[nc].s);                                                                           \
        cases[nc].s.width = cases[nc].s.height = 24;                                                              \
        {                                                                                                         \
            vs_settings *x = &cases[nc].s;                                                                        \
            stmt;                                                                                                 \
        }                                                                                                         \
        nc++;                                                                                                     \
    } while (0)
    const vs_status INV = VS_ERR_INVALID_ARGUMENT;
    ADD("width 0", INV, x->width = 0);
    ADD("height -5", INV, x->height = -5);
    ADD("width 1e6", INV, x->width = 1000000);
    ADD("zoom 0", INV, x->zoom = 0);
    ADD("zoom NaN", INV, x->zoom = NAN);
    ADD("zoom -1", INV, x->zoom = -1);
    ADD("zoom inf", INV, x->zoom = INFINITY);
    ADD("azimuth NaN", INV, x->azimuth = NAN);
    ADD("elevation inf", INV, x->elevation = INFINITY);
    ADD("center NaN", INV, (x->has_center = 1, x->center[1] = NAN));
    ADD("perspective NaN", INV, x->perspective_fov = NAN);
    ADD("perspective -1", INV, x->perspective_fov = -1);
    ADD("perspective 180", INV, x->perspective_fov = 180);
    ADD("perspective inf", INV, x->perspective_fov = INFINITY);
    ADD("slab 0", INV, x->slab = 0);
    ADD("slab NaN", INV, x->slab = NAN);
    ADD("slab -1", INV, x->slab = -1);
    ADD("slab 1e9", INV, x->slab = 1e9);
    ADD("kernel radius NaN", INV, x->kernel_radius = NAN);
    ADD("kernel radius 0", INV, x->kernel_radius = 0);
    ADD("kernel radius 100", INV, x->kernel_radius = 100);
    ADD("footprint resolution 0", INV, x->footprint_resolution = 0);
    ADD("depth resolution -1", INV, x->depth_resolution = -1);
    ADD("seam -2", INV, x->seam = -2);
    ADD("seam 1000", INV, x->seam = 1000);
    ADD("iso NaN", INV, (x->has_iso = 1, x->iso_lo = NAN));
    ADD("iso hi NaN", INV, (x->has_iso = 1, x->iso_lo = 0.5, x->iso_hi = NAN));
    ADD("iso hi < lo", INV, (x->has_iso = 1, x->iso_lo = 0.5, x->iso_hi = 0.2));
    ADD("ramp inf", INV, (x->has_iso = 1, x->iso_lo = 0.5, x->ramp = INFINITY));
    ADD("ramp NaN", INV, (x->has_iso = 1, x->iso_lo = 0.5, x->ramp = NAN));
    ADD("iso opacity 2", INV, x->iso_opacity = 2.0f);
    ADD("iso opacity NaN", INV, x->iso_opacity = NAN);
    ADD("iso opacity -1", INV, x->iso_opacity = -1.0f);
    ADD("material NaN", INV, x->material[1] = NAN);
    ADD("material 2", INV, x->material[0] = 2.0f);
    ADD("tf NULL", INV, (x->tf = NULL, x->tf_count = 2));
    ADD("tf count -1", INV, (x->tf = tf_alpha, x->tf_count = -1));
    ADD("tf value NaN", INV, (x->tf = tf_nan, x->tf_count = 2));
    ADD("tf out of order", INV, (x->tf = tf_order, x->tf_count = 3));
    ADD("tf alpha 1.5", INV, (x->tf = tf_alpha, x->tf_count = 2));
    ADD("tf colour -0.1", INV, (x->tf = tf_color, x->tf_count = 2));
    ADD("tf value -inf", INV, (x->tf = tf_inf, x->tf_count = 2));
    ADD("tf alpha NaN", INV, (x->tf = tf_nan_a, x->tf_count = 2));
    ADD("ambient NaN", INV, x->ambient = NAN);
    ADD("diffuse -1", INV, x->diffuse = -1);
    ADD("shininess inf", INV, x->shininess = INFINITY);
    ADD("background NaN", INV, x->background[0] = NAN);
    ADD("background alpha 2", INV, x->background[3] = 2);
    ADD("occlusion threshold 0", INV, x->occlusion_threshold = 0);
    ADD("occlusion threshold NaN", INV, x->occlusion_threshold = NAN);
    ADD("tile size 0", INV, x->tile_size = 0);
    ADD("tile size 1e6", INV, x->tile_size = 1000000);
    ADD("normal LUT 0", INV, x->normal_lut_size = 0);
    ADD("threads -1", INV, x->threads = -1);
    ADD("threads 100000", INV, x->threads = 100000);
    ADD("isa 99", INV, x->isa = (vs_isa)99);
    ADD("pipeline 99", INV, x->pipeline = (vs_pipeline)99);
    ADD("pipeline -1", INV, x->pipeline = (vs_pipeline)-1);
    ADD("ray step 0", INV, (x->pipeline = VS_PIPELINE_RAYCAST, x->ray_step = 0));
    ADD("ray step NaN", INV, (x->pipeline = VS_PIPELINE_RAYCAST, x->ray_step = NAN));
#undef ADD
    for (int c = 0; c < nc; c++) {
        int pls = cases[c].s.pipeline == VS_PIPELINE_PRE ? 5 : 1; /* default pipeline: try all five */
        for (int p = 0; p < pls; p++) {
            vs_settings x = cases[c].s;
            if (pls == 5) x.pipeline = (vs_pipeline)p;
            vs_image im = {3, 3, (float *)1};
            memset(ctx->error, 0, sizeof ctx->error);
            vs_status rc = vs_render(ctx, v, &x, &im, &st);
            CHECK(rc == cases[c].want, "%s (%s): got %s (%s), want %s", cases[c].what,
                  vs_pipeline_name(x.pipeline), vs_status_string(rc), vs_last_error(ctx),
                  vs_status_string(cases[c].want));
            CHECK(im.rgba == NULL && im.width == 0, "%s: output not cleared", cases[c].what);
            CHECK(*vs_last_error(ctx), "%s: no message", cases[c].what);
            if (rc == VS_OK) vs_image_free(&im);
        }
    }
    /* settings that are odd but defined: a zero or NaN light direction falls
     * back to the headlight; any non-zero flag counts as "on" */
    for (int p = 0; p <= VS_PIPELINE_RAYCAST; p++) {
        vs_settings x;
        vs_settings_init(&x);
        x.width = x.height = 24;
        x.pipeline = (vs_pipeline)p;
        x.headlight = 0;
        x.light_dir[0] = NAN;
        x.occlusion = 7;
        x.exact_normals = -3;
        vs_image im;
        vs_status rc = vs_render(ctx, v, &x, &im, &st);
        CHECK(rc == VS_OK && image_finite(&im), "%s: NaN light: %s", vs_pipeline_name(x.pipeline), vs_last_error(ctx));
        if (rc == VS_OK) vs_image_free(&im);
    }
    /* the progress callback cancels */
    int calls = 0;
    for (int p = 0; p <= VS_PIPELINE_RAYCAST; p++) {
        vs_settings x;
        vs_settings_init(&x);
        x.width = x.height = 24;
        x.pipeline = (vs_pipeline)p;
        x.progress = cancel_now;
        x.progress_user = &calls;
        vs_image im = {1, 1, (float *)1};
        vs_status rc = vs_render(ctx, v, &x, &im, &st);
        /* the splatting pipelines ask from worker 0's tiles only: with one
         * tile taken by another worker the frame finishes first (then the
         * image is complete); the request must never break anything */
        CHECK((rc == VS_ERR_CANCELLED && im.rgba == NULL) || (rc == VS_OK && image_finite(&im)),
              "%s: cancel gave %s", vs_pipeline_name(x.pipeline), vs_status_string(rc));
        if (rc == VS_OK) vs_image_free(&im);
        printf("progress callback cancelling %-10s -> %s\n", vs_pipeline_name(x.pipeline), vs_status_string(rc));
    }
    CHECK(calls >= 5, "progress called %d times", calls);
    vs_volume_release(v);
}

static void test_image_api(void)
{
    float px[4 * 4 * 4];
    for (int i = 0; i < 64; i++) px[i] = 0.5f;
    vs_image good = {4, 4, px}, nodata = {4, 4, NULL}, zero = {0, 4, px}, neg = {-4, 4, px};
    char path[1100];
    path_of(path, sizeof path, "w.png");
    CHECK(vs_image_write(ctx, NULL, &good, 8) == VS_ERR_INVALID_ARGUMENT, "write(path NULL)");
    CHECK(vs_image_write(ctx, "", &good, 8) == VS_ERR_INVALID_ARGUMENT, "write('')");
    CHECK(vs_image_write(ctx, path, NULL, 8) == VS_ERR_INVALID_ARGUMENT, "write(img NULL)");
    CHECK(vs_image_write(ctx, path, &nodata, 8) == VS_ERR_INVALID_ARGUMENT, "write(rgba NULL)");
    CHECK(vs_image_write(ctx, path, &zero, 8) == VS_ERR_INVALID_ARGUMENT, "write(width 0)");
    CHECK(vs_image_write(ctx, path, &neg, 8) == VS_ERR_INVALID_ARGUMENT, "write(width -4)");
    CHECK(vs_image_write(ctx, path, &good, 12) == VS_ERR_INVALID_ARGUMENT, "write(bits 12)");
    CHECK(vs_image_write(NULL, path, &good, 99) == VS_ERR_INVALID_ARGUMENT, "write(ctx NULL)");
    /* NaN and out-of-range pixels are written (clamped), not a crash */
    float odd[16] = {NAN, INFINITY, -1, 2, 0, 0, 0, 1, 1, 1, 1, 1, 0.5f, 0.5f, 0.5f, NAN};
    vs_image oddimg = {2, 2, odd};
    vs_status rc = vs_image_write(ctx, path, &oddimg, 8);
    CHECK(rc == VS_OK, "write NaN pixels: %s", vs_last_error(ctx));
    /* unwritable paths: a status, the path in the message, nothing left */
    char dirpath[1100];
    path_of(dirpath, sizeof dirpath, "a_folder.png");
    mkdir(dirpath, 0755);
    const char *unwritable[] = {"/nonexistent/x.png", dirpath, "/proc/version.png"};
    for (int i = 0; i < 3; i++) {
        rc = vs_image_write(ctx, unwritable[i], &good, 8);
        CHECK(rc == VS_ERR_IO || rc == VS_ERR_INVALID_ARGUMENT, "write %s: %s", unwritable[i], vs_status_string(rc));
        CHECK(strstr(vs_last_error(ctx), unwritable[i]) != NULL, "write %s: message '%s'", unwritable[i],
              vs_last_error(ctx));
    }
    path_of(path, sizeof path, "w.bmpx");
    rc = vs_image_write(ctx, path, &good, 8);
    CHECK(rc != VS_OK, "write .bmpx succeeded");
    /* the temporary files of failed writes are gone */
    DIR *dir = opendir(tmp);
    struct dirent *e;
    int strays = 0;
    while (dir && (e = readdir(dir)))
        if (strstr(e->d_name, "tmp")) {
            strays++;
            printf("  stray file %s\n", e->d_name);
        }
    if (dir) closedir(dir);
    CHECK(strays == 0, "%d temporary files left", strays);

    vs_image out = {1, 1, (float *)1};
    CHECK(vs_image_read(ctx, NULL, &out) == VS_ERR_INVALID_ARGUMENT && out.rgba == NULL, "read(NULL)");
    CHECK(vs_image_read(ctx, "x.png", NULL) == VS_ERR_INVALID_ARGUMENT, "read(out NULL)");
    CHECK(vs_image_read(ctx, "/nonexistent/y.png", &out) != VS_OK && out.rgba == NULL, "read missing");
    CHECK(vs_image_read(ctx, dirpath, &out) != VS_OK && out.rgba == NULL, "read folder");
    vs_image_diff d;
    CHECK(vs_image_compare(ctx, &good, &good, NULL) == VS_ERR_INVALID_ARGUMENT, "compare(out NULL)");
    CHECK(vs_image_compare(ctx, NULL, &good, &d) == VS_ERR_INVALID_ARGUMENT, "compare(a NULL)");
    CHECK(vs_image_compare(ctx, &good, &nodata, &d) == VS_ERR_INVALID_ARGUMENT, "compare(rgba NULL)");
    CHECK(vs_image_compare(ctx, &good, &oddimg, &d) == VS_ERR_INVALID_ARGUMENT, "compare(sizes)");
    CHECK(vs_image_compare(NULL, &good, &good, &d) == VS_OK, "compare(ctx NULL)");
}

/* ------------------------------------------------------------ NaN / Inf voxels */

/* Policy (docs/PERFORMANCE.md "Stiff cases"): non-finite voxels are accepted; they are
 * left out of the value range and the default iso-value, and every
 * pipeline and the ray caster render them as 0.  So the image must be
 * finite, and close to the image of the same volume with those voxels set
 * to 0 (not bit-identical: the relevant-voxel builder only includes a
 * non-finite voxel when a finite neighbour needs it, which changes sums by
 * the order of additions only). */
static void test_nonfinite(void)
{
    const int n = 32;
    int dims[3] = {n, n, n};
    vs_volume *v, *z;
    if (vs_volume_create(ctx, VS_F32, dims, NULL, &v) != VS_OK || vs_volume_create(ctx, VS_F32, dims, NULL, &z) != VS_OK) {
        CHECK(0, "create: %s", vs_last_error(ctx));
        return;
    }
    float *a = vs_volume_data(v), *b = vs_volume_data(z);
    int nonfinite = 0;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                size_t o = ((size_t)k * n + j) * n + i;
                double r = sqrt((i - 15.5) * (i - 15.5) + (j - 15.5) * (j - 15.5) + (k - 15.5) * (k - 15.5));
                double f = 0.5 + (10.0 - r) / 4.0;
                f = f < 0 ? 0 : (f > 1 ? 1 : f);
                a[o] = b[o] = (float)f;
                /* a NaN block through the surface, Inf and -Inf specks */
                if ((i >= 20 && i < 24 && j >= 12 && j < 18) || (o % 97 == 0) || (o % 101 == 0)) {
                    a[o] = (o % 97 == 0) ? INFINITY : (o % 101 == 0) ? -INFINITY : NAN;
                    b[o] = 0.0f;
                    nonfinite++;
                }
            }
    vs_volume_update_range(v);
    vs_volume_update_range(z);
    double lo, hi, zlo, zhi;
    vs_volume_range(v, &lo, &hi);
    vs_volume_range(z, &zlo, &zhi);
    CHECK(isfinite(lo) && isfinite(hi) && hi == 1.0, "range with NaN/Inf: %g..%g", lo, hi);
    CHECK(isfinite(vs_volume_default_iso(v)), "default iso with NaN/Inf: %g", vs_volume_default_iso(v));
    printf("NaN/Inf volume: %d non-finite voxels, range %g..%g, default iso %g\n", nonfinite, lo, hi,
           vs_volume_default_iso(v));
    for (int p = 0; p <= VS_PIPELINE_RAYCAST + 1; p++) {
        vs_settings s;
        vs_settings_init(&s);
        s.width = s.height = 48;
        s.azimuth = 30;
        s.elevation = 20;
        s.has_iso = 1;
        s.iso_lo = 0.5;
        s.ramp = 0.05;
        s.pipeline = (vs_pipeline)(p > VS_PIPELINE_RAYCAST ? VS_PIPELINE_RAYCAST : p);
        if (p > VS_PIPELINE_RAYCAST) s.ray_trilinear = 1;
        for (int open = 0; open < 2; open++) {
            /* open: default iso from the histogram, translucent, so the
             * inside of the NaN block is seen too */
            if (open) {
                s.has_iso = 0;
                s.iso_opacity = 0.1f;
            }
            vs_image iv, iz;
            vs_stats st;
            vs_status r1 = vs_render(ctx, v, &s, &iv, &st);
            vs_status r2 = vs_render(ctx, z, &s, &iz, &st);
            const char *name = p > VS_PIPELINE_RAYCAST ? "raycast-trilinear" : vs_pipeline_name(s.pipeline);
            CHECK(r1 == VS_OK && r2 == VS_OK, "%s: %s", name, vs_last_error(ctx));
            if (r1 != VS_OK || r2 != VS_OK) continue;
            CHECK(image_finite(&iv), "%s: non-finite pixels with NaN/Inf voxels", name);
            double md = 0;
            for (size_t i = 0; i < (size_t)48 * 48 * 4; i++) {
                double dd = fabs((double)iv.rgba[i] - iz.rgba[i]);
                if (!(dd <= md)) md = dd;
            }
            printf("  %-18s %s: max difference to the zeroed volume %.2e\n", name, open ? "default iso" : "iso 0.5   ",
                   md);
            /* float sums in a different order: 1e-4 is far above rounding
             * and far below anything visible */
            /* pre and post-alpha too: their voxel gradients read a
             * non-finite neighbour as the value outside, 0 here
             * (src/voxel_gradient.h) */
            CHECK(md <= 1e-4, "%s: NaN/Inf voxels not rendered as 0 (max difference %g)", name, md);
            vs_image_free(&iv);
            vs_image_free(&iz);
        }
    }
    /* a volume of nothing but NaN: range 0..0, a blank finite image */
    float *d = vs_volume_data(v);
    for (size_t i = 0; i < (size_t)n * n * n; i++) d[i] = NAN;
    vs_volume_update_range(v);
    vs_volume_range(v, &lo, &hi);
    CHECK(lo == 0 && hi == 0, "all-NaN range %g..%g", lo, hi);
    for (int p = 0; p <= VS_PIPELINE_RAYCAST; p++) {
        vs_settings s;
        vs_settings_init(&s);
        s.width = s.height = 24;
        s.pipeline = (vs_pipeline)p;
        vs_image im;
        vs_status rc = vs_render(ctx, v, &s, &im, NULL);
        CHECK(rc == VS_OK && image_finite(&im), "all-NaN %s: %s", vs_pipeline_name(s.pipeline), vs_last_error(ctx));
        if (rc == VS_OK) vs_image_free(&im);
    }
    vs_volume_release(v);
    vs_volume_release(z);
}

/* The shading table with gradients that have no direction: NaN or infinite
 * components (float densities that overflowed) and magnitudes under 1e-30
 * must shade like a zero gradient (facing the eye), exactly as the exact
 * path (vs_light_eval) does.  Before the guard in shade_lut.h, lrintf(NaN)
 * gave INT_MIN and the look-up read far outside the tables (a crash on
 * +-FLT_MAX volumes, tests/test_stiff.c), and gradients between 3.7e-37 and
 * 1e-30 got a direction the exact path does not give them. */
static void test_shade_lut_nonfinite(void)
{
    vs_settings s;
    vs_settings_init(&s);
    vs_camera cam;
    vs_volume *v;
    if (vs_volume_scene(ctx, "cube", &v) != VS_OK) return;
    vs_camera_setup(ctx, v, &s, &cam);
    vs_light l;
    vs_light_setup(&s, &cam, &l);
    vs_shade_lut lut = {0}; /* zeroed: vs_shade_lut_setup keeps tables it finds */
    if (vs_shade_lut_setup(ctx, 256, &l, &lut) != VS_OK) {
        CHECK(0, "lut: %s", vs_last_error(ctx));
        vs_volume_release(v);
        return;
    }
    float d0, s0;
    vs_shade_lut_eval(&lut, 0, 0, 0, &d0, &s0);
    const float g[][3] = {{NAN, 1, 2},     {1, NAN, 0.5f},     {0, 0, NAN},       {INFINITY, 0, 0},
                          {-INFINITY, 1, 1}, {INFINITY, -INFINITY, 0}, {1e-35f, 0, 0}, {0, -3e-31f, 1e-33f},
                          {FLT_MAX, FLT_MAX, -FLT_MAX}};
    for (size_t i = 0; i < sizeof g / sizeof g[0]; i++) {
        float dd, ss;
        vs_shade_lut_eval(&lut, g[i][0], g[i][1], g[i][2], &dd, &ss);
        double n[3] = {g[i][0], g[i][1], g[i][2]}, de, se;
        vs_light_eval(&l, n, &de, &se);
        int finite_ok = isfinite(g[i][0]) && isfinite(g[i][1]) && isfinite(g[i][2]) && fabsf(g[i][0]) >= 1e-30f;
        if (!finite_ok && fabs(g[i][0]) < 1e38) {
            CHECK(dd == d0 && ss == s0, "lut(%g,%g,%g) = %g,%g, zero gradient gives %g,%g", g[i][0], g[i][1], g[i][2],
                  dd, ss, d0, s0);
            CHECK(fabs(dd - de) < 0.02 && fabs(ss - se) < 0.02, "lut(%g,%g,%g) = %g,%g, exact %g,%g", g[i][0],
                  g[i][1], g[i][2], dd, ss, de, se);
        }
        CHECK(isfinite(dd) && isfinite(ss), "lut(%g,%g,%g) not finite", g[i][0], g[i][1], g[i][2]);
    }
    vs_shade_lut_free(&lut);
    vs_volume_release(v);
}

/* ------------------------------------------------------------ loaders */

static vs_volume *expect_load(const char *path, const char *why)
{
    vs_volume *v = NULL;
    vs_status st = vs_volume_load(ctx, path, NULL, &v);
    CHECK(st == VS_OK, "%s: %s", why, vs_last_error(ctx));
    printf("  %-34s -> %s\n", why, st == VS_OK ? "loaded" : vs_last_error(ctx));
    return v;
}

/* NIfTI-1 header: the fields the loader reads, little-endian. */
static void nifti_header(unsigned char h[352], int ndim, const int16_t dim[7], int16_t datatype, int16_t bitpix,
                         const float pixdim[3], float vox_offset, float slope)
{
    memset(h, 0, 352);
    int32_t i32 = 348;
    memcpy(h, &i32, 4);
    int16_t d[8] = {(int16_t)ndim, 1, 1, 1, 1, 1, 1, 1};
    for (int a = 0; a < 7; a++) d[a + 1] = dim[a];
    memcpy(h + 40, d, sizeof d);
    memcpy(h + 70, &datatype, 2);
    memcpy(h + 72, &bitpix, 2);
    float pd[8] = {1, pixdim[0], pixdim[1], pixdim[2], 1, 1, 1, 1};
    memcpy(h + 76, pd, sizeof pd);
    memcpy(h + 108, &vox_offset, 4);
    memcpy(h + 112, &slope, 4);
    memcpy(h + 344, "n+1", 4);
}

static void write_nifti(const char *name, int ndim, const int16_t dim[7], int16_t dt, int16_t bitpix,
                        const float pd[3], float off, float slope, const void *data, size_t n)
{
    char path[1100];
    path_of(path, sizeof path, name);
    unsigned char *all = calloc(1, 352 + n);
    nifti_header(all, ndim, dim, dt, bitpix, pd, off, slope);
    if (n) memcpy(all + 352, data, n);
    tu_write_file(path, all, 352 + n);
    free(all);
}

static void test_nifti_hostile(void)
{
    char path[1100];
    float data[4 * 4 * 4];
    for (int i = 0; i < 64; i++) data[i] = (float)i;
    const int16_t d444[7] = {4, 4, 4, 1, 1, 1, 1};
    const float unit[3] = {1, 1, 1};
    struct {
        const char *name;
        float pd[3];
        int ok;
    } sp[] = {{"pixdim_nan.nii", {1, NAN, 1}, 0},       {"pixdim_zero.nii", {0, 1, 1}, 0},
              {"pixdim_inf.nii", {1, 1, INFINITY}, 0},  {"pixdim_negative.nii", {-2, 1, 1}, 1},
              {"pixdim_tiny.nii", {1e-30f, 1, 1}, 0}};
    for (int i = 0; i < 5; i++) {
        write_nifti(sp[i].name, 3, d444, 16, 32, sp[i].pd, 352, 0, data, sizeof data);
        path_of(path, sizeof path, sp[i].name);
        if (sp[i].ok) {
            vs_volume *v = expect_load(path, "nifti negative pixdim (|pixdim|)");
            double s[3];
            vs_volume_spacing(v, s);
            CHECK(!v || s[0] == 2.0, "negative pixdim: spacing %g", s[0]);
            vs_volume_release(v);
        } else {
            tu_expect_load_fail(ctx, path, NULL, sp[i].name);
        }
    }
    /* sizes whose byte count overflows 32 bits, negative and zero dims */
    const int16_t big[7] = {32767, 32767, 32767, 1, 1, 1, 1};
    write_nifti("dims_32767cubed.nii", 3, big, 16, 32, unit, 352, 0, data, sizeof data);
    path_of(path, sizeof path, "dims_32767cubed.nii");
    tu_expect_load_fail(ctx, path, NULL, "nifti 32767^3 f32 (overflows)");
    const int16_t ovf[7] = {16384, 16384, 16384, 1, 1, 1, 1};
    write_nifti("dims_16384cubed.nii", 3, ovf, 64, 64, unit, 352, 0, data, sizeof data);
    path_of(path, sizeof path, "dims_16384cubed.nii");
    tu_expect_load_fail(ctx, path, NULL, "nifti 16384^3 f64 (2^45 bytes)");
    const int16_t negd[7] = {4, -4, 4, 1, 1, 1, 1};
    write_nifti("dims_negative.nii", 3, negd, 16, 32, unit, 352, 0, data, sizeof data);
    path_of(path, sizeof path, "dims_negative.nii");
    tu_expect_load_fail(ctx, path, NULL, "nifti negative dim[2]");
    const int16_t zero4[7] = {4, 4, 4, 0, 1, 1, 1};
    write_nifti("dims_zero_t.nii", 4, zero4, 16, 32, unit, 352, 0, data, sizeof data);
    path_of(path, sizeof path, "dims_zero_t.nii");
    tu_expect_load_fail(ctx, path, NULL, "nifti 4-D with dim[4] = 0");
    /* vox_offset past the end, and absurd */
    write_nifti("offset_past_end.nii", 3, d444, 16, 32, unit, 100000, 0, data, sizeof data);
    path_of(path, sizeof path, "offset_past_end.nii");
    tu_expect_load_fail(ctx, path, NULL, "nifti vox_offset past the end");
    write_nifti("offset_huge.nii", 3, d444, 16, 32, unit, 3e38f, 0, data, sizeof data);
    path_of(path, sizeof path, "offset_huge.nii");
    tu_expect_load_fail(ctx, path, NULL, "nifti vox_offset 3e38");
    write_nifti("offset_nan.nii", 3, d444, 16, 32, unit, NAN, 0, data, sizeof data);
    path_of(path, sizeof path, "offset_nan.nii");
    vs_volume *v = NULL;
    vs_status st = vs_volume_load(ctx, path, NULL, &v);
    printf("  %-34s -> %s: %s\n", "nifti vox_offset NaN", vs_status_string(st), st == VS_OK ? "" : vs_last_error(ctx));
    vs_volume_release(v);
    /* unsupported / inconsistent datatypes */
    write_nifti("complex.nii", 3, d444, 32, 64, unit, 352, 0, data, sizeof data);
    path_of(path, sizeof path, "complex.nii");
    tu_expect_load_fail(ctx, path, NULL, "nifti complex64");
    write_nifti("rgb.nii", 3, d444, 128, 24, unit, 352, 0, data, sizeof data);
    path_of(path, sizeof path, "rgb.nii");
    tu_expect_load_fail(ctx, path, NULL, "nifti RGB24");
    write_nifti("datatype_bogus.nii", 3, d444, 12345, 8, unit, 352, 0, data, sizeof data);
    path_of(path, sizeof path, "datatype_bogus.nii");
    tu_expect_load_fail(ctx, path, NULL, "nifti datatype 12345");
    write_nifti("data_truncated.nii", 3, d444, 16, 32, unit, 352, 0, data, sizeof data - 5);
    path_of(path, sizeof path, "data_truncated.nii");
    tu_expect_load_fail(ctx, path, NULL, "nifti data 5 bytes short");
    /* scl_slope that overflows f32: accepted, the Inf voxels follow the
     * non-finite policy (range from the finite ones) */
    int16_t i16[64];
    for (int i = 0; i < 64; i++) i16[i] = (int16_t)(i * 500 - 16000);
    write_nifti("slope_overflow.nii", 3, d444, 4, 16, unit, 352, 1e36f, i16, sizeof i16);
    path_of(path, sizeof path, "slope_overflow.nii");
    v = expect_load(path, "nifti scl_slope 1e36 (-> Inf voxels)");
    if (v) {
        double lo, hi;
        vs_volume_range(v, &lo, &hi);
        CHECK(isfinite(lo) && isfinite(hi), "slope overflow range %g..%g", lo, hi);
        vs_settings s;
        vs_settings_init(&s);
        s.width = s.height = 16;
        for (int p = 0; p <= VS_PIPELINE_RAYCAST; p++) {
            s.pipeline = (vs_pipeline)p;
            vs_image im;
            st = vs_render(ctx, v, &s, &im, NULL);
            CHECK(st == VS_OK && image_finite(&im), "slope overflow %s: %s", vs_pipeline_name(s.pipeline),
                  vs_last_error(ctx));
            if (st == VS_OK) vs_image_free(&im);
        }
        vs_volume_release(v);
    }
    /* every truncation of a valid file */
    write_nifti("valid.nii", 3, d444, 16, 32, unit, 352, 0, data, sizeof data);
    path_of(path, sizeof path, "valid.nii");
    size_t n;
    unsigned char *b = tu_read_file(path, &n);
    int loaded = 0;
    double t0 = tu_now_s();
    for (size_t cut = 0; cut < n; cut += 7) {
        path_of(path, sizeof path, "cut.nii");
        tu_write_file(path, b, cut);
        v = (vs_volume *)1;
        st = vs_volume_load(ctx, path, NULL, &v);
        loaded += st == VS_OK;
        CHECK(st != VS_OK && v == NULL && strstr(vs_last_error(ctx), "cut.nii"), "nifti cut at %zu: %s", cut,
              vs_last_error(ctx));
        if (st == VS_OK) vs_volume_release(v);
    }
    printf("  %-34s -> %d of them loaded, %.2f s\n", "nifti cut every 7 bytes", loaded, tu_now_s() - t0);
    free(b);
}

static void test_nrrd_hostile(void)
{
    char path[1100];
    struct {
        const char *name, *text;
        int ok;
    } cases[] = {
        {"spacing_nan.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nspacings: 1 nan 1\nencoding: raw\n\n01234567", -1},
        {"spacing_zero.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nspacings: 1 0 1\nencoding: raw\n\n01234567", -1},
        {"spacing_negative.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nspacings: 1 -2 1\nencoding: raw\n\n01234567", -1},
        {"spacing_inf.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nspacings: inf 1 1\nencoding: raw\n\n01234567", -1},
        {"sizes_zero.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 0 2\nencoding: raw\n\n01234567", 0},
        {"sizes_negative.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 -2 2\nencoding: raw\n\n01234567", 0},
        {"sizes_overflow.nrrd", "NRRD0004\ntype: double\ndimension: 3\nsizes: 4294967296 4294967296 4294967296\nencoding: raw\n\n01234567", 0},
        {"sizes_2e19.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 20000000000000000000 1 1\nencoding: raw\n\n01234567", 0},
        {"dimension_4.nrrd", "NRRD0004\ntype: uchar\ndimension: 4\nsizes: 2 2 2 1\nencoding: raw\n\n01234567", 0},
        {"dimension_0.nrrd", "NRRD0004\ntype: uchar\ndimension: 0\nsizes: \nencoding: raw\n\n01234567", 0},
        {"type_block.nrrd", "NRRD0004\ntype: block\nblock size: 4\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n01234567", 0},
        {"encoding_bogus.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: rot13\n\n01234567", 0},
        {"detached_missing.nhdr", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: does_not_exist.raw\n", 0},
        {"detached_self_loop.nhdr", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 200 200 200\nencoding: raw\ndata file: detached_self_loop.nhdr\n", 0},
        {"ascii_short.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nencoding: ascii\n\n1 2 3", 0},
        {"ascii_garbage.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nencoding: ascii\n\n1 2 x y z 6 7 8", 0},
        {"ascii_nan.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nencoding: ascii\n\nnan inf -inf 1 2 3 4 5", 1},
        {"magic_only.nrrd", "NRRD0004\n", 0},
        {"bad_magic.nrrd", "NRRD9999\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n01234567", 0},
        {"endian_bogus.nrrd", "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 1\nendian: middle\nencoding: raw\n\n01234567", 0},
        {"line_no_newline.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2", 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        path_of(path, sizeof path, cases[i].name);
        tu_write_file(path, cases[i].text, strlen(cases[i].text));
        if (cases[i].ok == 0) {
            tu_expect_load_fail(ctx, path, NULL, cases[i].name);
        } else {
            /* spacing: rejected, or accepted with a finite positive spacing
             * (Teem ignores unusable spacings: then 1) */
            vs_volume *v = NULL;
            vs_status st = vs_volume_load(ctx, path, NULL, &v);
            if (st == VS_OK) {
                double s[3], lo, hi;
                vs_volume_spacing(v, s);
                vs_volume_range(v, &lo, &hi);
                for (int a = 0; a < 3; a++)
                    CHECK(s[a] > 0 && isfinite(s[a]), "%s: spacing %d is %g", cases[i].name, a, s[a]);
                CHECK(isfinite(lo) && isfinite(hi), "%s: range %g..%g", cases[i].name, lo, hi);
                printf("  %-34s -> loaded, spacing %g,%g,%g, range %g..%g\n", cases[i].name, s[0], s[1], s[2], lo, hi);
                vs_volume_release(v);
            } else {
                CHECK(cases[i].ok < 0, "%s: %s", cases[i].name, vs_last_error(ctx));
                CHECK(strstr(vs_last_error(ctx), cases[i].name) != NULL, "%s: message '%s'", cases[i].name,
                      vs_last_error(ctx));
                printf("  %-34s -> %s: %s\n", cases[i].name, vs_status_string(st), vs_last_error(ctx));
            }
        }
    }
}

/* NRRD headers Teem 1.12 mishandles in its data-file and kind code: each
 * must be refused by vsplat's header check, with its own message (Teem's
 * would differ, or it would crash, hang, read standard input or leak). */
static void test_nrrd_header_refusals(void)
{
    char path[1100];
#define H "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n"
    static const struct {
        const char *name, *text, *says;
    } cases[] = {
        /* templates go to sprintf as the format and to loops over int */
        {"template_s.nhdr", H "data file: x%d%s 1 2 1\n", "other than %d"},
        {"template_n.nhdr", H "data file: x%d%n 1 2 1\n", "other than %d"},
        {"template_wide.nhdr", H "data file: x%0300d 1 2 1\n", "wider than 10"},
        {"template_two.nhdr", H "data file: x%d_%d 1 2 1\n", "more than one %d"},
        {"template_overflow.nhdr", H "data file: x%d 2147483000 2147483647 1000\n", "overflow an int"},
        {"template_overflow_down.nhdr", H "data file: x%d -2147483000 -2147483648 -1000\n", "overflow an int"},
        {"template_span.nhdr", H "data file: x%d -2147483000 2147483000 1\n", "overflow an int"},
        {"template_count.nhdr", H "data file: x%d 1 100000 1\n", "more data files"},
        /* standard input as the data (ctest's stdin may be empty: the
         * message tells the refusal from a failed read) */
        {"stdin.nhdr", H "data file: -\n", "standard input"},
        {"stdin_list.nhdr", H "data file: LIST\n-\n-\n", "standard input"},
        {"stdin_skiplist.nhdr", H "data file: SKIPLIST\n0 -\n0 -\n", "standard input"},
        {"stdin_after_blank.nhdr", H "data file: LIST\na\n\n-\n", "empty name"},
        /* a fixed-size kind: Teem freed the header file it kept open (the
         * data after the header), then leaked (the data detached) */
        {"kinds_attached.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nkinds: 3-vector domain domain\nsizes: 2 2 2\n"
                                "encoding: raw\n\n01234567",
         "not a scalar volume"},
        {"kinds_detached.nhdr", H "kinds: RGB-color domain domain\ndata file: kinds.raw\n", "not a scalar volume"},
    };
#undef H
    path_of(path, sizeof path, "kinds.raw");
    tu_write_file(path, "01234567", 8);
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        path_of(path, sizeof path, cases[i].name);
        tu_write_file(path, cases[i].text, strlen(cases[i].text));
        tu_expect_load_fail(ctx, path, NULL, cases[i].name);
        CHECK(strstr(vs_last_error(ctx), cases[i].says), "%s: message '%s' lacks '%s'", cases[i].name,
              vs_last_error(ctx), cases[i].says);
    }
}

/* gzip bytes of n bytes of data, into z (*nz: its size, then the length) */
static int gzip_bytes(const void *data, unsigned n, void *z, unsigned *nz)
{
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    if (deflateInit2(&zs, 9, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) return 0;
    zs.next_in = (Bytef *)data;
    zs.avail_in = n;
    zs.next_out = z;
    zs.avail_out = *nz;
    const int ok = deflate(&zs, Z_FINISH) == Z_STREAM_END;
    *nz = (unsigned)zs.total_out;
    deflateEnd(&zs);
    return ok;
}

/* Compressed NRRD data that Teem's readers leak their decoder on (gzip
 * 56 KB, bzip2 3.6 MB a file): corrupt, cut short, shorter than the sizes,
 * a byte skip past either end, not compressed data at all.  Each must fail
 * with one message (and, under ASan or valgrind, without a leak). */
static void test_nrrd_compressed_hostile(void)
{
    enum { N = 16 * 16 * 16 };
    static char data[N], z[N + 1000];
    for (int i = 0; i < N; i++) data[i] = (char)((i * 7) % 251);
    for (int gz = 0; gz < 2; gz++) {
        unsigned nz = sizeof z;
        if (gz) CHECK(gzip_bytes(data, N, z, &nz), "gzip");
        else CHECK(BZ2_bzBuffToBuffCompress(z, &nz, data, N, 9, 0, 0) == BZ_OK, "bzip2");
        char hdr[4][200];
        const char *enc = gz ? "gzip" : "bzip2";
        const char *sizes[4] = {"16 16 16", "16 16 17", "16 16 16", "16 16 17"};
        const char *skips[4] = {"", "", "byte skip: 100000\n", "byte skip: -1\n"};
        for (int h = 0; h < 4; h++)
            snprintf(hdr[h], sizeof hdr[h], "NRRD0004\ntype: uchar\ndimension: 3\nsizes: %s\n%sencoding: %s\n\n",
                     sizes[h], skips[h], enc);
        struct {
            const char *name, *header;
            unsigned keep; /* bytes of the stream kept */
            int flip;      /* a byte of the stream inverted at this offset, or -1 */
        } cases[] = {
            {"corrupt", hdr[0], nz, (int)nz / 2},  {"cut", hdr[0], nz / 2, -1},
            {"too_few", hdr[1], nz, -1},           {"skip_past_end", hdr[2], nz, -1},
            {"skip_before_start", hdr[3], nz, -1}, {"not_compressed", hdr[1], 0, -1},
        };
        char path[1100], name[64];
        for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
            const size_t h = strlen(cases[i].header);
            char *buf = malloc(h + nz + 64);
            if (!buf) return;
            memcpy(buf, cases[i].header, h);
            size_t n = h;
            if (cases[i].keep) {
                memcpy(buf + h, z, cases[i].keep);
                n += cases[i].keep;
            } else { /* gzip: read as is (zlib's transparent mode), too short */
                n += (size_t)sprintf(buf + h, "plain text, not a compressed stream");
            }
            if (cases[i].flip >= 0) buf[h + (size_t)cases[i].flip] ^= 0x55;
            snprintf(name, sizeof name, "%s_%s.nrrd", enc, cases[i].name);
            path_of(path, sizeof path, name);
            tu_write_file(path, buf, n);
            free(buf);
            tu_expect_load_fail(ctx, path, NULL, name);
            CHECK(!strchr(vs_last_error(ctx), '\n'), "%s: message of several lines", name);
        }
    }
}

/* PNG / TIFF / tar / .den / raw */
static void test_images_hostile(void)
{
    char path[1100], err[400];
    const vs_oiio_api *io = vs_oiio(ctx);
    if (!io) {
        CHECK(0, "image I/O module: %s", vs_last_error(ctx));
        return;
    }
    enum { W = 8, H = 6 };
    uint8_t px[3 * W * H];
    for (int i = 0; i < 3 * W * H; i++) px[i] = (uint8_t)(i * 7);
    path_of(path, sizeof path, "valid.png");
    CHECK(io->write_pages(path, W, H, 1, 1, VS_PIX_U8, px, 0, 0, NULL, err, sizeof err) == VS_OK, "png: %s", err);
    size_t n;
    unsigned char *png = tu_read_file(path, &n);
    path_of(path, sizeof path, "valid.tif");
    CHECK(io->write_pages(path, W, H, 1, 3, VS_PIX_U8, px, 2.0, 2.0, NULL, err, sizeof err) == VS_OK, "tif: %s",
          err);
    size_t nt;
    unsigned char *tif = tu_read_file(path, &nt);
    if (!png || !tif) {
        CHECK(0, "could not write the valid images");
        free(png);
        free(tif);
        return;
    }
    /* every truncation: rejected (or, for a TIFF cut after whole pages,
     * possibly fewer pages), never a crash */
    double t0 = tu_now_s();
    for (size_t cut = 0; cut < n; cut += 3) {
        path_of(path, sizeof path, "cut.png");
        tu_write_file(path, png, cut);
        vs_volume *v = (vs_volume *)1;
        vs_status st = vs_volume_load(ctx, path, NULL, &v);
        if (st == VS_OK) {
            /* only a cut inside the trailing IEND chunk (12 bytes) may load,
             * and then with the complete data */
            CHECK(cut + 12 >= n && memcmp(vs_volume_data(v), px, W * H) == 0, "png cut at %zu of %zu loaded", cut, n);
            vs_volume_release(v);
        } else {
            CHECK(v == NULL && strstr(vs_last_error(ctx), "cut.png"), "png cut at %zu of %zu: %s", cut, n,
                  vs_last_error(ctx));
        }
    }
    printf("  %-34s -> rejected (a cut IEND loads complete data), %.2f s\n", "png cut every 3 bytes", tu_now_s() - t0);
    t0 = tu_now_s();
    int accepted = 0;
    for (size_t cut = 0; cut < nt; cut += 5) {
        path_of(path, sizeof path, "cut.tif");
        tu_write_file(path, tif, cut);
        vs_volume *v = (vs_volume *)1;
        vs_status st = vs_volume_load(ctx, path, NULL, &v);
        if (st == VS_OK) {
            accepted++;
            vs_volume_release(v);
        } else {
            CHECK(v == NULL && strstr(vs_last_error(ctx), "cut.tif"), "tif cut at %zu: %s", cut, vs_last_error(ctx));
        }
    }
    printf("  %-34s -> %d of %zu cuts load (whole pages), the rest rejected, %.2f s\n", "tif cut every 5 bytes",
           accepted, (nt + 4) / 5, tu_now_s() - t0);
    /* a PNG whose IHDR claims 2^31-1 x 2^31-1 (CRC fixed up, so only the
     * size is wrong); and 100000 x 100000 */
    const uint32_t sizes[][2] = {{0x7fffffffu, 0x7fffffffu}, {100000, 100000}, {0, 5}};
    for (int k = 0; k < 3; k++) {
        unsigned char *c = malloc(n);
        memcpy(c, png, n);
        for (int i = 0; i < 4; i++) {
            c[16 + i] = (unsigned char)(sizes[k][0] >> (24 - 8 * i));
            c[20 + i] = (unsigned char)(sizes[k][1] >> (24 - 8 * i));
        }
        uLong crc = crc32(0L, c + 12, 17);
        for (int i = 0; i < 4; i++) c[29 + i] = (unsigned char)(crc >> (24 - 8 * i));
        char name[64];
        snprintf(name, sizeof name, "ihdr_%ux%u.png", sizes[k][0], sizes[k][1]);
        path_of(path, sizeof path, name);
        tu_write_file(path, c, n);
        tu_expect_load_fail(ctx, path, NULL, name);
        free(c);
    }
    /* garbage after a valid PNG signature; a TIFF header pointing nowhere */
    unsigned char junk[200];
    memcpy(junk, png, 8);
    for (int i = 8; i < 200; i++) junk[i] = (unsigned char)(i * 31);
    path_of(path, sizeof path, "signature_then_junk.png");
    tu_write_file(path, junk, sizeof junk);
    tu_expect_load_fail(ctx, path, NULL, "png signature then junk");
    const unsigned char tiff_bad_ifd[16] = {'I', 'I', 42, 0, 0xf0, 0xff, 0xff, 0x7f, 0, 0, 0, 0, 0, 0, 0, 0};
    path_of(path, sizeof path, "ifd_far.tif");
    tu_write_file(path, tiff_bad_ifd, sizeof tiff_bad_ifd);
    tu_expect_load_fail(ctx, path, NULL, "tiff IFD offset 2 GB");
    free(png);
    free(tif);

    /* tar: a member claiming 8 GB, a negative/base-256 size, a name without NUL */
    unsigned char tar[2048];
    memset(tar, 0, sizeof tar);
    memset(tar, 'a', 100); /* name fills the field: no NUL */
    memcpy(tar + 100, "0000644", 8);
    memcpy(tar + 124, "77777777777", 12);
    tar[156] = '0';
    memcpy(tar + 257, "ustar", 6);
    memcpy(tar + 263, "00", 2);
    memset(tar + 148, ' ', 8);
    unsigned sum = 0;
    for (int i = 0; i < 512; i++) sum += tar[i];
    snprintf((char *)tar + 148, 8, "%06o", sum & 0777777u);
    path_of(path, sizeof path, "member_8gb.tar");
    tu_write_file(path, tar, sizeof tar);
    tu_expect_load_fail(ctx, path, NULL, "tar member claiming 8 GB");
    tar[124] = 0xff; /* base-256 size, negative */
    memset(tar + 148, ' ', 8);
    sum = 0;
    for (int i = 0; i < 512; i++) sum += tar[i];
    snprintf((char *)tar + 148, 8, "%06o", sum & 0777777u);
    path_of(path, sizeof path, "member_base256.tar");
    tu_write_file(path, tar, sizeof tar);
    tu_expect_load_fail(ctx, path, NULL, "tar base-256 negative size");
    path_of(path, sizeof path, "zeros.tar");
    memset(tar, 0, sizeof tar);
    tu_write_file(path, tar, sizeof tar);
    tu_expect_load_fail(ctx, path, NULL, "tar of zero blocks");

    /* .den whose map_length and dims disagree; 65535^3 with map_length 0 */
    unsigned char den[62 + 8];
    memset(den, 0, sizeof den);
    den[0] = 1;
    den[50] = 2;
    den[52] = 2;
    den[54] = 2;
    den[58] = 9;
    path_of(path, sizeof path, "maplength.den");
    tu_write_file(path, den, sizeof den);
    tu_expect_load_fail(ctx, path, NULL, "den map_length 9 for 2x2x2");
    den[50] = den[51] = den[52] = den[53] = den[54] = den[55] = 0xff;
    den[58] = 0;
    path_of(path, sizeof path, "max_dims.den");
    tu_write_file(path, den, sizeof den);
    tu_expect_load_fail(ctx, path, NULL, "den 65535^3");
    den[50] = den[52] = den[54] = 0;
    den[51] = den[53] = den[55] = 0;
    path_of(path, sizeof path, "zero_dims.den");
    tu_write_file(path, den, sizeof den);
    tu_expect_load_fail(ctx, path, NULL, "den 0x0x0");

    /* raw named with dims that overflow, or do not parse */
    unsigned char zeros[64] = {0};
    const char *names[] = {"vol_99999x99999x99999_u8.raw", "vol_16384x16384x16384_f32.raw",
                           "vol_0x4x4_u8.raw", "vol_4x4x4_u12.raw"};
    for (int i = 0; i < 4; i++) {
        path_of(path, sizeof path, names[i]);
        tu_write_file(path, zeros, sizeof zeros);
        tu_expect_load_fail(ctx, path, NULL, names[i]);
    }
}

int main(void)
{
    if (vs_context_create(&ctx) != VS_OK) return 2;
    if (!tu_make_tmpdir(tmp, sizeof tmp, "test_hostile")) return 1;
    printf("temporary files in %s\n", tmp);
    test_context_and_names();
    test_volume_api();
    test_default_iso_follows_data();
    test_render_api();
    test_image_api();
    test_shade_lut_nonfinite();
    test_nonfinite();
    printf("NIfTI:\n");
    test_nifti_hostile();
    printf("NRRD:\n");
    test_nrrd_hostile();
    test_nrrd_compressed_hostile();
    test_nrrd_header_refusals();
    printf("images, tar, den, raw:\n");
    test_images_hostile();
    tu_remove_tmpdir(tmp);
    vs_context_release(ctx);
    TEST_DONE();
}
