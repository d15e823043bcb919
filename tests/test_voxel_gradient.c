/* The gradient pre-shaded voxels are lit by (src/voxel_gradient.h) against
 * the field splatting reconstructs, summed by brute force here: at every
 * voxel of small random volumes (u8, i16 with negative values, f32 with
 * NaN and Inf), faces included, it must point where the derivative of
 * sum_j (f_j - base) 2^(-2 |x - x_j|^2) over all voxels j within radius 2
 * points; on a linear ramp, along the ramp; with data spanning +-FLT_MAX,
 * finite.  (test_splat checks the images: post-alpha lit by it stays
 * near post-cd against the exact-Gaussian ray caster.) */
#include "testutil.h"
#include "volume.h"
#include "voxel_gradient.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

static vs_context *ctx;

static uint64_t rng = 0x2545F4914F6CDD1Dull;
static double urand(void) { return tu_urand(&rng); }

/* The derivative of the reconstruction at voxel (i, j, k), over every
 * voxel of the volume (outside ones read as base, so they add nothing;
 * non-finite ones too). */
static void brute_gradient(const struct vs_volume *v, int i, int j, int k, double g[3])
{
    const double base = vs_volume_base(v);
    const int *d = v->dims;
    g[0] = g[1] = g[2] = 0.0;
    for (int z = 0; z < d[2]; z++)
        for (int y = 0; y < d[1]; y++)
            for (int x = 0; x < d[0]; x++) {
                const double dx = x - i, dy = y - j, dz = z - k, r2 = dx * dx + dy * dy + dz * dz;
                if (r2 > 4.0) continue;
                double f = vs_volume_at(v, (size_t)x + (size_t)d[0] * ((size_t)y + (size_t)d[1] * (size_t)z)) - base;
                if (!isfinite(f)) f = 0.0;
                /* d/dp of 2^(-2 |p - x|^2) at p = voxel i is 4 ln 2 (x - p) 2^(-2 r^2) */
                const double w = 4.0 * log(2.0) * f * exp2(-2.0 * r2);
                g[0] += w * dx;
                g[1] += w * dy;
                g[2] += w * dz;
            }
}

/* Largest angle (degrees) between the two gradients over all voxels, how
 * many voxels have one gradient zero and the other not, and the largest
 * relative departure of |g| / |b| from the constant 0.5 / (4 ln 2) it
 * must be (the face path and the interior one on one scale). */
static double worst_angle(const struct vs_volume *v, int *zero_mismatch, double *scale_err)
{
    const int *d = v->dims;
    double worst = 0.0;
    *zero_mismatch = 0;
    *scale_err = 0.0;
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++) {
                const size_t idx = (size_t)i + (size_t)d[0] * ((size_t)j + (size_t)d[1] * (size_t)k);
                float g[3];
                double b[3];
                vs_voxel_gradient(v, idx, g);
                brute_gradient(v, i, j, k, b);
                const double ng = sqrt((double)g[0] * g[0] + (double)g[1] * g[1] + (double)g[2] * g[2]);
                const double nb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
                if (ng == 0.0 || nb == 0.0) {
                    *zero_mismatch += (ng == 0.0) != (nb < 1e-9);
                    continue;
                }
                double c = (g[0] * b[0] + g[1] * b[1] + g[2] * b[2]) / (ng * nb);
                c = c > 1.0 ? 1.0 : c < -1.0 ? -1.0 : c;
                const double a = acos(c) * 180.0 / M_PI;
                if (a > worst) worst = a;
                const double e = fabs(ng / nb / (0.5 / (4.0 * log(2.0))) - 1.0);
                if (e > *scale_err) *scale_err = e;
            }
    return worst;
}

/* A volume of unit spacing (sp NULL) or sp, or NULL with a failed check. */
static vs_volume *new_volume(vs_type t, const int dims[3], const double *sp)
{
    vs_volume *v = NULL;
    CHECK(vs_volume_create(ctx, t, dims, sp, &v) == VS_OK, "volume: %s", vs_last_error(ctx));
    return v;
}

static void test_against_brute_force(void)
{
    const vs_type types[4] = {VS_U8, VS_I16, VS_U16, VS_F32};
    const int dims[3] = {9, 8, 7};
    const double sp[3] = {1.0, 1.5, 2.0};
    for (int t = 0; t < 4; t++) {
        vs_volume *v = new_volume(types[t], dims, sp);
        if (!v) return;
        const size_t n = (size_t)dims[0] * dims[1] * dims[2];
        void *data = vs_volume_data(v);
        for (size_t i = 0; i < n; i++) {
            const double r = urand();
            if (types[t] == VS_U8) ((uint8_t *)data)[i] = (uint8_t)(255.0 * r);
            if (types[t] == VS_I16) ((int16_t *)data)[i] = (int16_t)(65535.0 * r - 32768.0);
            if (types[t] == VS_U16) ((uint16_t *)data)[i] = (uint16_t)(65535.0 * r);
            if (types[t] == VS_F32) ((float *)data)[i] = (float)(10.0 * r - 3.0);
        }
        if (types[t] == VS_F32) {
            ((float *)data)[100] = NAN;
            ((float *)data)[211] = INFINITY;
        }
        vs_volume_update_range(v);
        int zm;
        double se;
        const double a = worst_angle(v, &zm, &se);
        printf("%-4s %dx%dx%d, base %g: worst angle to the brute-force derivative %.2e degrees, scale %.1e off\n",
               vs_type_name(types[t]), dims[0], dims[1], dims[2], vs_volume_base(v), a, se);
        CHECK(se < 1e-5, "%s: gradient magnitudes %.3g off the reconstruction's scale", vs_type_name(types[t]), se);
        CHECK(a < 1e-3, "%s: gradient %.3g degrees off the reconstruction's", vs_type_name(types[t]), a);
        CHECK(zm == 0, "%s: %d voxels with a zero gradient where the reconstruction has none", vs_type_name(types[t]),
              zm);
        vs_volume_release(v);
    }
}

/* f = 3x - 2y + 5z: the kernel is symmetric, so its reconstruction's
 * derivative at an interior voxel is exactly along (3, -2, 5). */
static void test_ramp(void)
{
    const int dims[3] = {8, 8, 8};
    vs_volume *v = new_volume(VS_F32, dims, NULL);
    if (!v) return;
    float *f = vs_volume_data(v);
    for (int k = 0; k < 8; k++)
        for (int j = 0; j < 8; j++)
            for (int i = 0; i < 8; i++) f[i + 8 * (j + 8 * k)] = (float)(3 * i - 2 * j + 5 * k + 40);
    vs_volume_update_range(v);
    int bad = 0;
    for (int k = 2; k < 6; k++)
        for (int j = 2; j < 6; j++)
            for (int i = 2; i < 6; i++) {
                float g[3];
                vs_voxel_gradient(v, (size_t)(i + 8 * (j + 8 * k)), g);
                bad += !(fabsf(g[0] / g[2] - 0.6f) < 1e-6f && fabsf(g[1] / g[2] + 0.4f) < 1e-6f);
            }
    CHECK(bad == 0, "ramp: %d interior voxels not along (3, -2, 5)", bad);
    vs_volume_release(v);
}

/* Data spanning +-FLT_MAX, mixed and as a step from -FLT_MAX to FLT_MAX
 * along x (0.57 FLT_MAX there, over FLT_MAX if not halved): every
 * gradient finite. */
static void test_extremes(void)
{
    const int dims[3] = {6, 6, 6};
    vs_volume *v = new_volume(VS_F32, dims, NULL);
    if (!v) return;
    float *f = vs_volume_data(v);
    for (int pattern = 0; pattern < 2; pattern++) {
        for (int i = 0; i < 216; i++)
            f[i] = (pattern ? i % 6 >= 3 : (i % 7) < 3) ? FLT_MAX : -FLT_MAX;
        vs_volume_update_range(v);
        int bad = 0;
        for (int i = 0; i < 216; i++) {
            float g[3];
            vs_voxel_gradient(v, (size_t)i, g);
            bad += !(isfinite(g[0]) && isfinite(g[1]) && isfinite(g[2]));
        }
        CHECK(bad == 0, "+-FLT_MAX, pattern %d: %d gradients not finite", pattern, bad);
    }
    vs_volume_release(v);
}

int main(void)
{
    if (vs_context_create(&ctx) != VS_OK) return 1;
    test_against_brute_force();
    test_ramp();
    test_extremes();
    vs_context_release(ctx);
    TEST_DONE();
}
