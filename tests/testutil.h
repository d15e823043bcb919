/* Test helpers shared by tests/test_*.c: CHECK counts failures; TEST_DONE
 * returns the exit code.  A test that needs absent data prints "SKIP: why"
 * and returns 0.  Helpers two tests need live here, not in copies. */
#ifndef VS_TESTUTIL_H
#define VS_TESTUTIL_H
#include "vsplat.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

static int tu_failures = 0;
#define CHECK(cond, ...)                                                         \
    do {                                                                         \
        if (!(cond)) {                                                           \
            tu_failures++;                                                       \
            fprintf(stderr, "FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);      \
            fprintf(stderr, __VA_ARGS__);                                        \
            fprintf(stderr, "\n");                                               \
        }                                                                        \
    } while (0)
#define TEST_DONE()                                                              \
    do {                                                                         \
        if (tu_failures) {                                                       \
            fprintf(stderr, "%d check(s) failed\n", tu_failures);                \
            return 1;                                                            \
        }                                                                        \
        printf("all checks passed\n");                                           \
        return 0;                                                                \
    } while (0)

/* Folder of the real volumes: $VSPLAT_DATA, else ../shared/data beside the
 * source tree.  Returns NULL (and the caller skips with a message) if absent. */
static inline const char *tu_data_dir(void)
{
    static char buf[4096];
    const char *env = getenv("VSPLAT_DATA");
    struct stat st;
    if (env && *env && stat(env, &st) == 0) return env;
    const char *src = getenv("VSPLAT_SOURCE_DIR");
    if (!src) src = ".";
    snprintf(buf, sizeof buf, "%s/../shared/data", src);
    if (stat(buf, &st) == 0) return buf;
    return NULL;
}

/* xorshift64 on *state: the same sequence every run, uniform in [0, 1) */
static inline double tu_urand(uint64_t *state)
{
    uint64_t x = *state;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    *state = x;
    return (double)(x >> 11) / 9007199254740992.0;
}

/* Largest absolute difference of two images of the same size, over every
 * channel; a NaN on either side counts as a difference. */
static inline double tu_max_diff(const vs_image *a, const vs_image *b)
{
    double m = 0;
    for (size_t i = 0; i < (size_t)a->width * a->height * 4; i++) {
        double d = fabs((double)a->rgba[i] - b->rgba[i]);
        if (!(d <= m)) m = d;
    }
    return m;
}

static inline const char *tu_tmpdir(void)
{
    const char *t = getenv("TMPDIR");
    return (t && *t) ? t : "/tmp";
}

/* Monotonic wall clock, seconds. */
static inline double tu_now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* Hang guards ("this must not take minutes") scale their bound by this:
 * 10 under the sanitizers (tools/sanitize.sh sets VSPLAT_SANITIZED), whose
 * slowdown on a loaded 2-core machine passed the plain bounds; speed itself
 * is measured in bench/, never asserted here. */
static inline double tu_slack(void)
{
    const char *e = getenv("VSPLAT_SANITIZED");
    return e && *e && *e != '0' ? 10.0 : 1.0;
}

/* The whole file, malloc'ed with one spare byte, its size in *n; NULL (and
 * *n = 0) if it cannot be read. */
static inline unsigned char *tu_read_file(const char *path, size_t *n)
{
    *n = 0;
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    long len = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
    unsigned char *b = len >= 0 && fseek(f, 0, SEEK_SET) == 0 ? malloc((size_t)len + 1) : NULL;
    if (b) *n = fread(b, 1, (size_t)len, f);
    fclose(f);
    return b;
}

/* Write a test input; a test that cannot write its inputs stops. */
static inline void tu_write_file(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f) {
        fprintf(stderr, "cannot create %s\n", path);
        exit(1);
    }
    if (n && fwrite(data, 1, n, f) != n) exit(1);
    fclose(f);
}

/* A frame, with a failed check (and an empty image) if vs_render fails. */
static inline vs_image tu_render(vs_context *ctx, const vs_volume *v, const vs_settings *s, vs_stats *st)
{
    vs_image img = {0, 0, NULL};
    vs_status rc = vs_render(ctx, v, s, &img, st);
    CHECK(rc == VS_OK, "render: %s", vs_last_error(ctx));
    return img;
}

/* PSNR of two images of the same size (vs_image_compare), -1 if it fails. */
static inline double tu_psnr(vs_context *ctx, const vs_image *a, const vs_image *b)
{
    vs_image_diff d;
    if (vs_image_compare(ctx, a, b, &d) != VS_OK) return -1;
    return d.psnr;
}

/* A box filter of an image to 1/f of its size (a supersampled frame made
 * a reference for the small one). */
static inline vs_image tu_shrink(const vs_image *a, int f)
{
    vs_image o = {a->width / f, a->height / f, NULL};
    o.rgba = calloc((size_t)o.width * o.height * 4, sizeof(float));
    if (!o.rgba) return o;
    for (int y = 0; y < o.height; y++)
        for (int x = 0; x < o.width; x++)
            for (int c = 0; c < 4; c++) {
                double acc = 0;
                for (int j = 0; j < f; j++)
                    for (int i = 0; i < f; i++) acc += a->rgba[4 * ((size_t)(y * f + j) * a->width + x * f + i) + c];
                o.rgba[4 * ((size_t)y * o.width + x) + c] = (float)(acc / (f * f));
            }
    return o;
}

/* A synthetic scene (vs_volume_scene), or NULL after a failed check. */
static inline vs_volume *tu_scene(vs_context *ctx, const char *spec)
{
    vs_volume *v = NULL;
    vs_status st = vs_volume_scene(ctx, spec, &v);
    CHECK(st == VS_OK && v, "scene %s: %s", spec, vs_last_error(ctx));
    return st == VS_OK ? v : NULL;
}

/* Loading path must fail within 5 s, clear the output and name the file in
 * the message; why says what is wrong with it. */
static inline void tu_expect_load_fail(vs_context *ctx, const char *path, const vs_load_options *o, const char *why)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    vs_volume *v = (vs_volume *)1;
    double t0 = tu_now_s();
    vs_status st = vs_volume_load(ctx, path, o, &v);
    double dt = tu_now_s() - t0;
    const char *msg = vs_last_error(ctx);
    CHECK(st != VS_OK, "%s (%s): loaded although it should fail", base, why);
    CHECK(v == NULL, "%s (%s): out not cleared", base, why);
    CHECK(msg && *msg && strstr(msg, base), "%s (%s): message '%s' does not name the file", base, why, msg);
    CHECK(dt < 5.0 * tu_slack(), "%s (%s): took %.1f s", base, why, dt);
    if (st == VS_OK) vs_volume_release(v);
    printf("  %-34s -> %s: %s\n", why, vs_status_string(st), msg);
}

/* A fresh folder TMPDIR/vsplat_NAME_XXXXXX into buf; 0 (with a message)
 * if it cannot be made. */
static inline int tu_make_tmpdir(char *buf, size_t cap, const char *name)
{
    snprintf(buf, cap, "%s/vsplat_%s_XXXXXX", tu_tmpdir(), name);
    if (mkdtemp(buf)) return 1;
    perror("mkdtemp");
    return 0;
}

/* Remove a test's folder, unless a check failed: then it stays for a look. */
static inline void tu_remove_tmpdir(const char *dir)
{
    if (tu_failures) {
        fprintf(stderr, "kept %s\n", dir);
        return;
    }
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
}
#endif
