/* Transfer-function files (src/io/tf_file.c): ParaView JSON presets, ImageVis3D
 * .1dt, vsplat .vtf; the shipped presets; malformed files of every kind give
 * a clear error naming the file, never a crash or an absurd allocation. */
#include "testutil.h"
#include "vsplat.h"

#include <math.h>
#include <stdint.h>
#include <time.h>
#include <unistd.h>

static vs_context *ctx;
static vs_volume *vol; /* u8, values 0..100 */
static char dir[1024];

static const char *put(const char *name, const char *text)
{
    static char path[2048];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f) {
        fprintf(stderr, "cannot write %s\n", path);
        exit(1);
    }
    fputs(text, f);
    fclose(f);
    return path;
}

/* Piecewise-linear evaluation, as classify.c does (clamped at the ends). */
static void eval(const vs_tf_point *p, int n, double v, double out[4])
{
    const vs_tf_point *a = &p[0], *b = &p[0];
    if (v >= p[n - 1].value) a = b = &p[n - 1];
    else if (v > p[0].value)
        for (int i = 1; i < n; i++)
            if (v <= p[i].value) {
                a = &p[i - 1];
                b = &p[i];
                break;
            }
    double t = b->value > a->value ? (v - a->value) / (b->value - a->value) : 0.0;
    out[0] = a->r + t * (b->r - a->r);
    out[1] = a->g + t * (b->g - a->g);
    out[2] = a->b + t * (b->b - a->b);
    out[3] = a->a + t * (b->a - a->a);
}

/* Load and expect success; returns count (points in *pts, caller frees). */
static int load_ok(const char *name, const char *text, vs_tf_point **pts)
{
    const char *path = put(name, text);
    int n = -1;
    vs_status st = vs_tf_load_for_volume(ctx, path, vol, pts, &n);
    CHECK(st == VS_OK, "%s: %s", name, vs_last_error(ctx));
    if (st != VS_OK) return 0;
    /* every result must pass the renderer's own validation */
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 16;
    s.threads = 1;
    s.tf = *pts;
    s.tf_count = n;
    vs_image img = {0, 0, NULL};
    vs_stats stats;
    st = vs_render(ctx, vol, &s, &img, &stats);
    CHECK(st == VS_OK, "%s: render with the loaded points: %s", name, vs_last_error(ctx));
    vs_image_free(&img);
    return n;
}

/* Load and expect failure with status want and a message naming the file
 * (and containing `part`, if given). */
static void load_bad(const char *name, const char *text, vs_status want, const char *part)
{
    const char *path = put(name, text);
    vs_tf_point *pts = (vs_tf_point *)(uintptr_t)1;
    int n = -1;
    vs_status st = vs_tf_load_for_volume(ctx, path, vol, &pts, &n);
    const char *msg = vs_last_error(ctx);
    CHECK(st == want, "%s: status %s, wanted %s (%s)", name, vs_status_string(st), vs_status_string(want), msg);
    CHECK(pts == NULL && n == 0, "%s: outputs not cleared on failure", name);
    CHECK(strstr(msg, name) != NULL, "%s: message does not name the file: %s", name, msg);
    if (part) CHECK(strstr(msg, part) != NULL, "%s: message lacks '%s': %s", name, part, msg);
    printf("  %-22s -> %s\n", name, msg + (strstr(msg, name) ? strstr(msg, name) - msg : 0));
}

static int near(double a, double b, double tol)
{
    return fabs(a - b) <= tol;
}

static void test_json(void)
{
    vs_tf_point *p = NULL;
    double c[4];
    /* one object, linear: simplified to its two points */
    int n = load_ok("lin.json",
                    "{\"Name\": \"lin\", \"ColorSpace\": \"Diverging\",\n"
                    " \"RGBPoints\": [0, 0, 0, 0,  100, 1, 0.5, 1],\n"
                    " \"Points\": [0, 0, 0.5, 0,  100, 1, 0.5, 0]}\n",
                    &p);
    CHECK(n == 2, "lin.json: %d points, expected 2", n);
    if (n == 2)
        CHECK(p[0].value == 0 && p[1].value == 100 && p[1].r == 1.0f && p[1].g == 0.5f && p[1].a == 1.0f &&
                  p[0].a == 0.0f,
              "lin.json: wrong points");
    vs_tf_free(p);

    /* an array of presets: the first is used; different x sets merge */
    n = load_ok("two.json",
                "[{\"Name\": \"first\", \"RGBPoints\": [0, 1, 0, 0, 40, 0, 1, 0, 100, 0, 0, 1],\n"
                "  \"Points\": [20, 0, 0.5, 0, 80, 0.5, 0.5, 0]},\n"
                " {\"Name\": \"second\", \"RGBPoints\": [0, 1, 1, 1, 1, 1, 1, 1]}]",
                &p);
    if (n > 0) {
        eval(p, n, 40, c);
        CHECK(near(c[0], 0, 1e-6) && near(c[1], 1, 1e-6) && near(c[3], 0.5 * 20 / 60, 1e-6),
              "two.json at 40: %g %g %g %g", c[0], c[1], c[2], c[3]);
        eval(p, n, 10, c);
        CHECK(near(c[0], 0.75, 1e-6) && near(c[3], 0, 1e-9), "two.json at 10: %g a %g", c[0], c[3]);
        eval(p, n, 90, c);
        CHECK(near(c[1], 1.0 / 6.0, 1e-6) && near(c[2], 5.0 / 6.0, 1e-6) && near(c[3], 0.5, 1e-6),
              "two.json at 90: %g %g a %g", c[1], c[2], c[3]);
    }
    vs_tf_free(p);

    /* no "Points": opacity ramps 0 -> 1 over the RGB points */
    n = load_ok("ramp.json", "{\"RGBPoints\": [20, 1, 1, 1, 60, 1, 1, 1]}", &p);
    if (n > 0) {
        eval(p, n, 30, c);
        CHECK(near(c[3], 0.25, 1e-6), "ramp.json at 30: a %g", c[3]);
    }
    vs_tf_free(p);

    /* sharpness 1: a step at the midpoint (two points at one value) */
    n = load_ok("step.json", "{\"RGBPoints\": [0, 1, 1, 1, 100, 1, 1, 1], \"Points\": [0, 0, 0.3, 1, 100, 1, 0.5, 0]}",
                &p);
    int steps = 0;
    for (int i = 1; i < n; i++)
        if (p[i].value == p[i - 1].value && near(p[i].value, 30, 1e-9) && p[i - 1].a == 0.0f && p[i].a == 1.0f)
            steps++;
    CHECK(steps == 1, "step.json: no step at 30 (%d points)", n);
    vs_tf_free(p);

    /* midpoint 0.25, sharpness 0: half opacity a quarter of the way */
    n = load_ok("mid.json", "{\"RGBPoints\": [0, 1, 1, 1, 100, 1, 1, 1], \"Points\": [0, 0, 0.25, 0, 100, 1, 0.5, 0]}",
                &p);
    if (n > 0) {
        eval(p, n, 25, c);
        CHECK(near(c[3], 0.5, 0.02), "mid.json at 25: a %g", c[3]);
        eval(p, n, 62.5, c);
        CHECK(near(c[3], 0.75, 0.02), "mid.json at 62.5: a %g", c[3]);
    }
    vs_tf_free(p);

    /* sharpness 0.5: a curve, sampled; stays within [0,1] and is monotone */
    n = load_ok("curve.json",
                "{\"RGBPoints\": [0, 1, 1, 1, 100, 1, 1, 1], \"Points\": [0, 0, 0.5, 0.5, 100, 1, 0.5, 0]}", &p);
    CHECK(n > 10, "curve.json: %d points, expected a sampled curve", n);
    for (int i = 1; i < n; i++) CHECK(p[i].a >= p[i - 1].a, "curve.json: opacity not monotone at %d", i);
    vs_tf_free(p);

    /* equal x: the later point wins (VTK) */
    n = load_ok("dup.json", "{\"RGBPoints\": [0, 1, 0, 0, 0, 0, 1, 0, 100, 0, 1, 0]}", &p);
    if (n > 0) CHECK(p[0].r == 0.0f && p[0].g == 1.0f, "dup.json: first point %g %g", p[0].r, p[0].g);
    vs_tf_free(p);

    puts("malformed JSON:");
    load_bad("trunc.json", "[{\"RGBPoints\": [0, 0, 0", VS_ERR_FORMAT, "line 1");
    load_bad("trunc2.json", "{\"RGBPoints\": [0, 0, 0, 0],\n \"Points\": [0, 1, 0.5,", VS_ERR_FORMAT, "line");
    load_bad("garbage.json", "{\"RGBPoints\": [0, 0, 0, 0]} x", VS_ERR_FORMAT, "column");
    load_bad("badtok.json", "{\"RGBPoints\": [0, 0, 0, 0,\n  1, 0, 0, oops]}", VS_ERR_FORMAT, "line 2");
    load_bad("nan.json", "{\"RGBPoints\": [NaN, 0, 0, 0]}", VS_ERR_FORMAT, NULL);
    load_bad("inf.json", "{\"RGBPoints\": [1e999, 0, 0, 0]}", VS_ERR_FORMAT, "finite");
    load_bad("str.json", "{\"RGBPoints\": \"0 0 0 0\"}", VS_ERR_FORMAT, "array");
    load_bad("strelem.json", "{\"RGBPoints\": [0, \"1\", 0, 0]}", VS_ERR_FORMAT, "[1] is not a number");
    load_bad("obj.json", "{\"RGBPoints\": [0, 0, 0, 0], \"Points\": {\"x\": 1}}", VS_ERR_FORMAT, "Points");
    load_bad("name.json", "{\"Name\": 3, \"RGBPoints\": [0, 0, 0, 0]}", VS_ERR_FORMAT, "Name");
    load_bad("range.json", "{\"RGBPoints\": [0, 0, 1.5, 0]}", VS_ERR_FORMAT, "outside [0,1]");
    load_bad("negop.json", "{\"RGBPoints\": [0, 0, 0, 0], \"Points\": [0, -0.1, 0.5, 0]}", VS_ERR_FORMAT, "opacity");
    load_bad("mid.json", "{\"RGBPoints\": [0, 0, 0, 0], \"Points\": [0, 0, 1.5, 0]}", VS_ERR_FORMAT, "midpoint");
    load_bad("order.json", "{\"RGBPoints\": [0, 0, 0, 0, 50, 1, 1, 1, 40, 1, 1, 1]}", VS_ERR_FORMAT, "decrease");
    load_bad("order2.json", "{\"RGBPoints\": [0, 0, 0, 0], \"Points\": [5, 0, 0.5, 0, 1, 1, 0.5, 0]}", VS_ERR_FORMAT,
             "decrease");
    load_bad("stride.json", "{\"RGBPoints\": [0, 0, 0, 0, 1, 1]}", VS_ERR_FORMAT, "multiple of 4");
    load_bad("emptyarr.json", "{\"RGBPoints\": []}", VS_ERR_FORMAT, "empty");
    load_bad("emptypts.json", "{\"RGBPoints\": [0, 0, 0, 0], \"Points\": []}", VS_ERR_FORMAT, "empty");
    load_bad("emptytop.json", "[]", VS_ERR_FORMAT, "empty");
    load_bad("emptyobj.json", "{}", VS_ERR_FORMAT, "RGBPoints");
    load_bad("indexed.json", "{\"IndexedColors\": [1, 0, 0]}", VS_ERR_UNSUPPORTED, "IndexedColors");
    load_bad("number.json", "42", VS_ERR_FORMAT, NULL);
    load_bad("whitespace.json", "  \n ", VS_ERR_FORMAT, NULL);
    load_bad("comment.json", "// preset\n{\"RGBPoints\": [0, 0, 0, 0]}", VS_ERR_FORMAT, "line 1");
    {
        /* deep nesting: rejected by the parser's limit, not a stack overflow */
        size_t depth = 100000;
        char *deep = malloc(2 * depth + 1);
        memset(deep, '[', depth);
        memset(deep + depth, ']', depth);
        deep[2 * depth] = '\0';
        load_bad("deep.json", deep, VS_ERR_FORMAT, NULL);
        free(deep);
    }
    {
        /* a NUL byte inside the file */
        char path[2048];
        snprintf(path, sizeof path, "%s/nul.json", dir);
        FILE *f = fopen(path, "wb");
        fwrite("{\"RGBPoints\": [0, 0, 0, 0]}\0 trailing", 1, 37, f);
        fclose(f);
        vs_tf_point *q = NULL;
        int m = 0;
        CHECK(vs_tf_load(ctx, path, &q, &m) == VS_ERR_FORMAT && strstr(vs_last_error(ctx), "NUL"),
              "nul.json: %s", vs_last_error(ctx));
    }
}

static void test_1dt(void)
{
    vs_tf_point *p = NULL;
    int n = load_ok("three.1dt", "3\n0 0 0 0\n0.5 0.5 0.5 0.25 \n1 1 1 1\n", &p);
    /* collinear: simplified to the ends, spanning the volume's range 0..100 */
    CHECK(n >= 2 && p[0].value == 0.0 && p[n - 1].value == 100.0, "three.1dt: spans %g..%g",
          n ? p[0].value : -1, n ? p[n - 1].value : -1);
    double c[4];
    if (n) {
        eval(p, n, 50, c);
        CHECK(near(c[0], 0.5, 1e-6) && near(c[3], 0.25, 1e-6), "three.1dt at 50: %g %g", c[0], c[3]);
    }
    vs_tf_free(p);
    n = load_ok("bent.1dt", "3 0 0 0 0  1 0 0 1  0 0 1 0.5", &p); /* any white space */
    CHECK(n == 3 && p[1].value == 50.0 && p[1].r == 1.0f && p[2].b == 1.0f, "bent.1dt: %d points", n);
    vs_tf_free(p);
    n = load_ok("one.1dt", "1\n0.2 0.4 0.6 0.8\n", &p);
    CHECK(n == 1 && p[0].value == 0.0 && p[0].a == 0.8f, "one.1dt");
    vs_tf_free(p);

    /* without a volume .1dt cannot be placed */
    const char *path = put("novol.1dt", "2\n0 0 0 0\n1 1 1 1\n");
    p = NULL;
    n = 0;
    CHECK(vs_tf_load(ctx, path, &p, &n) == VS_ERR_INVALID_ARGUMENT && strstr(vs_last_error(ctx), "novol.1dt") &&
              strstr(vs_last_error(ctx), "vs_tf_load_for_volume"),
          "novol.1dt: %s", vs_last_error(ctx));

    puts("malformed .1dt:");
    load_bad("short.1dt", "5\n0 0 0 0\n1 1 1 1\n0.5 0.5 0.5 0.5\n", VS_ERR_FORMAT, "promises 5");
    load_bad("long.1dt", "2\n0 0 0 0\n1 1 1 1\n0.5 0.5 0.5 0.5\n", VS_ERR_FORMAT, "line 4");
    load_bad("partial.1dt", "2\n0 0 0 0\n1 1 1\n", VS_ERR_FORMAT, "entry 2");
    clock_t t0 = clock();
    load_bad("huge.1dt", "1e12\n0 0 0 0\n", VS_ERR_TOO_LARGE, "limit");
    load_bad("huge2.1dt", "1000000000000\n0 0 0 0\n", VS_ERR_TOO_LARGE, "limit");
    load_bad("huge3.1dt", "65537\n0 0 0 0\n", VS_ERR_TOO_LARGE, "limit");
    CHECK((double)(clock() - t0) / CLOCKS_PER_SEC < 0.5 * tu_slack(), "huge counts took %g s",
          (double)(clock() - t0) / CLOCKS_PER_SEC);
    load_bad("zero.1dt", "0\n", VS_ERR_FORMAT, "at least one");
    load_bad("neg.1dt", "-3\n", VS_ERR_FORMAT, "at least one");
    load_bad("frac.1dt", "2.5\n0 0 0 0\n", VS_ERR_FORMAT, "entry count");
    load_bad("word.1dt", "two\n0 0 0 0\n", VS_ERR_FORMAT, NULL); /* sniffed: not a count */
    load_bad("nan.1dt", "2\n0 0 0 0\nnan 1 1 1\n", VS_ERR_FORMAT, "line 3");
    load_bad("inf.1dt", "1\ninf 1 1 1\n", VS_ERR_FORMAT, "finite");
    load_bad("range.1dt", "2\n0 0 0 0\n1 1 1.2 1\n", VS_ERR_FORMAT, "outside [0,1]");
    load_bad("negalpha.1dt", "1\n0 0 0 -0.5\n", VS_ERR_FORMAT, "opacity");
    load_bad("empty.1dt", "", VS_ERR_FORMAT, "empty");
}

static void test_vtf(void)
{
    vs_tf_point *p = NULL;
    double c[4];
    int n = load_ok("two.vtf",
                    "# skin and bone\n"
                    "iso 40 60  1 0.8 0.6 0.1 5   # semi-transparent\n"
                    "\n"
                    "iso 80 inf 1 1 1 1 2\n",
                    &p);
    CHECK(n == 6, "two.vtf: %d points, expected 6", n);
    if (n == 6) {
        const double v[6] = {35, 45, 55, 65, 78, 82};
        const float a[6] = {0, 0.1f, 0.1f, 0, 0, 1};
        for (int i = 0; i < 6; i++)
            CHECK(p[i].value == v[i] && p[i].a == a[i], "two.vtf point %d: %g %g", i, p[i].value, p[i].a);
        eval(p, n, 50, c);
        CHECK(near(c[1], 0.8, 1e-6) && near(c[3], 0.1, 1e-6), "two.vtf at 50");
        eval(p, n, 1000, c);
        CHECK(near(c[3], 1, 1e-6), "two.vtf: open range not opaque at 1000");
    }
    vs_tf_free(p);
    /* any order; narrow range -> triangle; ramp 0 -> step */
    n = load_ok("tri.vtf", "iso 70 70 0 0 1 1 0\niso 10 14 1 0 0 0.8 4\n", &p);
    CHECK(n == 7, "tri.vtf: %d points, expected 7", n);
    if (n == 7) {
        CHECK(p[0].value == 6 && p[1].value == 12 && near(p[1].a, 0.8 * 12 / 16.0, 1e-6) && p[2].value == 18,
              "tri.vtf: triangle %g %g(%g) %g", p[0].value, p[1].value, p[1].a, p[2].value);
        CHECK(p[3].value == 70 && p[4].value == 70 && p[3].a == 0 && p[4].a == 1, "tri.vtf: step");
    }
    vs_tf_free(p);
    n = load_ok("points.vtf", "point 0 0 0 0 0\npoint 50 1 0 0 0.5\npoint 50 0 1 0 0.5\npoint 100 0 0 1 1\n", &p);
    CHECK(n == 4 && p[1].value == 50 && p[2].g == 1.0f, "points.vtf: %d points", n);
    vs_tf_free(p);

    puts("malformed .vtf:");
    load_bad("overlap.vtf", "iso 10 20 1 1 1 1 2\niso 21 30 1 1 1 1 2\n", VS_ERR_FORMAT, "overlaps");
    load_bad("after_open.vtf", "iso 10 inf 1 1 1 1 2\niso 100 200 1 1 1 1 2\n", VS_ERR_FORMAT, "overlaps");
    load_bad("unknown.vtf", "iso 10 20 1 1 1 1 2\nsurface 1 2\n", VS_ERR_FORMAT, "line 2");
    load_bad("fields.vtf", "iso 10 20 1 1 1 1\n", VS_ERR_FORMAT, "line 1");
    load_bad("fields2.vtf", "iso 10 20 1 1 1 1 2 3 4 5 6\n", VS_ERR_FORMAT, "line 1");
    load_bad("mixed.vtf", "point 0 0 0 0 0\niso 10 20 1 1 1 1 2\n", VS_ERR_FORMAT, "mixed");
    load_bad("order.vtf", "point 10 0 0 0 0\npoint 5 1 1 1 1\n", VS_ERR_FORMAT, "line 2");
    load_bad("emptyrange.vtf", "iso 20 10 1 1 1 1 2\n", VS_ERR_FORMAT, "empty");
    load_bad("negramp.vtf", "iso 10 20 1 1 1 1 -2\n", VS_ERR_FORMAT, "ramp");
    load_bad("nan.vtf", "iso nan 20 1 1 1 1 2\n", VS_ERR_FORMAT, "not a finite number");
    load_bad("infl.vtf", "iso inf inf 1 1 1 1 2\n", VS_ERR_FORMAT, "not a finite number");
    load_bad("color.vtf", "iso 10 20 1 2 1 1 2\n", VS_ERR_FORMAT, "outside [0,1]");
    load_bad("alpha.vtf", "iso 10 20 1 1 1 1.5 2\n", VS_ERR_FORMAT, "opacity");
    load_bad("comments.vtf", "# nothing here\n\n", VS_ERR_FORMAT, "no 'iso'");
    load_bad("what.txt", "hello\n", VS_ERR_FORMAT, "unknown transfer-function format");
    {
        vs_tf_point *q = NULL;
        int m = 0;
        char path[2048];
        snprintf(path, sizeof path, "%s/does-not-exist.vtf", dir);
        CHECK(vs_tf_load(ctx, path, &q, &m) == VS_ERR_IO && strstr(vs_last_error(ctx), "does-not-exist.vtf"),
              "missing file: %s", vs_last_error(ctx));
        CHECK(vs_tf_load(ctx, NULL, &q, &m) == VS_ERR_INVALID_ARGUMENT, "NULL path");
        CHECK(vs_tf_load(ctx, dir, &q, &m) != VS_OK, "a folder: %s", vs_last_error(ctx));
    }
}

static void test_presets(void)
{
    const char *src = getenv("VSPLAT_SOURCE_DIR");
    if (!src) src = ".";
    const char *names[] = {"colin27-skin-brain.vtf", "ct-head-bone-soft.json", "engine.1dt"};
    for (int i = 0; i < 3; i++) {
        char path[2048];
        snprintf(path, sizeof path, "%s/tools/tf/%s", src, names[i]);
        vs_tf_point *p = NULL;
        int n = 0;
        vs_status st = vs_tf_load_for_volume(ctx, path, vol, &p, &n);
        CHECK(st == VS_OK && n >= 2, "preset %s: %s", names[i], vs_last_error(ctx));
        int translucent = 0, opaque = 0;
        for (int k = 0; k < n; k++) {
            if (p[k].a > 0.0f && p[k].a < 0.3f) translucent = 1;
            if (p[k].a >= 0.5f) opaque = 1;
        }
        CHECK(translucent && (opaque || i == 0), "preset %s: expected a semi-transparent material", names[i]);
        printf("preset %s: %d points\n", names[i], n);
        vs_tf_free(p);
    }
}

int main(void)
{
    if (!tu_make_tmpdir(dir, sizeof dir, "tf")) return 1;
    if (vs_context_create(&ctx) != VS_OK) return 1;
    int dims[3] = {8, 8, 8};
    double sp[3] = {1, 1, 1};
    if (vs_volume_create(ctx, VS_U8, dims, sp, &vol) != VS_OK) return 1;
    uint8_t *d = vs_volume_data(vol);
    for (int z = 0; z < 8; z++)
        for (int y = 0; y < 8; y++)
            for (int x = 0; x < 8; x++) {
                double r = sqrt((x - 3.5) * (x - 3.5) + (y - 3.5) * (y - 3.5) + (z - 3.5) * (z - 3.5));
                d[(z * 8 + y) * 8 + x] = (uint8_t)(r < 3.0 ? 100 : 0);
            }
    vs_volume_update_range(vol);

    test_json();
    test_1dt();
    test_vtf();
    test_presets();

    vs_volume_release(vol);
    vs_context_release(ctx);
    tu_remove_tmpdir(dir);
    TEST_DONE();
}
