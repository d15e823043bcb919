/* The struct_size scheme (docs/ABI.md) as a program built against an older,
 * shorter header sees it.  Such a program is simulated by cutting the
 * structs after some field: vs_settings_init_sized / vs_load_options_init_sized
 * get the shorter sizes, the structs sit in front of canary bytes (writes)
 * or of a page without access (reads), and the results are compared with
 * the full layout whose fields beyond the cut keep their defaults.
 * Unknown sizes must be refused with VS_ERR_INVALID_ARGUMENT and a one-line
 * message. */
#include "testutil.h"

#include <stddef.h>
#include <stdint.h>
#include <sys/mman.h>
#include <unistd.h>

#define END(T, m) (offsetof(T, m) + sizeof(((T *)0)->m))
#define ROUND8(n) (((n) + 7) / 8 * 8)
#define CANARY 0xA5
#define NCANARY 64

/* A block of `size` bytes whose end touches a page without access: reading
 * or writing one byte past the struct faults.  *base/munmap to free. */
static void *guarded(size_t size, void **base)
{
    const size_t pg = (size_t)sysconf(_SC_PAGESIZE);
    char *m = mmap(NULL, 2 * pg, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED || size > pg || mprotect(m + pg, pg, PROT_NONE)) {
        fprintf(stderr, "test_abi: cannot map a guard page\n");
        exit(1);
    }
    *base = m;
    return m + pg - size;
}

static void unguard(void *base) { munmap(base, 2 * (size_t)sysconf(_SC_PAGESIZE)); }

/* n bytes followed by NCANARY canary bytes, all canary at first. */
static unsigned char *canaried(size_t n)
{
    unsigned char *p = malloc(n + NCANARY);
    if (!p) exit(1);
    memset(p, CANARY, n + NCANARY);
    return p;
}

static int canary_intact(const unsigned char *p, size_t n)
{
    for (size_t i = 0; i < NCANARY; i++)
        if (p[n + i] != CANARY) return 0;
    return 1;
}

static int count_progress(void *user, double fraction)
{
    (void)fraction;
    if (user) ++*(int *)user;
    return 0;
}

/* The message a refused size must give, one line. */
static void expect_refused(vs_context *ctx, vs_status rc, const char *want, const char *what)
{
    CHECK(rc == VS_ERR_INVALID_ARGUMENT, "%s: got %s", what, vs_status_string(rc));
    const char *msg = vs_last_error(ctx);
    CHECK(strstr(msg, want) != NULL, "%s: message \"%s\" lacks \"%s\"", what, msg, want);
    CHECK(!strchr(msg, '\n'), "%s: message has more than one line", what);
}

/* Settings a program changes: fields all along the struct, none at its
 * default, so a field dropped or taken from beyond the cut shows. */
static void changed_settings(vs_settings *s, int *progress_calls)
{
    vs_settings_init(s);
    s->pipeline = VS_PIPELINE_PRE;
    s->width = 40;
    s->height = 36;
    s->azimuth = 30;
    s->elevation = 20;
    s->zoom = 0.9;
    s->kernel_radius = 1.6;
    s->seam = 2;
    s->iso_opacity = 0.7f;
    s->material[1] = 0.5f;
    s->background[3] = 1.0f;
    s->diffuse = 0.5;
    s->occlusion = 0;
    s->tile_size = 16;
    s->threads = 1;
    s->isa = VS_ISA_SCALAR;
    s->pin = 0;
    s->ray_step = 0.2;
    s->progress = count_progress;
    s->progress_user = progress_calls;
}

/* The stats fields that do not measure time, as far as `size` reaches. */
static int same_counts(const vs_stats *a, const vs_stats *b, size_t size)
{
#define SAME(m) (END(vs_stats, m) > size || a->m == b->m)
    return SAME(threads) && SAME(width) && SAME(height) && SAME(voxels_total) && SAME(voxels_relevant) &&
           SAME(voxels_splatted) && SAME(voxels_culled) && SAME(sheets) && SAME(tiles_total) &&
           SAME(tiles_shaded) && SAME(iso_lo) && SAME(iso_hi) && SAME(ramp) && SAME(pin_warning) &&
           (END(vs_stats, pipeline) > size || !strcmp(a->pipeline, b->pipeline)) &&
           (END(vs_stats, isa) > size || !strcmp(a->isa, b->isa));
#undef SAME
}

static void test_init_writes_only_the_callers_bytes(void)
{
    vs_settings full;
    vs_settings_init(&full);
    CHECK(full.struct_size == sizeof(vs_settings) && full.stats_size == sizeof(vs_stats),
          "vs_settings_init records %zu/%zu", full.struct_size, full.stats_size);
    const size_t cuts[] = {sizeof(size_t), ROUND8(END(vs_settings, pipeline)), ROUND8(END(vs_settings, center)),
                           ROUND8(END(vs_settings, material)), ROUND8(END(vs_settings, tile_size)),
                           ROUND8(END(vs_settings, progress)), sizeof(vs_settings)};
    for (size_t i = 0; i < sizeof cuts / sizeof *cuts; i++) {
        const size_t n = cuts[i];
        unsigned char *p = canaried(n);
        vs_settings_init_sized((vs_settings *)p, n, 96);
        CHECK(canary_intact(p, n), "vs_settings_init_sized(%zu) wrote past the struct", n);
        CHECK(((vs_settings *)p)->struct_size == n, "struct_size %zu recorded as %zu", n,
              ((vs_settings *)p)->struct_size);
        /* the defaults, as far as the struct reaches */
        if (n > offsetof(vs_settings, pipeline))
            CHECK(!memcmp(p + offsetof(vs_settings, pipeline), (unsigned char *)&full + offsetof(vs_settings, pipeline),
                          n - offsetof(vs_settings, pipeline)),
                  "init_sized(%zu) did not write the defaults", n);
        free(p);
    }
    unsigned char *p = canaried(4);
    vs_settings_init_sized((vs_settings *)p, 4, sizeof(vs_stats)); /* too short to hold struct_size */
    CHECK(canary_intact(p, 0), "init_sized(4) wrote into the 4 bytes");
    free(p);
    vs_settings_init_sized(NULL, sizeof(vs_settings), sizeof(vs_stats));

    const size_t lcut = ROUND8(END(vs_load_options, type));
    p = canaried(lcut);
    vs_load_options_init_sized((vs_load_options *)p, lcut);
    CHECK(canary_intact(p, lcut), "vs_load_options_init_sized(%zu) wrote past the struct", lcut);
    CHECK(((vs_load_options *)p)->struct_size == lcut && ((vs_load_options *)p)->type == VS_U8,
          "load options init_sized(%zu)", lcut);
    free(p);
}

/* A program built before levels of detail gets none, however small it
 * renders; one built with them gets them by default. */
static void test_lod_default(vs_context *ctx)
{
    vs_volume *v = tu_scene(ctx, "sphere:128");
    if (!v) return;
    const size_t cut = ROUND8(END(vs_settings, preintegration));
    void *base;
    vs_settings *old = guarded(cut, &base);
    vs_settings_init_sized(old, cut, sizeof(vs_stats));
    old->width = old->height = 32;
    vs_settings now;
    vs_settings_init(&now);
    now.width = now.height = 32;
    vs_image a = {0, 0, NULL}, b = {0, 0, NULL};
    vs_stats sa, sb;
    CHECK(vs_render(ctx, v, old, &a, &sa) == VS_OK && vs_render(ctx, v, &now, &b, &sb) == VS_OK, "render: %s",
          vs_last_error(ctx));
    CHECK(sa.lod_level == 0 && sb.lod_level > 0, "levels: older layout %d, current %d", sa.lod_level, sb.lod_level);
    vs_image_free(&a);
    vs_image_free(&b);
    unguard(base);
    vs_volume_release(v);
}

/* A program built before the copy on cubic voxels splats an anisotropic
 * grid as stored; one built with it gets the copy by default. */
static void test_resample_default(vs_context *ctx)
{
    const int d[3] = {24, 24, 12};
    const double sp[3] = {1, 1, 2};
    vs_volume *v = NULL;
    CHECK(vs_volume_create(ctx, VS_U8, d, sp, &v) == VS_OK, "create");
    if (!v) return;
    unsigned char *f = vs_volume_data(v);
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++) {
                const double x = i - 11.5, y = j - 11.5, z = 2 * (k - 5.5);
                f[(k * d[1] + j) * d[0] + i] = x * x + y * y + z * z < 64 ? 200 : 0;
            }
    vs_volume_update_range(v);
    const size_t cut = ROUND8(END(vs_settings, lod_pixels));
    void *base;
    vs_settings *old = guarded(cut, &base);
    vs_settings_init_sized(old, cut, sizeof(vs_stats));
    old->width = old->height = 48;
    old->azimuth = 30;
    old->elevation = 30;
    vs_settings now;
    vs_settings_init(&now);
    now.width = now.height = 48;
    now.azimuth = 30;
    now.elevation = 30;
    vs_image a = {0, 0, NULL}, b = {0, 0, NULL};
    vs_stats sa, sb;
    CHECK(vs_render(ctx, v, old, &a, &sa) == VS_OK && vs_render(ctx, v, &now, &b, &sb) == VS_OK, "render: %s",
          vs_last_error(ctx));
    CHECK(sa.resampled == 0 && sb.resampled == 1, "copy: older layout %d, current %d", sa.resampled, sb.resampled);
    vs_image_free(&a);
    vs_image_free(&b);
    unguard(base);
    vs_volume_release(v);
}

/* Render with settings cut after various fields and stats cut likewise:
 * the same image and counts as the full layout with the missing fields at
 * their defaults, no byte read or written past either struct. */
static void test_older_layouts_render(vs_context *ctx, const vs_volume *vol)
{
    const size_t scuts[] = {ROUND8(END(vs_settings, width)),         ROUND8(END(vs_settings, zoom)),
                            ROUND8(END(vs_settings, kernel_radius)), ROUND8(END(vs_settings, seam)),
                            ROUND8(END(vs_settings, material)),      ROUND8(END(vs_settings, background)),
                            ROUND8(END(vs_settings, occlusion)),     ROUND8(END(vs_settings, tile_size)),
                            ROUND8(END(vs_settings, threads)),       ROUND8(END(vs_settings, pin)),
                            ROUND8(END(vs_settings, ray_step)),      ROUND8(END(vs_settings, progress)),
                            sizeof(vs_settings)};
    const size_t tcuts[] = {ROUND8(END(vs_stats, isa)),          ROUND8(END(vs_stats, height)),
                            ROUND8(END(vs_stats, voxels_splatted)), ROUND8(END(vs_stats, tiles_shaded)),
                            ROUND8(END(vs_stats, ms_stage)),     ROUND8(END(vs_stats, ramp)),
                            sizeof(vs_stats)};
    const size_t ns = sizeof scuts / sizeof *scuts, nt = sizeof tcuts / sizeof *tcuts;
    int calls_old = 0, calls_ref = 0;
    vs_settings changed;
    changed_settings(&changed, &calls_old);
    for (size_t i = 0; i < ns; i++) {
        const size_t n = scuts[i], m = tcuts[i % nt];
        /* the old program: its init, then its own fields changed */
        void *base;
        vs_settings *old = guarded(n, &base);
        vs_settings_init_sized(old, n, m);
        memcpy((char *)old + offsetof(vs_settings, pipeline), (char *)&changed + offsetof(vs_settings, pipeline),
               n - offsetof(vs_settings, pipeline));
        unsigned char before[sizeof(vs_settings)];
        memcpy(before, old, n);
        /* the full layout: the same fields changed, the rest default */
        vs_settings ref;
        vs_settings_init(&ref);
        memcpy((char *)&ref + offsetof(vs_settings, pipeline), (char *)&changed + offsetof(vs_settings, pipeline),
               n - offsetof(vs_settings, pipeline));
        const int has_progress = n >= END(vs_settings, progress_user);
        if (has_progress) ref.progress_user = &calls_ref;
        /* older programs render at full resolution (docs/ABI.md) */
        if (n < END(vs_settings, lod_pixels)) ref.lod_pixels = 0.0;
        if (n < END(vs_settings, resample)) ref.resample = 0;

        unsigned char *st = canaried(m);
        vs_image a = {0, 0, NULL}, b = {0, 0, NULL};
        vs_stats sref;
        calls_old = calls_ref = 0;
        vs_status ra = vs_render(ctx, vol, old, &a, (vs_stats *)st);
        vs_status rb = vs_render(ctx, vol, &ref, &b, &sref);
        CHECK(ra == VS_OK && rb == VS_OK, "settings cut at %zu: %s / %s (%s)", n, vs_status_string(ra),
              vs_status_string(rb), vs_last_error(ctx));
        if (ra == VS_OK && rb == VS_OK) {
            CHECK(a.width == b.width && a.height == b.height && tu_max_diff(&a, &b) == 0.0,
                  "settings cut at %zu: image %dx%d differs from the full layout's %dx%d (max %g)", n, a.width,
                  a.height, b.width, b.height, a.width == b.width && a.height == b.height ? tu_max_diff(&a, &b) : -1);
            CHECK(canary_intact(st, m), "stats of %zu bytes: vs_render wrote past them", m);
            const vs_stats *so = (const vs_stats *)st;
            CHECK(so->struct_size == m, "stats struct_size %zu, want %zu", so->struct_size, m);
            CHECK(same_counts(so, &sref, m), "settings cut at %zu, stats cut at %zu: counts differ", n, m);
            CHECK(calls_old == calls_ref && (calls_ref > 0) == has_progress,
                  "settings cut at %zu: progress called %d times, full layout %d", n, calls_old, calls_ref);
            /* JSON of the short stats: nothing read past them, only their keys */
            void *sbase;
            vs_stats *gs = guarded(m, &sbase);
            memcpy(gs, st, m);
            char json[2048];
            size_t len = vs_stats_to_json(gs, json, sizeof json);
            CHECK(len > 0 && len < sizeof json && json[len - 2] == '}', "stats_to_json of %zu bytes: %zu", m, len);
            CHECK((strstr(json, "\"pin_warning\"") != NULL) == (m == sizeof(vs_stats)),
                  "stats_to_json of %zu bytes: pin_warning key", m);
            CHECK((strstr(json, "\"ms_stage\"") != NULL) == (m >= END(vs_stats, ms_stage)),
                  "stats_to_json of %zu bytes: ms_stage key", m);
            unguard(sbase);
        }
        CHECK(!memcmp(before, old, n), "vs_render changed the caller's settings");
        vs_image_free(&a);
        vs_image_free(&b);
        free(st);
        unguard(base);
    }
}

static void test_unknown_sizes_refused(vs_context *ctx, const vs_volume *vol)
{
    char want[200];
    const size_t inside_center = offsetof(vs_settings, center) + 8; /* cuts through center[3] */
    const size_t bad[] = {0, 3, 1234, inside_center, sizeof(vs_settings) + 8, (size_t)0x5A5A5A5A5A5A5A5AULL};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        /* room for a newer header's larger struct */
        _Alignas(vs_settings) unsigned char buf[sizeof(vs_settings) + 64];
        vs_settings *s = (vs_settings *)buf;
        memset(buf, 0x5A, sizeof buf);
        vs_settings_init(s);
        s->width = s->height = 16;
        s->struct_size = bad[i];
        unsigned char *st = canaried(0);
        vs_image im = {3, 3, (float *)1};
        vs_status rc = vs_render(ctx, vol, s, &im, (vs_stats *)st);
        snprintf(want, sizeof want,
                 "vs_settings of %zu bytes: not a layout this vsplat %s knows; initialise it with vs_settings_init()",
                 bad[i], VS_VERSION_STRING);
        expect_refused(ctx, rc, want, "struct_size");
        CHECK(im.rgba == NULL && im.width == 0, "struct_size %zu: output not cleared", bad[i]);
        CHECK(canary_intact(st, 0), "struct_size %zu: stats written", bad[i]);
        free(st);
    }
    /* never initialised: stack garbage, or zeroed with = {0} */
    vs_settings junk;
    memset(&junk, 0x5A, sizeof junk);
    vs_image im = {0, 0, NULL};
    expect_refused(ctx, vs_render(ctx, vol, &junk, &im, NULL), "not a layout this vsplat", "garbage settings");
    memset(&junk, 0, sizeof junk);
    expect_refused(ctx, vs_render(ctx, vol, &junk, &im, NULL), "vs_settings of 0 bytes", "zeroed settings");
    /* a valid settings layout with a stats size no layout has */
    vs_settings s;
    vs_settings_init(&s);
    s.stats_size = END(vs_stats, pipeline) + 1;
    expect_refused(ctx, vs_render(ctx, vol, &s, &im, NULL), "vs_settings.stats_size", "stats_size");
    s.stats_size = sizeof(vs_stats) + 8;
    expect_refused(ctx, vs_render(ctx, vol, &s, &im, NULL), "vs_settings.stats_size", "newer stats_size");

    /* stats of an unknown size give no JSON */
    vs_stats z;
    memset(&z, 0, sizeof z);
    char json[64];
    memset(json, 'x', sizeof json);
    CHECK(vs_stats_to_json(&z, json, sizeof json) == 0 && json[0] == '\0', "stats_to_json of 0 bytes");
    z.struct_size = sizeof z + 8;
    CHECK(vs_stats_to_json(&z, NULL, 0) == 0, "stats_to_json of a newer layout");
}

/* vs_volume_load: load options cut after `type` (no endian, no spacing)
 * load as the full options with those at their defaults; unknown sizes
 * are refused. */
static void test_load_options(vs_context *ctx)
{
    char path[512];
    snprintf(path, sizeof path, "%s/test_abi_%d.raw", tu_tmpdir(), (int)getpid());
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL, "cannot write %s", path);
    if (!f) return;
    for (int i = 0; i < 6 * 5 * 4; i++) fputc(i * 2, f);
    fclose(f);

    const size_t n = ROUND8(END(vs_load_options, type));
    void *base;
    vs_load_options *old = guarded(n, &base);
    vs_load_options_init_sized(old, n);
    old->raw = 1;
    old->dims[0] = 6, old->dims[1] = 5, old->dims[2] = 4;
    vs_load_options full;
    vs_load_options_init(&full);
    full.raw = 1;
    memcpy(full.dims, old->dims, sizeof full.dims);
    vs_volume *a = NULL, *b = NULL;
    vs_status ra = vs_volume_load(ctx, path, old, &a), rb = vs_volume_load(ctx, path, &full, &b);
    CHECK(ra == VS_OK && rb == VS_OK, "load with options of %zu bytes: %s", n, vs_last_error(ctx));
    if (a && b) {
        int da[3], db[3];
        double sa[3], sb[3];
        vs_volume_dims(a, da);
        vs_volume_dims(b, db);
        vs_volume_spacing(a, sa);
        vs_volume_spacing(b, sb);
        CHECK(!memcmp(da, db, sizeof da) && !memcmp(sa, sb, sizeof sa) &&
                  !memcmp(vs_volume_data(a), vs_volume_data(b), 6 * 5 * 4),
              "options of %zu bytes load another volume", n);
    }
    vs_volume_release(a);
    vs_volume_release(b);
    unguard(base);

    char want[200];
    const size_t bad[] = {0, 5, sizeof(vs_load_options) + 8};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        full.struct_size = bad[i];
        vs_volume *v = NULL;
        snprintf(want, sizeof want,
                 "vs_load_options of %zu bytes: not a layout this vsplat %s knows; initialise it with "
                 "vs_load_options_init()",
                 bad[i], VS_VERSION_STRING);
        expect_refused(ctx, vs_volume_load(ctx, path, &full, &v), want, "load options struct_size");
        CHECK(v == NULL, "refused load returned a volume");
    }
    remove(path);
}

int main(void)
{
    vs_context *ctx = NULL;
    vs_volume *vol = NULL;
    if (vs_context_create(&ctx) != VS_OK || vs_volume_scene(ctx, "sphere:24", &vol) != VS_OK) {
        fprintf(stderr, "test_abi: set-up failed\n");
        return 1;
    }
    test_init_writes_only_the_callers_bytes();
    test_resample_default(ctx);
    test_older_layouts_render(ctx, vol);
    test_unknown_sizes_refused(ctx, vol);
    test_load_options(ctx);
    test_lod_default(ctx);
    vs_volume_release(vol);
    vs_context_release(ctx);
    TEST_DONE();
}
