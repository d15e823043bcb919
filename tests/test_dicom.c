/* DICOM series through the GDCM module.  tests/dicom_write.py (pydicom)
 * writes oblique series whose every voxel holds round(2R + 3A + 5S) of its
 * own world position; the loaded transform must put each voxel where its
 * value says, whatever the file names, order, preamble, compression or
 * rescale.  Hostile folders must fail with a message that says why.  The
 * real CT series is checked against facts from its headers (MANIFEST.md). */
#include "testutil.h"
#include "dicom_adapter.h"

#include <dirent.h>
#include <sys/wait.h>
#include <unistd.h>

static const char *out_dir(void) { return VSPLAT_TEST_BINARY_DIR "/dicom_series"; }

static vs_volume *load(vs_context *ctx, const char *sub, const char *series)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", out_dir(), sub);
    vs_load_options o;
    vs_load_options_init(&o);
    o.series = series;
    vs_volume *v = NULL;
    vs_status st = vs_volume_load(ctx, path, &o, &v);
    CHECK(st == VS_OK && v, "%s: %s", sub, vs_last_error(ctx));
    return st == VS_OK ? v : NULL;
}

/* The load fails, out is NULL, and the message holds `want`. */
static void expect_error(vs_context *ctx, const char *sub, const char *series, const char *want)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", out_dir(), sub);
    vs_load_options o;
    vs_load_options_init(&o);
    o.series = series;
    vs_volume *v = (vs_volume *)1;
    vs_status st = vs_volume_load(ctx, path, &o, &v);
    CHECK(st != VS_OK && v == NULL, "%s loaded, expected an error with '%s'", sub, want);
    CHECK(strstr(vs_last_error(ctx), want) != NULL, "%s: message '%s' lacks '%s'", sub, vs_last_error(ctx), want);
}

static double at(const vs_volume *v, size_t i)
{
    vs_volume *w = (vs_volume *)v;
    switch (vs_volume_type(v)) {
    case VS_U8: return ((uint8_t *)vs_volume_data(w))[i];
    case VS_I16: return ((int16_t *)vs_volume_data(w))[i];
    case VS_U16: return ((uint16_t *)vs_volume_data(w))[i];
    default: return ((float *)vs_volume_data(w))[i];
    }
}

/* Every voxel holds scale * round(2R + 3A + 5S) + offset of the world
 * position the volume's transform gives it. */
static void check_world(const char *what, const vs_volume *v, double scale, double offset)
{
    int d[3];
    double m[12];
    vs_volume_dims(v, d);
    CHECK(d[0] == 16 && d[1] == 12 && d[2] == 7, "%s: dims %dx%dx%d, expected 16x12x7", what, d[0], d[1], d[2]);
    if (d[0] != 16 || d[1] != 12 || d[2] != 7) return;
    CHECK(vs_volume_affine(v, m) == 1, "%s: no orientation", what);
    double sp[3];
    vs_volume_spacing(v, sp);
    CHECK(fabs(sp[0] - 0.6) < 1e-6 && fabs(sp[1] - 0.8) < 1e-6 && fabs(sp[2] - 1.5) < 1e-6,
          "%s: spacing %g %g %g, expected 0.6 0.8 1.5", what, sp[0], sp[1], sp[2]);
    int bad = 0;
    double worst = 0;
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++) {
                double w[3];
                for (int r = 0; r < 3; r++) w[r] = m[4 * r] * i + m[4 * r + 1] * j + m[4 * r + 2] * k + m[4 * r + 3];
                double f = 2 * w[0] + 3 * w[1] + 5 * w[2];
                double got = (at(v, (size_t)i + (size_t)d[0] * (j + (size_t)d[1] * k)) - offset) / scale;
                double e = fabs(got - f);
                if (e > worst) worst = e;
                if (e > 0.5 + 1e-6) bad++;
            }
    CHECK(bad == 0, "%s: %d voxels not where the transform puts them (worst %g)", what, bad, worst);
}

static int same_voxels(const vs_volume *a, const vs_volume *b)
{
    int da[3], db[3];
    vs_volume_dims(a, da);
    vs_volume_dims(b, db);
    if (memcmp(da, db, sizeof da) || vs_volume_type(a) != vs_volume_type(b)) return 0;
    double ma[12], mb[12];
    vs_volume_affine(a, ma);
    vs_volume_affine(b, mb);
    for (int i = 0; i < 12; i++)
        if (fabs(ma[i] - mb[i]) > 1e-9) return 0;
    for (size_t i = 0; i < (size_t)da[0] * da[1] * da[2]; i++)
        if (at(a, i) != at(b, i)) return 0;
    return 1;
}

static void test_written(vs_context *ctx)
{
    vs_volume *ob = load(ctx, "oblique", NULL);
    if (ob) {
        CHECK(vs_volume_type(ob) == VS_I16, "oblique: type %s, expected i16", vs_type_name(vs_volume_type(ob)));
        check_world("oblique", ob, 1, 0);
    }
    const char *same[] = {"renamed", "rle", "jpegls", "with_other_files", "bigendian"};
    for (size_t c = 0; c < sizeof same / sizeof *same; c++) {
        char p[4096];
        snprintf(p, sizeof p, "%s/%s", out_dir(), same[c]);
        struct stat st;
        if (stat(p, &st) != 0) {
            printf("SKIP: %s not written (no gdcmconv)\n", same[c]);
            continue;
        }
        vs_volume *v = load(ctx, same[c], NULL);
        if (v && ob) CHECK(same_voxels(ob, v), "%s: not the same volume as oblique/", same[c]);
        vs_volume_release(v);
    }
    /* one file of the series names its series: the whole volume */
    {
        char first[4096] = "";
        snprintf(first, sizeof first, "%s/renamed/s03.dcm", out_dir());
        vs_volume *v = NULL;
        CHECK(vs_volume_load(ctx, first, NULL, &v) == VS_OK, "one file: %s", vs_last_error(ctx));
        if (v && ob) CHECK(same_voxels(ob, v), "one file of the series: not the whole volume");
        vs_volume_release(v);
    }
    vs_volume *r = load(ctx, "rescale_i16", NULL);
    if (r) {
        CHECK(vs_volume_type(r) == VS_I16, "slope 1 intercept -1024: type %s, expected i16",
              vs_type_name(vs_volume_type(r)));
        check_world("rescale_i16", r, 1, 0);
    }
    vs_volume_release(r);
    r = load(ctx, "rescale_f32", NULL);
    if (r) {
        CHECK(vs_volume_type(r) == VS_F32, "slope 0.25: type %s, expected f32", vs_type_name(vs_volume_type(r)));
        /* stored = value + 1024, read as stored * 0.25 - 10.5 */
        check_world("rescale_f32", r, 0.25, 1024 * 0.25 - 10.5);
    }
    vs_volume_release(r);
    vs_volume *s = load(ctx, "single", NULL);
    if (s) {
        int d[3];
        double sp[3];
        vs_volume_dims(s, d);
        vs_volume_spacing(s, sp);
        CHECK(d[2] == 1 && fabs(sp[2] - 1.5) < 1e-9, "single slice: %d slices, spacing %g (SliceThickness 1.5)",
              d[2], sp[2]);
    }
    vs_volume_release(s);

    /* several series: listed, and picked by number or UID */
    expect_error(ctx, "two_series", NULL, "2 DICOM series in the folder");
    expect_error(ctx, "two_series", NULL, "1.2.3.4.1 \"first\" (CT, 3 slices)");
    expect_error(ctx, "two_series", "7", "no series 7 among the 2");
    vs_volume *a = load(ctx, "two_series", "1.2.3.4.1");
    if (a) {
        int d[3];
        vs_volume_dims(a, d);
        CHECK(d[2] == 3, "--series 1.2.3.4.1: %d slices, expected 3", d[2]);
    }
    vs_volume_release(a);
    for (int n = 1; n <= 2; n++) {
        char num[4];
        snprintf(num, sizeof num, "%d", n);
        a = load(ctx, "two_series", num);
        if (a) {
            int d[3];
            vs_volume_dims(a, d);
            CHECK(d[2] == 3 || d[2] == 4, "--series %d: %d slices", n, d[2]);
        }
        vs_volume_release(a);
    }
    /* the CLI: the listing exits 1, --series picks */
    const char *cli = getenv("VSPLAT_CLI");
    if (cli) {
        char cmd[8192];
        snprintf(cmd, sizeof cmd, "%s info %s/two_series >/dev/null 2>&1", cli, out_dir());
        int rc = system(cmd);
        CHECK(WIFEXITED(rc) && WEXITSTATUS(rc) == 1, "vsplat info of two series: exit %d, expected 1", rc);
        snprintf(cmd, sizeof cmd, "%s info %s/two_series --series 2 | grep -q '^dims: 16 12 [34]$'", cli, out_dir());
        CHECK(system(cmd) == 0, "vsplat info --series 2 did not load a series of the folder");
    }
    expect_error(ctx, "gap", NULL, "uneven slice spacing: 1.5 mm between most slices but 3 mm");
    expect_error(ctx, "duplicate", NULL, "lie at the same position");
    expect_error(ctx, "no_position", NULL, "no ImagePositionPatient");
    expect_error(ctx, "truncated_pixels", NULL, "t2: malformed DICOM: element (7fe0,0010) claims");
    expect_error(ctx, "truncated_header", NULL, "t5: malformed DICOM: element (0020,000e) claims");
    vs_volume_release(ob);
}

/* The real series: 512x512x10, 0.69 x 0.69 x 5 mm, z from -4.5 to 40.5,
 * values -1500..1439 (pydicom's pixel_array of the ten files agrees). */
static void test_real(vs_context *ctx)
{
    const char *data = tu_data_dir();
    char path[4200];
    struct stat st;
    if (data) snprintf(path, sizeof path, "%s/egsnrc_ct_bone_phantom_dicom", data);
    if (!data || stat(path, &st) != 0) {
        printf("SKIP: real DICOM series (egsnrc_ct_bone_phantom_dicom) not in $VSPLAT_DATA or ../shared/data\n");
        return;
    }
    vs_volume *v = NULL;
    CHECK(vs_volume_load(ctx, path, NULL, &v) == VS_OK, "%s", vs_last_error(ctx));
    if (!v) return;
    int d[3];
    double sp[3], m[12], lo, hi;
    vs_volume_dims(v, d);
    vs_volume_spacing(v, sp);
    vs_volume_range(v, &lo, &hi);
    CHECK(d[0] == 512 && d[1] == 512 && d[2] == 10, "dims %dx%dx%d", d[0], d[1], d[2]);
    CHECK(vs_volume_type(v) == VS_I16, "type %s", vs_type_name(vs_volume_type(v)));
    CHECK(fabs(sp[0] - 0.69) < 1e-6 && fabs(sp[2] - 5.0) < 1e-6, "spacing %g %g %g", sp[0], sp[1], sp[2]);
    CHECK(lo == -1500 && hi == 1439, "range %g..%g", lo, hi);
    CHECK(vs_volume_affine(v, m) == 1, "no orientation");
    /* sorted by position: slice 0 is the lowest (z = -4.5), +k goes up;
     * LPS x, y = -176.295 become RAS 176.295 */
    CHECK(fabs(m[11] + 4.5) < 1e-4 && fabs(m[10] - 5.0) < 1e-9, "slice 0 at z %g, step %g", m[11], m[10]);
    CHECK(fabs(m[3] - 176.294998) < 1e-4 && fabs(m[0] + 0.69) < 1e-9, "x origin %g, x step %g", m[3], m[0]);
    vs_volume_release(v);
}

/* tests/fuzz/regressions/dicom/: inputs of fuzz_dicom.c (first byte: how
 * many equal parts, 1 to 3, the rest is cut into, one file each) that once
 * ended the process or used gigabytes; each must now load or fail with a
 * message. */
static void test_regressions(vs_context *ctx, const char *src)
{
    char rdir[4096], dir[4096], p[8300];
    snprintf(rdir, sizeof rdir, "%s/tests/fuzz/regressions/dicom", src);
    snprintf(dir, sizeof dir, "%s/dicom_regress", VSPLAT_TEST_BINARY_DIR);
    mkdir(dir, 0755);
    DIR *d = opendir(rdir);
    if (!d) return;
    struct dirent *e;
    int n = 0;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        snprintf(p, sizeof p, "%s/%s", rdir, e->d_name);
        FILE *f = fopen(p, "rb");
        if (!f) continue;
        static unsigned char buf[1 << 20];
        size_t size = fread(buf, 1, sizeof buf, f);
        fclose(f);
        if (size < 2) continue;
        for (int i = 0; i < 3; i++) {
            snprintf(p, sizeof p, "%s/f%d", dir, i);
            unlink(p);
        }
        int files = buf[0] % 3 + 1;
        size_t part = (size - 1) / (size_t)files;
        for (int i = 0; i < files; i++) {
            snprintf(p, sizeof p, "%s/f%d", dir, i);
            FILE *o = fopen(p, "wb");
            if (!o) continue;
            fwrite(buf + 1 + part * (size_t)i, 1, i == files - 1 ? size - 1 - part * (size_t)i : part, o);
            fclose(o);
        }
        vs_volume *v = (vs_volume *)1;
        vs_status st = vs_volume_load(ctx, dir, NULL, &v);
        CHECK(st == VS_OK || (v == NULL && *vs_last_error(ctx)), "regression %s: status %d, no message", e->d_name,
              (int)st);
        /* oom-*: an element claiming gigabytes, or a stream GDCM rereads
         * with VRs guessed, made GDCM's child allocate them; refused by the
         * element walk before GDCM reads the file */
        if (!strncmp(e->d_name, "oom-", 4))
            CHECK(st != VS_OK && strstr(vs_last_error(ctx), "malformed DICOM"),
                  "regression %s: not refused by the element walk: %s", e->d_name, vs_last_error(ctx));
        if (st == VS_OK) vs_volume_release(v);
        n++;
    }
    closedir(d);
    printf("%d fuzz regression inputs handled\n", n);
}

int main(void)
{
    const char *src = getenv("VSPLAT_SOURCE_DIR");
    if (!src) src = ".";
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "/usr/bin/python3 %s/tests/dicom_write.py %s", src, out_dir());
    int rc = access("/usr/bin/python3", X_OK) == 0 ? system(cmd) : -1;
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return 2;
    /* a build without GDCM has no module: DICOM input says so, and there
     * is nothing else here to test */
    if (!vs_dicom(ctx)) {
#ifdef VSPLAT_HAVE_DICOM
        CHECK(0, "the DICOM module was built but does not load: %s", vs_last_error(ctx));
        vs_context_release(ctx);
        TEST_DONE();
#endif
        printf("SKIP: %s\n", vs_last_error(ctx));
        vs_context_release(ctx);
        return 0;
    }
    if (rc != 0)
        printf("SKIP: written series (needs Debian's python3-pydicom; %s exited %d)\n", cmd, rc);
    else
        test_written(ctx);
    test_real(ctx);
    test_regressions(ctx, src);
    vs_context_release(ctx);
    /* without the module: an error that names it, not a crash */
    if (rc == 0 && vs_context_create(&ctx) == VS_OK) {
        setenv("VSPLAT_DICOM_MODULE", "/nonexistent/vsplat-dicom.so", 1);
        expect_error(ctx, "oblique", NULL, "DICOM: cannot load the GDCM module VSPLAT_DICOM_MODULE=");
        unsetenv("VSPLAT_DICOM_MODULE");
        vs_context_release(ctx);
    }
    TEST_DONE();
}
