/* Image files and comparison: write/read round trips per format, compare on
 * pairs with known answers, failed writes leave nothing behind. */
#include "internal.h"
#include "testutil.h"

#include <dirent.h>
#include <math.h>
#include <unistd.h>

static char tmp[1024];

static vs_image make(int w, int h, int opaque)
{
    vs_image im = {w, h, malloc(sizeof(float) * 4 * (size_t)w * h)};
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float *p = im.rgba + ((size_t)y * w + x) * 4;
            p[0] = (float)x / (float)(w - 1);
            p[1] = (float)y / (float)(h - 1);
            p[2] = (float)((x * 7 + y * 13) % 17) / 16.0f;
            p[3] = opaque ? 1.0f : (float)((x + y) % 5) / 4.0f;
        }
    return im;
}

static vs_image copy(const vs_image *a)
{
    vs_image b = {a->width, a->height, malloc(sizeof(float) * 4 * (size_t)a->width * a->height)};
    memcpy(b.rgba, a->rgba, sizeof(float) * 4 * (size_t)a->width * a->height);
    return b;
}

/* Largest channel difference, skipping colour where alpha is 0 if asked
 * (premultiplied formats cannot keep it). */
static double max_diff(const vs_image *a, const vs_image *b, int skip_transparent)
{
    double m = 0;
    size_t n = (size_t)a->width * a->height;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 4; c++) {
            if (skip_transparent && c < 3 && a->rgba[i * 4 + 3] == 0.0f) continue;
            double d = fabs((double)a->rgba[i * 4 + c] - b->rgba[i * 4 + c]);
            if (d > m) m = d;
        }
    return m;
}

static int count_temp_files(void)
{
    DIR *d = opendir(tmp);
    int n = 0;
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL)
        if (strstr(e->d_name, ".tmp-")) n++;
    if (d) closedir(d);
    return n;
}

static void round_trip(vs_context *ctx, const char *name, int bits, int opaque, double tol,
                       int skip_transparent)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", tmp, name);
    vs_image a = make(37, 23, opaque), b = {0, 0, NULL};
    vs_status st = vs_image_write(ctx, path, &a, bits);
    CHECK(st == VS_OK, "write %s: %s", name, vs_last_error(ctx));
    st = vs_image_read(ctx, path, &b);
    CHECK(st == VS_OK, "read %s: %s", name, vs_last_error(ctx));
    if (st == VS_OK) {
        CHECK(b.width == a.width && b.height == a.height, "%s: size %dx%d", name, b.width, b.height);
        double m = max_diff(&a, &b, skip_transparent);
        CHECK(m <= tol, "%s (bits %d): max difference %g > %g", name, bits, m, tol);
        printf("  %-14s bits %2d %s: max difference %.3g\n", name, bits, opaque ? "opaque" : "alpha ",
               m);
    }
    vs_image_free(&a);
    vs_image_free(&b);
}

static void test_round_trips(vs_context *ctx)
{
    const double q8 = 0.5 / 255 + 1e-6, q16 = 0.5 / 65535 + 1e-7;
    round_trip(ctx, "a8.png", 8, 0, q8, 0);      /* straight alpha kept */
    round_trip(ctx, "a16.png", 16, 0, q16, 0);
    round_trip(ctx, "f.exr", 0, 1, 0.0, 0);      /* float, opaque: exact */
    round_trip(ctx, "fa.exr", 32, 0, 1e-6, 1);   /* stored premultiplied */
    round_trip(ctx, "h.exr", 16, 0, 1e-3, 1);    /* half */
    round_trip(ctx, "t16.tif", 16, 0, q16, 0);
    round_trip(ctx, "t8.tiff", 8, 0, q8, 0);
    round_trip(ctx, "tf.tif", 32, 0, 0.0, 0);    /* float TIFF: exact */
    CHECK(count_temp_files() == 0, "temporary files left behind");

    /* out-of-range and NaN values are clamped for integer formats */
    char path[1200];
    snprintf(path, sizeof path, "%s/clamp.png", tmp);
    vs_image a = make(4, 3, 1), b = {0, 0, NULL};
    a.rgba[0] = -1.0f;
    a.rgba[1] = 7.0f;
    a.rgba[2] = NAN;
    CHECK(vs_image_write(ctx, path, &a, 8) == VS_OK, "clamp write: %s", vs_last_error(ctx));
    CHECK(vs_image_read(ctx, path, &b) == VS_OK, "clamp read: %s", vs_last_error(ctx));
    if (b.rgba)
        CHECK(b.rgba[0] == 0.0f && b.rgba[1] == 1.0f && b.rgba[2] == 0.0f, "clamped to %g %g %g",
              b.rgba[0], b.rgba[1], b.rgba[2]);
    vs_image_free(&a);
    vs_image_free(&b);
}

static void test_compare(vs_context *ctx)
{
    vs_image a = make(64, 48, 0);
    vs_image b = copy(&a);
    vs_image_diff d;
    vs_status st = vs_image_compare(ctx, &a, &b, &d);
    CHECK(st == VS_OK, "compare: %s", vs_last_error(ctx));
    CHECK(d.rmse == 0.0 && d.max_abs == 0.0, "identical: rmse %g max %g", d.rmse, d.max_abs);
    CHECK(isinf(d.psnr) && d.psnr > 0, "identical: psnr %g", d.psnr);
    CHECK(d.ssim == 1.0, "identical: ssim %.17g", d.ssim);

    /* constant offset of 0.1 on every channel: values 0.25 apart keep float
     * arithmetic close to exact */
    size_t n = (size_t)a.width * a.height * 4;
    for (size_t i = 0; i < n; i++) {
        a.rgba[i] = 0.25f + 0.5f * a.rgba[i];
        b.rgba[i] = a.rgba[i] + 0.1f;
    }
    st = vs_image_compare(ctx, &a, &b, &d);
    CHECK(st == VS_OK, "compare: %s", vs_last_error(ctx));
    CHECK(fabs(d.rmse - 0.1) < 1e-6, "offset: rmse %.9g", d.rmse);
    CHECK(fabs(d.max_abs - 0.1) < 1e-6, "offset: max %.9g", d.max_abs);
    CHECK(fabs(d.psnr - 20.0) < 1e-4, "offset: psnr %.9g", d.psnr);
    CHECK(d.ssim < 1.0 && d.ssim > 0.9, "offset: ssim %.9g", d.ssim);
    printf("  offset 0.1: rmse %.6f max %.6f psnr %.4f ssim %.6f\n", d.rmse, d.max_abs, d.psnr, d.ssim);

    /* one pixel, one channel changed by exactly 0.375 */
    memcpy(b.rgba, a.rgba, n * sizeof(float));
    size_t k = ((size_t)17 * a.width + 29) * 4 + 2;
    a.rgba[k] = 0.5f;
    b.rgba[k] = 0.875f;
    st = vs_image_compare(ctx, &a, &b, &d);
    CHECK(st == VS_OK, "compare: %s", vs_last_error(ctx));
    CHECK(d.max_abs == 0.375, "single pixel: max %.17g", d.max_abs);
    double rmse = sqrt(0.375 * 0.375 / (double)n);
    CHECK(fabs(d.rmse - rmse) < 1e-12, "single pixel: rmse %.17g, expected %.17g", d.rmse, rmse);
    CHECK(d.ssim < 1.0 && d.ssim > 0.99, "single pixel: ssim %.9g", d.ssim);

    /* unrelated images score low */
    for (size_t i = 0; i < n; i++) b.rgba[i] = (float)((i * 2654435761u) % 1000) / 999.0f;
    st = vs_image_compare(ctx, &a, &b, &d);
    CHECK(st == VS_OK && d.ssim < 0.2, "noise: ssim %.6g", d.ssim);

    /* size mismatch */
    vs_image c = make(10, 10, 1);
    st = vs_image_compare(ctx, &a, &c, &d);
    CHECK(st == VS_ERR_INVALID_ARGUMENT, "size mismatch: status %d", (int)st);
    CHECK(strstr(vs_last_error(ctx), "64x48") && strstr(vs_last_error(ctx), "10x10"),
          "size mismatch message: %s", vs_last_error(ctx));
    vs_image_free(&c);

    /* tiny images (smaller than the SSIM window) work */
    vs_image t1 = make(2, 3, 0), t2 = copy(&t1);
    st = vs_image_compare(ctx, &t1, &t2, &d);
    CHECK(st == VS_OK && d.ssim == 1.0, "tiny: ssim %.17g (%s)", d.ssim, vs_last_error(ctx));
    vs_image_free(&t1);
    vs_image_free(&t2);
    vs_image_free(&a);
    vs_image_free(&b);
}

static void test_failures(vs_context *ctx)
{
    vs_image a = make(8, 8, 1), b = {0, 0, NULL};
    vs_status st = vs_image_write(ctx, "/nonexistent-dir/x.png", &a, 8);
    CHECK(st != VS_OK, "write to a missing folder succeeded");
    CHECK(strstr(vs_last_error(ctx), "x.png") != NULL, "message: %s", vs_last_error(ctx));
    CHECK(access("/nonexistent-dir/x.png", F_OK) != 0, "file exists");
    printf("  unwritable: %s\n", vs_last_error(ctx));

    char path[1200];
    snprintf(path, sizeof path, "%s/x.bmpx", tmp);
    st = vs_image_write(ctx, path, &a, 8);
    CHECK(st == VS_ERR_UNSUPPORTED && strstr(vs_last_error(ctx), "x.bmpx"), "unknown format: %s",
          vs_last_error(ctx));
    CHECK(access(path, F_OK) != 0, "unknown format left a file");
    st = vs_image_write(ctx, path, &a, 12);
    CHECK(st == VS_ERR_INVALID_ARGUMENT, "bits 12 accepted");

    /* a folder where the file should go: the rename fails, no temp file left */
    snprintf(path, sizeof path, "%s/dir.png", tmp);
    mkdir(path, 0755);
    char inner[1300];
    snprintf(inner, sizeof inner, "%s/keep", path);
    FILE *f = fopen(inner, "wb");
    if (f) fclose(f);
    st = vs_image_write(ctx, path, &a, 8);
    CHECK(st != VS_OK && strstr(vs_last_error(ctx), "dir.png"), "write over a folder: %s",
          vs_last_error(ctx));
    CHECK(count_temp_files() == 0, "temporary file left after a failed rename");
    printf("  over a folder: %s\n", vs_last_error(ctx));

    snprintf(path, sizeof path, "%s/missing.png", tmp);
    st = vs_image_read(ctx, path, &b);
    CHECK(st != VS_OK && strstr(vs_last_error(ctx), "missing.png") && !b.rgba, "read missing: %s",
          vs_last_error(ctx));
    snprintf(path, sizeof path, "%s/garbage.png", tmp);
    f = fopen(path, "wb");
    if (f) {
        fputs("this is not a png file at all", f);
        fclose(f);
    }
    st = vs_image_read(ctx, path, &b);
    CHECK(st != VS_OK && strstr(vs_last_error(ctx), "garbage.png") && !b.rgba, "read garbage: %s",
          vs_last_error(ctx));
    printf("  garbage: %s\n", vs_last_error(ctx));
    vs_image bad = {0, 5, NULL};
    CHECK(vs_image_write(ctx, path, &bad, 8) == VS_ERR_INVALID_ARGUMENT, "empty image written");
    vs_image_free(&a);
}

int main(void)
{
    vs_context *ctx;
    if (vs_context_create(&ctx) != VS_OK) return 1;
    if (!tu_make_tmpdir(tmp, sizeof tmp, "test_image")) return 1;
    test_round_trips(ctx);
    test_compare(ctx);
    test_failures(ctx);
    tu_remove_tmpdir(tmp);
    vs_context_release(ctx);
    TEST_DONE();
}
