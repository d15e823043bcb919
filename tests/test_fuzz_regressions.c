/* Fuzzer reproducers and seeds in the normal test suite: every file under
 * tests/fuzz/regressions/<target>/ and tests/fuzz/seeds/<target>/ is loaded
 * exactly as its libFuzzer harness (tests/fuzz/fuzz_<target>.c) loads it.
 * Any status is fine; the test fails on a crash (the process dies), a
 * loaded volume with impossible dims or range, an error without a message,
 * or a load that takes more than 5 s.  Seeds must load. */
#include "internal.h"
#include "testutil.h"
#include "fuzz/tf_case.h"

#include <dirent.h>
#include <time.h>
#include <unistd.h>

static vs_context *ctx;
static vs_volume *tf_vols[4];
static char tmp[1024];

/* Returns 1 if the input loaded. */
static int run_one(const char *target, const unsigned char *d, size_t n, const char *what)
{
    const char *sfx = NULL;
    vs_load_options o, *opt = NULL;
    const unsigned char *body = d;
    size_t bn = n;
    if (!strcmp(target, "nifti")) sfx = n && d[0] == 0x1f ? ".nii.gz" : ".nii";
    else if (!strcmp(target, "nrrd")) sfx = ".nrrd";
    else if (!strcmp(target, "den")) sfx = ".den";
    else if (!strcmp(target, "tar")) sfx = ".tar";
    else if (!strcmp(target, "stack")) sfx = n >= 4 && d[0] == 0x89 && d[1] == 'P' ? ".png" : ".tif";
    else if (!strcmp(target, "raw")) {
        sfx = ".raw";
        vs_load_options_init(&o);
        o.raw = 1;
        o.dims[0] = o.dims[1] = o.dims[2] = 8;
        o.type = VS_U16;
        o.endian = VS_ENDIAN_BIG;
        opt = &o;
    } else if (!strcmp(target, "tf")) {
        if (n < 1) return 0;
        sfx = tf_case_suffix(d[0]);
        body = d + 1;
        bn = n - 1;
    } else {
        return 0;
    }
    char path[1200];
    snprintf(path, sizeof path, "%s/input%s", tmp, sfx);
    FILE *f = fopen(path, "wb");
    if (!f || (bn && fwrite(body, 1, bn, f) != bn)) {
        CHECK(0, "cannot write %s", path);
        if (f) fclose(f);
        return 0;
    }
    fclose(f);
    double t0 = tu_now_s();
    int ok = 0;
    if (!strcmp(target, "tf")) {
        vs_tf_point *pts = NULL;
        int cnt = 0, with_vol = 1;
        const vs_volume *tf_vol = tf_case_volume(ctx, d[0], tf_vols, &with_vol);
        vs_status st = with_vol ? vs_tf_load_for_volume(ctx, path, tf_vol, &pts, &cnt) : vs_tf_load(ctx, path, &pts, &cnt);
        ok = st == VS_OK;
        if (ok) {
            vs_settings s;
            vs_settings_init(&s);
            s.width = s.height = 8;
            s.tf = pts;
            s.tf_count = cnt;
            for (int p = 0; p <= VS_PIPELINE_RAYCAST; p++) {
                s.pipeline = (vs_pipeline)p;
                vs_image img;
                if (vs_render(ctx, tf_vol, &s, &img, NULL) == VS_OK) {
                    for (int i = 0; i < 8 * 8 * 4; i++)
                        CHECK(isfinite(img.rgba[i]) && (i % 4 != 3 || (img.rgba[i] >= 0 && img.rgba[i] <= 1)),
                              "%s: pixel %d is %g with its transfer function", what, i, img.rgba[i]);
                    vs_image_free(&img);
                }
            }
            vs_tf_free(pts);
        } else {
            CHECK(pts == NULL && *vs_last_error(ctx), "%s: failed without a message or left points", what);
        }
    } else {
        vs_volume *v = (vs_volume *)1;
        vs_status st = vs_volume_load(ctx, path, opt, &v);
        ok = st == VS_OK;
        if (ok) {
            int dd[3];
            double lo, hi;
            vs_volume_dims(v, dd);
            vs_volume_range(v, &lo, &hi);
            CHECK(dd[0] >= 1 && dd[1] >= 1 && dd[2] >= 1 && lo <= hi, "%s: dims %d,%d,%d range %g..%g", what, dd[0],
                  dd[1], dd[2], lo, hi);
            vs_volume_release(v);
        } else {
            CHECK(v == NULL && *vs_last_error(ctx), "%s: failed without a message or left a volume", what);
        }
    }
    /* a hang guard, not a speed test: the first image of a run also starts
     * the OpenImageIO module, seen taking 8.5 s on a loaded 2-core machine */
    CHECK(tu_now_s() - t0 < 30.0 * tu_slack(), "%s: took %.1f s", what, tu_now_s() - t0);
    unlink(path);
    return ok;
}

static void run_dir(const char *kind, const char *target, int must_load)
{
    char dir[1200];
    const char *src = getenv("VSPLAT_SOURCE_DIR");
    snprintf(dir, sizeof dir, "%s/tests/fuzz/%s/%s", src ? src : ".", kind, target);
    DIR *dd = opendir(dir);
    if (!dd) return;
    struct dirent *e;
    int files = 0, loaded = 0;
    while ((e = readdir(dd))) {
        if (e->d_name[0] == '.') continue;
        char p[2400];
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        size_t n;
        unsigned char *b = tu_read_file(p, &n);
        if (!b) continue;
        char what[300];
        snprintf(what, sizeof what, "%s/%s/%s", kind, target, e->d_name);
        int ok = run_one(target, b, n, what);
        if (must_load) CHECK(ok, "%s: seed does not load: %s", what, vs_last_error(ctx));
        files++;
        loaded += ok;
        free(b);
    }
    closedir(dd);
    printf("  %-12s %-6s %3d files, %3d load\n", kind, target, files, loaded);
}

int main(void)
{
    if (vs_context_create(&ctx) != VS_OK) return 2;
    if (!tu_make_tmpdir(tmp, sizeof tmp, "fuzzreg")) return 2;
    static const char *const targets[] = {"nifti", "nrrd", "den", "raw", "stack", "tar", "tf"};
    for (int i = 0; i < 7; i++) {
        run_dir("seeds", targets[i], 1);
        run_dir("regressions", targets[i], 0);
    }
    rmdir(tmp);
    for (int i = 0; i < 4; i++) vs_volume_release(tf_vols[i]);
    vs_context_release(ctx);
    TEST_DONE();
}
