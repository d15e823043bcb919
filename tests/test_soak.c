/* Soak: many frames in one context with changing views, iso-ranges,
 * pipelines, thread counts and volumes, checking that resident memory stays
 * flat after a warm-up and (in the ASan build, tools/sanitize.sh) that
 * nothing leaks.  Brief by default so it runs in CI:
 *   VSPLAT_SOAK_FRAMES=N   frames (default 1000; 200 with VSPLAT_TEST_QUICK)
 * e.g. VSPLAT_SOAK_FRAMES=20000 build/tests/test_soak for a long run.
 * Resident memory comes from /proc/self/statm, sampled every 1/20 of the
 * run; after the first quarter (pool, tables and caches warmed up) it may
 * not grow by more than 4 MB.  Sanitizer builds (VSPLAT_SANITIZED=1) skip
 * that bound: ASan's quarantine keeps freed memory resident by design, and
 * LeakSanitizer checks the leaks there instead.
 *
 * Also checked: a volume released and another created in its place (same
 * dims, same value range, very likely the same address) must not be drawn
 * from the first one's cached relevant-voxel list. */
#include "internal.h"
#include "testutil.h"

#include <math.h>
#include <time.h>
#include <unistd.h>

static vs_context *ctx;

static double rss_mb(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    if (!f) return -1;
    long size = 0, res = 0;
    int n = fscanf(f, "%ld %ld", &size, &res);
    fclose(f);
    if (n != 2) return -1;
    return (double)res * (double)sysconf(_SC_PAGESIZE) / (1024.0 * 1024.0);
}

/* A ball of radius r at centre (cx, cy, cz), linear ramp, 0..1 exactly
 * (the range does not depend on r or the centre). */
static vs_volume *ball(int n, double cx, double cy, double cz, double r)
{
    vs_volume *v;
    int d[3] = {n, n, n};
    if (vs_volume_create(ctx, VS_F32, d, NULL, &v) != VS_OK) return NULL;
    float *p = vs_volume_data(v);
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double q = sqrt((i - cx) * (i - cx) + (j - cy) * (j - cy) + (k - cz) * (k - cz));
                double f = 0.5 + (r - q) / 3.0;
                p[((size_t)k * n + j) * n + i] = (float)(f < 0 ? 0 : f > 1 ? 1 : f);
            }
    vs_volume_update_range(v);
    return v;
}

/* Same dims and range, different content, probably the same address. */
static void test_volume_replaced(void)
{
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 48;
    s.has_iso = 1;
    s.iso_lo = 0.5;
    s.ramp = 0.05;
    for (int p = 0; p < 4; p++) {
        s.pipeline = (vs_pipeline)p;
        vs_volume *a = ball(24, 8, 8, 8, 5);
        vs_image ia, ib, fresh;
        if (!a || vs_render(ctx, a, &s, &ia, NULL) != VS_OK) {
            CHECK(0, "render a: %s", vs_last_error(ctx));
            return;
        }
        const void *addr = a;
        vs_volume_release(a);
        vs_volume *b = ball(24, 15, 15, 15, 6);
        if (!b || vs_render(ctx, b, &s, &ib, NULL) != VS_OK) {
            CHECK(0, "render b: %s", vs_last_error(ctx));
            return;
        }
        vs_context *c2;
        vs_context_create(&c2);
        vs_render(c2, b, &s, &fresh, NULL);
        double d = tu_max_diff(&ib, &fresh);
        printf("volume replaced (%s address), %-10s: difference to a fresh context %.3g\n",
               (const void *)b == addr ? "same" : "other", vs_pipeline_name(s.pipeline), d);
        CHECK(d == 0.0, "%s: a new volume was drawn from the old one's cached voxels (difference %g)",
              vs_pipeline_name(s.pipeline), d);
        vs_image_free(&ia);
        vs_image_free(&ib);
        vs_image_free(&fresh);
        vs_context_release(c2);
        vs_volume_release(b);
    }
}

/* The same volume, its data rewritten and the range recomputed (the
 * vs_volume_update_range contract) to the same range: the next frame must
 * show the new data, not the relevant-voxel list cached for the old. */
static void test_volume_rewritten(void)
{
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 48;
    s.has_iso = 1;
    s.iso_lo = 0.5;
    s.ramp = 0.05;
    vs_volume *a = ball(24, 8, 8, 8, 5), *b = ball(24, 15, 15, 15, 6);
    if (!a || !b) return;
    vs_image ia, ib, fresh;
    if (vs_render(ctx, a, &s, &ia, NULL) == VS_OK) {
        memcpy(vs_volume_data(a), vs_volume_data(b), (size_t)24 * 24 * 24 * sizeof(float));
        vs_volume_update_range(a);
        if (vs_render(ctx, a, &s, &ib, NULL) == VS_OK && vs_render(ctx, b, &s, &fresh, NULL) == VS_OK) {
            double d = tu_max_diff(&ib, &fresh);
            printf("volume data rewritten in place: difference to the new data's image %.3g\n", d);
            CHECK(d == 0.0, "rewritten volume drawn from its old cached voxels (difference %g)", d);
            vs_image_free(&ib);
            vs_image_free(&fresh);
        }
        vs_image_free(&ia);
    }
    vs_volume_release(a);
    vs_volume_release(b);
}

int main(void)
{
    const char *q = getenv("VSPLAT_TEST_QUICK"), *fr = getenv("VSPLAT_SOAK_FRAMES"), *san = getenv("VSPLAT_SANITIZED");
    int quick = q && *q && strcmp(q, "0") != 0;
    int sanitized = san && *san && strcmp(san, "0") != 0;
    long frames = fr && *fr ? strtol(fr, NULL, 10) : (quick ? 200 : 1000);
    if (frames < 20) frames = 20;
    if (vs_context_create(&ctx) != VS_OK) return 2;

    test_volume_replaced();
    test_volume_rewritten();

    vs_volume *vols[2] = {ball(28, 13.5, 13.5, 13.5, 9), NULL};
    if (vs_volume_scene(ctx, "ml:24", &vols[1]) != VS_OK || !vols[0]) {
        CHECK(0, "volumes: %s", vs_last_error(ctx));
        TEST_DONE();
    }
    const long warm = frames / 4, step = frames / 20 > 0 ? frames / 20 : 1;
    double rss0 = -1, rss_max = 0, rss_first = rss_mb(), t0 = tu_now_s();
    unsigned long long splatted = 0;
    int failures = 0;
    for (long f = 0; f < frames; f++) {
        vs_settings s;
        vs_settings_init(&s);
        s.width = 40 + (int)(f % 3) * 12;
        s.height = 40 + (int)(f % 5) * 6;
        s.pipeline = (vs_pipeline)(f % 5);
        s.azimuth = fmod(f * 7.3, 360.0);
        s.elevation = fmod(f * 3.1, 180.0) - 90.0;
        s.has_iso = 1;
        s.iso_lo = 0.3 + 0.05 * (double)((f / 7) % 8); /* a new relevant set every 7 frames */
        s.ramp = 0.03;
        s.threads = (int)((f / 50) % 3);               /* 0 (auto), 1, 2: the pool is rebuilt */
        s.tile_size = (f / 13) % 2 ? 16 : 64;
        s.slab = (f / 11) % 3 == 0 ? 0.5 : 1.0;
        s.exact_normals = (int)(f / 17) % 2;
        s.pin = 0;
        const vs_volume *v = vols[(f / 100) % 2];
        if (f % 250 == 249) { /* replace a volume now and then */
            vs_volume_release(vols[0]);
            vols[0] = ball(28, 13.5, 13.5, 13.5, 7 + (f / 250) % 4);
            v = vols[0];
        }
        vs_image img;
        vs_stats st;
        vs_status rc = vs_render(ctx, v, &s, &img, &st);
        if (rc != VS_OK) {
            if (failures++ < 5) CHECK(0, "frame %ld: %s", f, vs_last_error(ctx));
            continue;
        }
        splatted += st.voxels_splatted;
        for (size_t i = 0; i < (size_t)img.width * img.height * 4; i++)
            if (!isfinite(img.rgba[i])) {
                if (failures++ < 5) CHECK(0, "frame %ld: non-finite pixel", f);
                break;
            }
        vs_image_free(&img);
        if (f == warm) rss0 = rss_mb();
        if (f % step == 0 || f == frames - 1) {
            double r = rss_mb();
            if (f >= warm && r > rss_max) rss_max = r;
            printf("frame %6ld  rss %.1f MB\n", f, r);
        }
    }
    double rss_end = rss_mb(), secs = tu_now_s() - t0;
    printf("%ld frames in %.1f s (%.1f ms/frame), %llu voxel-sheet splats; rss: start %.1f MB, after warm-up %.1f MB, "
           "max %.1f MB, end %.1f MB\n",
           frames, secs, 1e3 * secs / frames, splatted, rss_first, rss0, rss_max, rss_end);
    if (sanitized) {
        printf("sanitizer build: resident-memory bound not checked (LeakSanitizer checks leaks at exit)\n");
    } else {
        CHECK(rss_max - rss0 <= 4.0, "resident memory grew by %.1f MB after warm-up (%.1f -> %.1f MB)", rss_max - rss0,
              rss0, rss_max);
    }
    vs_volume_release(vols[0]);
    vs_volume_release(vols[1]);
    vs_context_release(ctx);
    TEST_DONE();
}
