/* Synthetic scenes: sizes, types, spacing, analytic functions against the
 * sampled voxels and against numerical derivatives, determinism, errors. */
#include "internal.h"
#include "testutil.h"

#include <math.h>

static void check_shape(const vs_volume *v, const char *name, int nx, int ny, int nz, vs_type t,
                        double sx, double sy, double sz)
{
    CHECK(v->dims[0] == nx && v->dims[1] == ny && v->dims[2] == nz, "%s dims %dx%dx%d", name,
          v->dims[0], v->dims[1], v->dims[2]);
    CHECK(v->type == t, "%s type %s", name, vs_type_name(v->type));
    CHECK(v->spacing[0] == sx && v->spacing[1] == sy && v->spacing[2] == sz, "%s spacing %g %g %g",
          name, v->spacing[0], v->spacing[1], v->spacing[2]);
    CHECK(isfinite(v->default_iso) && isfinite(v->default_ramp), "%s has default iso/ramp", name);
}

/* Analytic f equals the stored voxel at every voxel centre. */
static void check_samples(const vs_volume *v, const char *name)
{
    double worst = 0.0;
    size_t i = 0;
    for (int k = 0; k < v->dims[2]; k++)
        for (int j = 0; j < v->dims[1]; j++)
            for (int x = 0; x < v->dims[0]; x++, i++) {
                const double p[3] = {x, j, k};
                double e = fabs(v->analytic.f(v->analytic.params, p) - vs_volume_at(v, i));
                if (e > worst) worst = e;
            }
    printf("%s: max |analytic - voxel| = %.3g\n", name, worst);
    CHECK(worst < 1e-6, "%s: analytic f differs from the voxels by %g", name, worst);
}

/* Analytic gradient against central differences of the analytic f at
 * pseudo-random points; skip(p) excludes kinks. */
static void check_gradient(const vs_volume *v, const char *name, int (*skip)(const vs_volume *, const double *))
{
    const double h = 1e-4;
    double worst = 0.0, scale = 0.0;
    uint64_t s = 12345;
    int tested = 0;
    for (int it = 0; it < 4000; it++) {
        double p[3];
        for (int a = 0; a < 3; a++) {
            s = s * 6364136223846793005ull + 1442695040888963407ull;
            p[a] = (double)(s >> 11) / 9007199254740992.0 * (v->dims[a] - 1);
        }
        if (skip && skip(v, p)) continue;
        double g[3];
        v->analytic.grad(v->analytic.params, p, g);
        for (int a = 0; a < 3; a++) {
            double q1[3] = {p[0], p[1], p[2]}, q0[3] = {p[0], p[1], p[2]};
            q1[a] += h;
            q0[a] -= h;
            double cd = (v->analytic.f(v->analytic.params, q1) - v->analytic.f(v->analytic.params, q0)) / (2 * h);
            double e = fabs(cd - g[a]);
            if (e > worst) worst = e;
            if (fabs(g[a]) > scale) scale = fabs(g[a]);
        }
        tested++;
    }
    printf("%s: %d points, max |grad - central diff| = %.3g (max |grad| %.3g)\n", name, tested, worst, scale);
    CHECK(tested > 1000, "%s: too few gradient points", name);
    CHECK(worst < 1e-5 * (scale > 1 ? scale : 1), "%s: gradient differs from central differences by %g", name,
          worst);
}

static int sphere_kink(const vs_volume *v, const double *p)
{
    const double *q = v->analytic.params;
    double r = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
    return fabs(r - (q[3] - q[4])) < 1e-3 || fabs(r - (q[3] + q[4])) < 1e-3 || r < 1e-3;
}

int main(void)
{
    vs_context *ctx;
    if (vs_context_create(&ctx) != VS_OK) return 1;

    /* cube: the 8^3 block centred in 16^3 */
    vs_volume *v = tu_scene(ctx, "cube");
    if (v) {
        check_shape(v, "cube", 16, 16, 16, VS_F32, 1, 1, 1);
        CHECK(v->has_analytic, "cube analytic");
        check_samples(v, "cube");
        const float *d = v->data;
        int ones = 0;
        for (int i = 0; i < 16 * 16 * 16; i++) ones += d[i] == 1.0f;
        CHECK(ones == 512, "cube holds %d ones", ones);
        CHECK(d[(4 * 16 + 4) * 16 + 4] == 1.0f && d[(11 * 16 + 11) * 16 + 11] == 1.0f &&
                  d[(3 * 16 + 4) * 16 + 4] == 0.0f && d[(12 * 16 + 11) * 16 + 11] == 0.0f,
              "cube occupies indices 4..11");
        /* the iso edge halfway between 11 and 12; gradient into the cube */
        const double out_x[3] = {11.51, 7.0, 8.0}, in_x[3] = {11.49, 7.0, 8.0}, lo_z[3] = {7, 8, 3.6};
        double g[3];
        CHECK(v->analytic.f(v->analytic.params, out_x) == 0.0 && v->analytic.f(v->analytic.params, in_x) == 1.0,
              "cube edge at 11.5");
        v->analytic.grad(v->analytic.params, out_x, g);
        CHECK(g[0] == -1 && g[1] == 0 && g[2] == 0, "cube +x face gradient %g %g %g", g[0], g[1], g[2]);
        v->analytic.grad(v->analytic.params, lo_z, g);
        CHECK(g[0] == 0 && g[1] == 0 && g[2] == 1, "cube -z face gradient %g %g %g", g[0], g[1], g[2]);
        vs_volume_release(v);
    }
    v = tu_scene(ctx, "cube:8");
    if (v) {
        check_samples(v, "cube:8");
        vs_volume_release(v);
    }

    v = tu_scene(ctx, "sphere");
    if (v) {
        check_shape(v, "sphere", 64, 64, 64, VS_F32, 1, 1, 1);
        CHECK(v->has_analytic, "sphere analytic");
        check_samples(v, "sphere");
        check_gradient(v, "sphere", sphere_kink);
        CHECK(v->vmin == 0.0 && v->vmax == 1.0, "sphere range %g..%g", v->vmin, v->vmax);
        vs_volume_release(v);
    }

    v = tu_scene(ctx, "ml");
    if (v) {
        check_shape(v, "ml", 41, 41, 41, VS_F32, 1, 1, 1);
        check_samples(v, "ml");
        check_gradient(v, "ml", NULL);
        printf("ml range %.4f..%.4f\n", v->vmin, v->vmax);
        CHECK(v->vmin >= -1e-6 && v->vmin < 0.05 && v->vmax <= 1.0 + 1e-6 && v->vmax > 0.95,
              "ml range %g..%g", v->vmin, v->vmax);
        /* the axis point (0,0,-1) of the ML function: rho = (2 + 2 alpha)/(2(1+alpha)) = 1 */
        const double p[3] = {20, 20, 0};
        CHECK(fabs(v->analytic.f(v->analytic.params, p) - 1.0) < 1e-12, "ml(0,0,-1) = 1");
        vs_volume_release(v);
    }
    v = tu_scene(ctx, "ml:64");
    if (v) {
        check_gradient(v, "ml:64", NULL);
        vs_volume_release(v);
    }

    double t = vs_now_ms();
    v = tu_scene(ctx, "head");
    printf("head: %.0f ms\n", vs_now_ms() - t);
    if (v) {
        check_shape(v, "head", 256, 256, 145, VS_F32, 1, 1, 1);
        check_samples(v, "head");
        printf("head range %.3f..%.3f iso %.2f\n", v->vmin, v->vmax, v->default_iso);
        CHECK(fabs(v->vmin) < 1e-6 && fabs(v->vmax - 1.0) < 1e-6, "head range %g..%g", v->vmin, v->vmax);
        const double c[3] = {127.5, 127.5, 72.0};
        CHECK(fabs(v->analytic.f(v->analytic.params, c) - 0.2) < 1e-6, "head brain is 0.2");
        /* skull along +x: outer edge at X = 0.69 -> index 127.5 + 0.69*127.5 */
        double xe = 127.5 + 0.69 * 127.5;
        const double pin[3] = {xe - 0.01, 127.5, 72.0}, pout[3] = {xe + 0.01, 127.5, 72.0};
        CHECK(fabs(v->analytic.f(v->analytic.params, pin) - 1.0) < 1e-9 && v->analytic.f(v->analytic.params, pout) == 0.0,
              "head skull edge");
        double g[3];
        v->analytic.grad(v->analytic.params, pout, g);
        CHECK(fabs(g[0] + 1.0) < 1e-9 && fabs(g[1]) < 1e-9 && fabs(g[2]) < 1e-9, "head skull normal %g %g %g",
              g[0], g[1], g[2]);
        /* inner skull boundary at X = 0.6624: gradient points outwards (into the bone) */
        double xi = 127.5 + 0.6624 * 127.5;
        const double pi2[3] = {xi - 0.01, 127.5, 72.0};
        v->analytic.grad(v->analytic.params, pi2, g);
        CHECK(g[0] > 0.79 && fabs(sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) - 0.8) < 1e-9,
              "head inner skull normal %g %g %g", g[0], g[1], g[2]);
        vs_volume_release(v);
    }
    v = tu_scene(ctx, "head:64");
    if (v) {
        check_shape(v, "head:64", 64, 64, 36, VS_F32, 1, 1, 1);
        check_samples(v, "head:64");
        vs_volume_release(v);
    }

    t = vs_now_ms();
    v = tu_scene(ctx, "cell");
    double ms_cell = vs_now_ms() - t;
    printf("cell: %.0f ms\n", ms_cell);
    if (v) {
        check_shape(v, "cell", 512, 512, 76, VS_U8, 1, 1, 2.5);
        CHECK(!v->has_analytic, "cell has no analytic form");
        CHECK(ms_cell < 4000 * tu_slack(), "cell generation took %.0f ms", ms_cell);
        size_t n = (size_t)512 * 512 * 76, above = 0;
        const uint8_t *d = v->data;
        for (size_t i = 0; i < n; i++) above += d[i] > v->default_iso;
        printf("cell: %.2f%% of voxels above iso %.0f, range %.0f..%.0f\n", 100.0 * above / n, v->default_iso,
               v->vmin, v->vmax);
        CHECK(above > n / 1000 && above < n / 5, "cell: %zu voxels above iso", above);
        vs_volume *w = tu_scene(ctx, "cell");
        if (w) {
            CHECK(memcmp(v->data, w->data, n) == 0, "cell generation is deterministic");
            vs_volume_release(w);
        }
        vs_volume_release(v);
    }
    v = tu_scene(ctx, "cell:64");
    if (v) {
        check_shape(v, "cell:64", 64, 64, 10, VS_U8, 1, 1, 2.5);
        vs_volume_release(v);
    }

    /* errors */
    const char *bad[] = {"", "teapot", "sphere:", "sphere:1", "sphere:1025", "sphere:abc", "sphere:12x",
                         "cube:7", ":16", "averyveryveryveryverylongscenename"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        vs_volume *x = (vs_volume *)1;
        vs_status st = vs_volume_scene(ctx, bad[i], &x);
        CHECK(st == VS_ERR_INVALID_ARGUMENT && x == NULL, "'%s' gives %d", bad[i], (int)st);
        CHECK(strlen(vs_last_error(ctx)) > 10, "'%s' has a message", bad[i]);
    }
    printf("message: %s\n", vs_last_error(ctx));
    CHECK(vs_volume_scene(ctx, NULL, &v) == VS_ERR_INVALID_ARGUMENT, "NULL spec");
    CHECK(vs_volume_scene(ctx, "cube", NULL) == VS_ERR_INVALID_ARGUMENT, "NULL out");

    vs_context_release(ctx);
    TEST_DONE();
}
