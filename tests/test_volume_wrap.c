/* Caller-owned volumes (vs_volume_wrap): a wrapped buffer is not copied,
 * renders bit for bit like the same voxels copied into vs_volume_create's
 * volume (every voxel type, every pipeline), has the same value range and
 * default iso, is handed back through the release callback exactly once
 * (never on a refused wrap), and after writing into the buffer plus
 * vs_volume_update_range the context's caches see the new data.  Layouts the
 * renderer cannot read (strided, misaligned) are refused with a message. */
#include "testutil.h"

#include <stdint.h>

static vs_context *ctx;

typedef struct released {
    int calls;
    void *data;
} released;

static void on_release(void *user, void *data)
{
    released *r = user;
    r->calls++;
    r->data = data;
}

/* A blob with a shell, in the type's range: every pipeline finds a surface. */
static void fill(vs_type t, const int d[3], void *buf, int variant)
{
    size_t i = 0;
    for (int z = 0; z < d[2]; z++)
        for (int y = 0; y < d[1]; y++)
            for (int x = 0; x < d[0]; x++, i++) {
                double dx = x - d[0] / 2.0 + variant, dy = y - d[1] / 2.0, dz = (z - d[2] / 2.0) * 1.3;
                double r = sqrt(dx * dx + dy * dy + dz * dz) / (d[0] / 2.0);
                double f = r < 0.7 ? 0.8 - 0.3 * r : (r < 0.9 ? 0.3 : 0.05 * ((x * 7 + y * 3 + z) % 5));
                switch (t) {
                case VS_U8: ((uint8_t *)buf)[i] = (uint8_t)(f * 250); break;
                case VS_I16: ((int16_t *)buf)[i] = (int16_t)(f * 3000 - 1000); break;
                case VS_U16: ((uint16_t *)buf)[i] = (uint16_t)(f * 60000); break;
                case VS_F32: ((float *)buf)[i] = (float)f; break;
                }
            }
}

static size_t type_size(vs_type t) { return t == VS_U8 ? 1 : t == VS_F32 ? 4 : 2; }

static int render(const vs_volume *v, const vs_settings *s, vs_image *img)
{
    vs_status st = vs_render(ctx, v, s, img, NULL);
    CHECK(st == VS_OK, "render: %s", vs_last_error(ctx));
    return st == VS_OK;
}

static int same_image(const vs_image *a, const vs_image *b)
{
    return a->width == b->width && a->height == b->height &&
           !memcmp(a->rgba, b->rgba, (size_t)a->width * a->height * 4 * sizeof(float));
}

static void check_type(vs_type t)
{
    const int d[3] = {40, 36, 30};
    const double sp[3] = {1.0, 1.1, 1.4};
    const size_t n = (size_t)d[0] * d[1] * d[2], bytes = n * type_size(t);
    void *buf = malloc(bytes);
    fill(t, d, buf, 0);
    released rel = {0, NULL};
    vs_volume *w = NULL, *c = NULL;
    CHECK(vs_volume_wrap(ctx, t, d, NULL, sp, buf, on_release, &rel, &w) == VS_OK, "%s wrap: %s", vs_type_name(t),
          vs_last_error(ctx));
    CHECK(vs_volume_create(ctx, t, d, sp, &c) == VS_OK, "%s create", vs_type_name(t));
    if (!w || !c) return;
    memcpy(vs_volume_data(c), buf, bytes);
    vs_volume_update_range(c);
    CHECK(vs_volume_data(w) == buf, "%s: wrapped volume copied its data", vs_type_name(t));
    double wl, wh, cl, ch;
    vs_volume_range(w, &wl, &wh);
    vs_volume_range(c, &cl, &ch);
    CHECK(wl == cl && wh == ch && wh > wl, "%s: range %g..%g, copy %g..%g", vs_type_name(t), wl, wh, cl, ch);
    CHECK(vs_volume_default_iso(w) == vs_volume_default_iso(c), "%s: default iso", vs_type_name(t));
    int wd[3];
    double ws[3];
    vs_volume_dims(w, wd);
    vs_volume_spacing(w, ws);
    CHECK(!memcmp(wd, d, sizeof wd) && ws[2] == sp[2] && vs_volume_type(w) == t, "%s: dims, spacing, type",
          vs_type_name(t));

    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 96;
    s.azimuth = 30;
    s.elevation = 20;
    s.threads = 2;
    s.pin = 0;
    for (int p = 0; p <= VS_PIPELINE_RAYCAST; p++) {
        s.pipeline = (vs_pipeline)p;
        s.ray_step = 0.5;
        s.has_iso = 0; /* the Otsu iso of each volume: the same voxels must give the same */
        vs_image a, b;
        if (!render(w, &s, &a)) continue;
        if (render(c, &s, &b)) {
            CHECK(same_image(&a, &b), "%s %s: wrapped and copied volumes render differently", vs_type_name(t),
                  vs_pipeline_name(s.pipeline));
            vs_image_free(&b);
        }
        vs_image_free(&a);
    }

    /* rewritten in place: after vs_volume_update_range the cached relevant
     * voxels and Otsu iso of the old data must not be reused */
    s.pipeline = VS_PIPELINE_POST_CD;
    vs_image before, after, fresh;
    if (render(w, &s, &before)) {
        fill(t, d, buf, 6);
        memcpy(vs_volume_data(c), buf, bytes);
        vs_volume_update_range(w);
        vs_volume_update_range(c);
        if (render(w, &s, &after) && render(c, &s, &fresh)) {
            CHECK(!same_image(&before, &after), "%s: new data rendered as the old", vs_type_name(t));
            CHECK(same_image(&after, &fresh), "%s: rewritten buffer differs from a copy of it", vs_type_name(t));
            vs_image_free(&after);
            vs_image_free(&fresh);
        }
        vs_image_free(&before);
    }

    CHECK(rel.calls == 0, "%s: released before vs_volume_release", vs_type_name(t));
    vs_volume_release(w);
    CHECK(rel.calls == 1 && rel.data == buf, "%s: release called %d times (data %p, want %p)", vs_type_name(t),
          rel.calls, rel.data, buf);
    vs_volume_release(c);
    free(buf);
    printf("%-4s wrapped = copied for every pipeline; range, iso, rewrite; released once\n", vs_type_name(t));
}

static void expect_refused(const char *why, vs_status want, vs_type t, const int d[3], const size_t *strides,
                           void *data)
{
    released rel = {0, NULL};
    vs_volume *v = (vs_volume *)1;
    vs_status st = vs_volume_wrap(ctx, t, d, strides, NULL, data, on_release, &rel, &v);
    CHECK(st == want, "%s: status %s, want %s", why, vs_status_string(st), vs_status_string(want));
    CHECK(v == NULL, "%s: output not cleared", why);
    CHECK(rel.calls == 0, "%s: release called on a refused wrap", why);
    CHECK(*vs_last_error(ctx), "%s: no message", why);
    printf("  refused, %-28s -> %s: %s\n", why, vs_status_string(st), vs_last_error(ctx));
    if (st == VS_OK) vs_volume_release(v);
}

static void check_layouts(void)
{
    const int d[3] = {8, 6, 4};
    float *buf = calloc(8 * 6 * 4 + 1, sizeof(float));
    buf[5] = 2.0f;
    const size_t dense[3] = {4, 32, 192};
    released rel = {0, NULL};
    vs_volume *v = NULL;
    CHECK(vs_volume_wrap(ctx, VS_F32, d, dense, NULL, buf, on_release, &rel, &v) == VS_OK,
          "explicit dense strides: %s", vs_last_error(ctx));
    double lo, hi;
    vs_volume_range(v, &lo, &hi);
    CHECK(lo == 0.0 && hi == 2.0, "range %g..%g, want 0..2", lo, hi);
    vs_volume_release(v);
    CHECK(rel.calls == 1, "released %d times", rel.calls);
    vs_volume_release(NULL);

    /* no callback: the buffer is left alone (ASan would report a free) */
    CHECK(vs_volume_wrap(ctx, VS_F32, d, NULL, NULL, buf, NULL, NULL, &v) == VS_OK, "NULL release");
    vs_volume_release(v);
    buf[0] = 1.0f;

    /* an axis of extent 1 may have any stride (NumPy leaves them arbitrary) */
    const int flat[3] = {8, 6, 1};
    const size_t odd[3] = {4, 32, 12345};
    CHECK(vs_volume_wrap(ctx, VS_F32, flat, odd, NULL, buf, NULL, NULL, &v) == VS_OK, "extent-1 axis stride: %s",
          vs_last_error(ctx));
    vs_volume_release(v);

    const size_t fortran[3] = {4 * 6 * 4, 4 * 4, 4};
    expect_refused("x not fastest", VS_ERR_UNSUPPORTED, VS_F32, d, fortran, buf);
    CHECK(strstr(vs_last_error(ctx), "strides"), "message names the strides: %s", vs_last_error(ctx));
    const size_t padded[3] = {4, 36, 216};
    expect_refused("padded rows", VS_ERR_UNSUPPORTED, VS_F32, d, padded, buf);
    expect_refused("misaligned data", VS_ERR_INVALID_ARGUMENT, VS_F32, d, NULL, (char *)buf + 2);
    expect_refused("NULL data", VS_ERR_INVALID_ARGUMENT, VS_F32, d, NULL, NULL);
    const int zero[3] = {8, 0, 4}, huge[3] = {VS_MAX_DIM + 1, 1, 1};
    expect_refused("zero dimension", VS_ERR_TOO_LARGE, VS_F32, zero, NULL, buf);
    expect_refused("oversized dimension", VS_ERR_TOO_LARGE, VS_F32, huge, NULL, buf);
    expect_refused("unknown type", VS_ERR_INVALID_ARGUMENT, (vs_type)7, d, NULL, buf);
    CHECK(vs_volume_wrap(ctx, VS_F32, d, NULL, NULL, buf, NULL, NULL, NULL) == VS_ERR_INVALID_ARGUMENT,
          "NULL output");
    free(buf);
}

int main(void)
{
    if (vs_context_create(&ctx) != VS_OK) return 2;
    check_type(VS_U8);
    check_type(VS_I16);
    check_type(VS_U16);
    check_type(VS_F32);
    check_layouts();
    vs_context_release(ctx);
    TEST_DONE();
}
