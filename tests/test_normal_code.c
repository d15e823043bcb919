/* Pre-shaded voxels' normals as octahedral codes (src/normal_code.h):
 * every direction comes back within the code's angular resolution, g and
 * -g share a code, directionless gradients face the eye; the per-view table
 * gives the exact light's terms of the direction it codes; and the codes a
 * context keeps per voxel follow the data (a rewritten volume is re-coded)
 * and give the image of a fresh context for any thread count. */
#include "light.h"
#include "context.h"
#include "normal_code.h"
#include "testutil.h"

#include <float.h>
#include <math.h>
#include <stdint.h>

static vs_context *ctx;

/* xorshift: the same directions every run */
static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double urand(void) { return tu_urand(&rng); }
static void random_dir(double w[3])
{
    double m;
    do {
        for (int i = 0; i < 3; i++) w[i] = 2.0 * urand() - 1.0;
        m = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    } while (m < 1e-3 || m > 1.0);
    for (int i = 0; i < 3; i++) w[i] /= m;
}

/* Angle in degrees between w and the direction of code c, up to sign. */
static double code_angle(int c, const double w[3])
{
    double n[3];
    vs_normal_decode(c, n);
    double m = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    double d = fabs(n[0] * w[0] + n[1] * w[1] + n[2] * w[2]) / m;
    return acos(d > 1.0 ? 1.0 : d) * 180.0 / M_PI;
}

/* The angular resolution of 181 x 181 cells on the half octahedron, where
 * the map stretches most (measured over 1e6 directions: 0.77 degrees). */
#define MAX_ANGLE_DEG 0.8

static void test_codes(void)
{
    double worst = 0.0;
    int bad_range = 0, bad_sign = 0, bad_scale = 0;
    for (int n = 0; n < 1000000; n++) {
        double w[3];
        random_dir(w);
        if (n < 26) { /* first the axes, face diagonals and corners: {-1,0,1}^3 less 0 */
            const int m = n < 13 ? n : n + 1;
            const double a = m % 3 - 1.0, b = (m / 3) % 3 - 1.0, c = m / 9 - 1.0, r = sqrt(a * a + b * b + c * c);
            w[0] = a / r;
            w[1] = b / r;
            w[2] = c / r;
        }
        const float g[3] = {(float)w[0], (float)w[1], (float)w[2]};
        const int c = vs_normal_code(g[0], g[1], g[2]);
        if (c < 0 || c >= VS_NORMAL_ZERO) {
            bad_range++;
            continue;
        }
        const double a = code_angle(c, w);
        if (a > worst) worst = a;
        if (g[2] != 0.0f && vs_normal_code(-g[0], -g[1], -g[2]) != c) bad_sign++;
        if (vs_normal_code(4.0f * g[0], 4.0f * g[1], 4.0f * g[2]) != c ||
            vs_normal_code(0x1p-60f * g[0], 0x1p-60f * g[1], 0x1p-60f * g[2]) != c)
            bad_scale++;
    }
    printf("codes: worst angle %.3f degrees over 1e6 directions\n", worst);
    CHECK(bad_range == 0, "%d directions got no code", bad_range);
    CHECK(worst <= MAX_ANGLE_DEG, "a code is %.3f degrees off its direction (> %.1f)", worst, MAX_ANGLE_DEG);
    CHECK(bad_sign == 0, "%d directions code apart from their opposites", bad_sign);
    CHECK(bad_scale == 0, "%d directions code apart when scaled by a power of two", bad_scale);
    /* no direction: zero, tiny, NaN, infinite */
    CHECK(vs_normal_code(0.0f, 0.0f, 0.0f) == VS_NORMAL_ZERO, "zero gradient");
    CHECK(vs_normal_code(1e-31f, 0.0f, -1e-32f) == VS_NORMAL_ZERO, "gradient under 1e-30");
    CHECK(vs_normal_code(NAN, 1.0f, 0.0f) == VS_NORMAL_ZERO, "NaN component");
    CHECK(vs_normal_code(1.0f, -INFINITY, 0.0f) == VS_NORMAL_ZERO, "infinite component");
    /* finite components whose sum overflows keep their direction */
    const int big = vs_normal_code(FLT_MAX, -FLT_MAX, FLT_MAX);
    const double diag[3] = {1 / sqrt(3.0), -1 / sqrt(3.0), 1 / sqrt(3.0)};
    CHECK(big < VS_NORMAL_ZERO && code_angle(big, diag) <= MAX_ANGLE_DEG, "FLT_MAX components: code %d", big);
}

/* The table's terms for a direction's code against the light evaluated
 * exactly for that direction, for a headlight and a light from the side,
 * seen from two views: the difference is what the angle allows. */
static void test_table(void)
{
    vs_normal_table tab = {0};
    const double s2 = sqrt(0.5);
    /* camera axes in the volume's frame: right, up, dir (orthonormal) */
    const double views[2][3][3] = {{{1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
                                   {{s2, s2, 0}, {-0.5, 0.5, s2}, {0.5, -0.5, s2}}};
    for (int lit = 0; lit < 2; lit++)
        for (int vw = 0; vw < 2; vw++) {
            vs_light l = {.ka = 0.2, .kd = 0.6, .ks = 0.2, .n = 20};
            const double L[3] = {lit ? -0.6 : 0.0, lit ? -0.48 : 0.0, lit ? -0.64 : -1.0};
            double H[3] = {L[0], L[1], L[2] - 1.0}, hm = sqrt(H[0] * H[0] + H[1] * H[1] + H[2] * H[2]);
            for (int i = 0; i < 3; i++) {
                l.L[i] = L[i];
                l.H[i] = H[i] / hm;
            }
            const double(*cam)[3] = views[vw];
            if (vs_normal_table_setup(ctx, &l, cam[0], cam[1], cam[2], &tab) != VS_OK) {
                CHECK(0, "table: %s", vs_last_error(ctx));
                continue;
            }
            /* two-sided lighting flips a normal that faces away from the eye,
             * so the light is discontinuous where a normal turns edge-on;
             * directions that close to edge-on are left out */
            const double rad = MAX_ANGLE_DEG * M_PI / 180.0;
            double worst_d = 0.0, worst_s = 0.0;
            for (int n = 0; n < 20000; n++) {
                double w[3], e[3], d, s;
                random_dir(w);
                for (int r = 0; r < 3; r++) e[r] = w[0] * cam[r][0] + w[1] * cam[r][1] + w[2] * cam[r][2];
                if (fabs(e[2]) < sin(rad)) continue;
                e[1] = -e[1]; /* the eye frame's second axis points down */
                vs_light_eval(&l, e, &d, &s);
                const float *t = tab.terms[vs_normal_code((float)w[0], (float)w[1], (float)w[2])];
                if (fabs(t[0] - d) > worst_d) worst_d = fabs(t[0] - d);
                if (fabs(t[1] - s) > worst_s) worst_s = fabs(t[1] - s);
            }
            /* kd cos moves at most kd a for an angle a, ks cos^20 at most
             * ks 20 cos^19 sin a, whose largest value is 0.137 ks 20 a */
            printf("table, light %d, view %d: diffuse within %.4f, specular within %.4f\n", lit, vw, worst_d, worst_s);
            CHECK(worst_d <= 0.6 * rad, "light %d view %d: diffuse off by %.4f", lit, vw, worst_d);
            CHECK(worst_s <= 0.2 * 20 * 0.137 * rad, "light %d view %d: specular off by %.4f", lit, vw, worst_s);
            const float *z = tab.terms[VS_NORMAL_ZERO];
            double d0, s0;
            const double none[3] = {0, 0, 0};
            vs_light_eval(&l, none, &d0, &s0);
            CHECK(z[0] == (float)d0 && z[1] == (float)s0, "no direction: terms %g %g, the light's %g %g", z[0], z[1],
                  d0, s0);
        }
    vs_normal_table_free(&tab);
}

/* A render in a context of its own (tu_render checks it). */
static vs_image render_fresh(const vs_volume *v, const vs_settings *s)
{
    vs_context *c;
    vs_image img = {0, 0, NULL};
    if (vs_context_create(&c) != VS_OK) return img;
    img = tu_render(c, v, s, NULL);
    vs_context_release(c);
    return img;
}

/* On the sphere, against the analytic ray caster: table normals are as
 * close as exact ones, in both pre-shaded pipelines, with the headlight and
 * a light from the upper left.  (Against each other they differ most where
 * a normal turns edge-on, where two-sided lighting flips it.) */
static void test_images_against_truth(void)
{
    vs_volume *v = tu_scene(ctx, "sphere");
    if (!v) return;
    for (int lit = 0; lit < 2; lit++) {
        vs_settings s;
        vs_settings_init(&s);
        s.width = s.height = 128;
        s.azimuth = 30;
        s.elevation = 20;
        if (lit) {
            s.headlight = 0;
            s.light_dir[0] = -1.0;
            s.light_dir[1] = 0.5;
            s.light_dir[2] = 1.0;
        }
        s.pipeline = VS_PIPELINE_RAYCAST;
        s.ray_step = 0.05;
        s.ray_analytic = 1;
        vs_image truth = render_fresh(v, &s);
        for (int p = 0; p < 2 && truth.rgba; p++) {
            s.pipeline = p ? VS_PIPELINE_POST_ALPHA : VS_PIPELINE_PRE;
            s.exact_normals = 0;
            vs_image a = render_fresh(v, &s);
            s.exact_normals = 1;
            vs_image b = render_fresh(v, &s);
            if (a.rgba && b.rgba) {
                const double pa = tu_psnr(ctx, &a, &truth), pb = tu_psnr(ctx, &b, &truth), pab = tu_psnr(ctx, &a, &b);
                printf("%s, light %d: against the ray caster, table normals %.2f dB, exact %.2f dB; against "
                       "each other %.1f dB\n", vs_pipeline_name(s.pipeline), lit, pa, pb, pab);
                CHECK(pa >= pb - 0.1, "%s, light %d: table normals %.2f dB, exact %.2f dB",
                      vs_pipeline_name(s.pipeline), lit, pa, pb);
                /* a headlight is continuous where normals turn edge-on */
                CHECK(lit || pab >= 65.0, "%s, headlight: table normals %.1f dB from exact ones",
                      vs_pipeline_name(s.pipeline), pab);
            }
            vs_image_free(&a);
            vs_image_free(&b);
        }
        vs_image_free(&truth);
    }
    vs_volume_release(v);
}

/* A context's kept codes: its second frame, a frame on two threads after one
 * (codes filled in by racing workers), and a frame after the data were
 * rewritten in place (vs_volume_update_range) each equal a fresh context's.
 * The rewrite turns a ramp along x into one along y, so stale codes would
 * light the new data as the old. */
static void test_kept_codes(void)
{
    const int dims[3] = {24, 24, 24};
    vs_volume *v = NULL;
    if (vs_volume_create(ctx, VS_F32, dims, NULL, &v) != VS_OK) {
        CHECK(0, "create: %s", vs_last_error(ctx));
        return;
    }
    float *f = vs_volume_data(v);
    vs_context *kept;
    if (vs_context_create(&kept) != VS_OK) {
        vs_volume_release(v);
        return;
    }
    vs_image first = {0, 0, NULL};
    for (int round = 0; round < 2; round++) {
        /* a ball whose density ramps along x (round 0) or y (round 1) */
        for (int k = 0; k < 24; k++)
            for (int j = 0; j < 24; j++)
                for (int i = 0; i < 24; i++) {
                    const double r = sqrt((i - 11.5) * (i - 11.5) + (j - 11.5) * (j - 11.5) + (k - 11.5) * (k - 11.5));
                    const int ramp = round ? j : i;
                    f[i + 24 * (j + 24 * k)] = r < 10.0 ? (float)(50 + 4 * ramp) : 0.0f;
                }
        vs_volume_update_range(v);
        for (int p = 0; p < 2; p++) {
            vs_settings s;
            vs_settings_init(&s);
            s.pipeline = p ? VS_PIPELINE_POST_ALPHA : VS_PIPELINE_PRE;
            s.width = s.height = 64;
            s.azimuth = 35;
            s.elevation = 25;
            s.has_iso = 1;
            s.iso_lo = 40;
            s.iso_hi = 200;
            s.ramp = 4;
            s.iso_opacity = 0.4f; /* translucent: the ramp's inside shows */
            s.threads = 2;
            vs_image fresh = render_fresh(v, &s);
            vs_image a = tu_render(kept, v, &s, NULL);
            s.threads = 1;
            vs_image b = tu_render(kept, v, &s, NULL);
            if (fresh.rgba && a.rgba && b.rgba) {
                CHECK(tu_max_diff(&fresh, &a) == 0.0, "round %d %s: kept context, 2 threads, differs by %g", round,
                      vs_pipeline_name(s.pipeline), tu_max_diff(&fresh, &a));
                CHECK(tu_max_diff(&fresh, &b) == 0.0, "round %d %s: kept context, 1 thread, differs by %g", round,
                      vs_pipeline_name(s.pipeline), tu_max_diff(&fresh, &b));
            }
            if (p == 0 && round == 0) {
                first = fresh;
                fresh.rgba = NULL;
            } else if (p == 0 && first.rgba && fresh.rgba) {
                CHECK(tu_max_diff(&first, &fresh) > 0.02, "the rewrite changed the image by only %g (the test "
                      "shows nothing)", tu_max_diff(&first, &fresh));
            }
            vs_image_free(&fresh);
            vs_image_free(&a);
            vs_image_free(&b);
        }
    }
    vs_image_free(&first);
    vs_context_release(kept);
    vs_volume_release(v);
}

/* The value outside the volume is part of a voxel's gradient near a face
 * (src/voxel_gradient.h), and a declared range sets it: after
 * vs_volume_set_range a context that kept the codes must render what a
 * fresh one renders.  An i16 ball that runs into the faces, in air of
 * -1000 (outside value -1000), then declared 0..1000 (outside value 0). */
static void test_codes_follow_range(void)
{
    const int dims[3] = {32, 32, 32};
    vs_volume *v = NULL;
    if (vs_volume_create(ctx, VS_I16, dims, NULL, &v) != VS_OK) {
        CHECK(0, "create: %s", vs_last_error(ctx));
        return;
    }
    int16_t *f = vs_volume_data(v);
    for (int k = 0; k < 32; k++)
        for (int j = 0; j < 32; j++)
            for (int i = 0; i < 32; i++) {
                const double r = sqrt((i - 15.5) * (i - 15.5) + (j - 15.5) * (j - 15.5) + (k - 15.5) * (k - 15.5));
                f[i + 32 * (j + 32 * k)] = (int16_t)(r < 18.0 ? 400 + 10 * i : -1000);
            }
    vs_volume_update_range(v);
    vs_context *kept;
    if (vs_context_create(&kept) != VS_OK) {
        vs_volume_release(v);
        return;
    }
    vs_settings s;
    vs_settings_init(&s);
    s.pipeline = VS_PIPELINE_PRE;
    s.width = s.height = 64;
    s.azimuth = 35;
    s.elevation = 25;
    s.has_iso = 1;
    s.iso_lo = 300;
    s.iso_hi = 1000;
    s.ramp = 40;
    vs_image before = tu_render(kept, v, &s, NULL);
    CHECK(vs_volume_set_range(v, 0.0, 1000.0) == VS_OK, "set_range");
    vs_image a = tu_render(kept, v, &s, NULL), fresh = render_fresh(v, &s);
    if (before.rgba && a.rgba && fresh.rgba) {
        printf("codes after a new range: kept vs fresh %g, before vs after %g\n", tu_max_diff(&a, &fresh),
               tu_max_diff(&before, &fresh));
        CHECK(tu_max_diff(&a, &fresh) == 0.0, "after a new range the kept codes differ by %g", tu_max_diff(&a, &fresh));
        CHECK(tu_max_diff(&before, &fresh) > 1e-3, "the new range changed nothing (%g): the test shows nothing",
              tu_max_diff(&before, &fresh));
    }
    vs_image_free(&before);
    vs_image_free(&a);
    vs_image_free(&fresh);
    vs_context_release(kept);
    vs_volume_release(v);
}

/* The codes are kept: after a frame, the context's array for the volume
 * holds codes, each that of its voxel (a brick's slot is
 * vs_normal_code_slot of its lowest voxel, plus the voxel's place in it). */
static void test_codes_kept(void)
{
    vs_volume *v = tu_scene(ctx, "sphere:48"); /* isotropic: splatted as it is */
    if (!v) return;
    vs_context *c;
    if (vs_context_create(&c) != VS_OK) {
        vs_volume_release(v);
        return;
    }
    vs_settings s;
    vs_settings_init(&s);
    s.pipeline = VS_PIPELINE_POST_ALPHA;
    s.width = s.height = 96;
    vs_image img = tu_render(c, v, &s, NULL);
    vs_image_free(&img);
    const _Atomic uint16_t *kept = vs_normal_codes_get(c, v);
    const int *d = v->dims;
    float sc[3];
    vs_normal_code_scale(v, sc);
    size_t filled = 0, wrong = 0;
    for (int k = 0; kept && k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++) {
                const uint32_t slot = vs_normal_code_slot(v, i & ~(VS_BRICK - 1), j & ~(VS_BRICK - 1), k & ~(VS_BRICK - 1)) +
                                      (uint32_t)((i & (VS_BRICK - 1)) | (j & (VS_BRICK - 1)) << VS_BRICK_BITS |
                                                 (k & (VS_BRICK - 1)) << (2 * VS_BRICK_BITS));
                const unsigned got = atomic_load(&kept[slot]);
                if (!got) continue;
                filled++;
                const size_t idx = (size_t)i + (size_t)d[0] * ((size_t)j + (size_t)d[1] * (size_t)k);
                wrong += got - 1 != (unsigned)vs_voxel_normal_code(v, sc, idx);
            }
    printf("kept codes after one frame: %zu voxels, %zu wrong\n", filled, wrong);
    CHECK(kept != NULL && filled > 1000, "the context kept %zu codes", filled);
    CHECK(wrong == 0, "%zu kept codes are not their voxels'", wrong);
    vs_context_release(c);
    vs_volume_release(v);
}

int main(void)
{
    if (vs_context_create(&ctx) != VS_OK) return 1;
    test_codes();
    test_table();
    test_images_against_truth();
    test_kept_codes();
    test_codes_follow_range();
    test_codes_kept();
    vs_context_release(ctx);
    TEST_DONE();
}
