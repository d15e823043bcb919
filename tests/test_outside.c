/* What lies outside the volume: every pipeline and the ray caster read the
 * volume's minimum there when it is negative (vs_volume_base), so that a CT
 * volume's air stays air at its faces.  The property tested is invariance:
 * a CT-like ball (air -1000, bone +1000) rendered at iso -500 gives the
 * image of the same ball shifted by +1000 (air 0) at iso +500, in every
 * pipeline and the ray caster; with 0 outside, the shifted ball's faces
 * stay clear but the CT one's draw a surface (ray caster: the whole box;
 * splatting: outlines).  And splatting agrees with the ray caster there. */
#include "testutil.h"
#include "volume.h"

#include <float.h>

static vs_context *ctx;

/* 40^3 i16: a ball of radius 12 at `inside`, falling linearly to `air` over
 * 4 voxels of radius. */
static vs_volume *ball(int air, int inside)
{
    const int n = 40, dims[3] = {n, n, n};
    vs_volume *v = NULL;
    if (vs_volume_create(ctx, VS_I16, dims, NULL, &v) != VS_OK) return NULL;
    int16_t *d = vs_volume_data(v);
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                const double r = sqrt((i - 19.5) * (i - 19.5) + (j - 19.5) * (j - 19.5) + (k - 19.5) * (k - 19.5));
                double t = (16.0 - r) / 4.0;
                t = t < 0 ? 0 : t > 1 ? 1 : t;
                d[((size_t)k * n + j) * n + i] = (int16_t)lrint(air + t * (inside - air));
            }
    vs_volume_update_range(v);
    return v;
}

/* Pixels with any opacity. */
static int covered(const vs_image *im)
{
    int c = 0;
    for (size_t i = 0; i < (size_t)im->width * im->height; i++) c += im->rgba[4 * i + 3] > 0.01f;
    return c;
}

int main(void)
{
    if (vs_context_create(&ctx) != VS_OK) return 2;
    vs_volume *ct = ball(-1000, 1000), *mr = ball(0, 2000);
    CHECK(ct && mr, "volumes: %s", vs_last_error(ctx));
    if (!ct || !mr) TEST_DONE();
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 96;
    s.azimuth = 30;
    s.elevation = 20;
    s.has_iso = 1;
    s.iso_hi = INFINITY;
    s.ramp = 100;
    s.threads = 2;
    s.lod_pixels = 0;
    const vs_pipeline pipes[] = {VS_PIPELINE_PRE, VS_PIPELINE_POST_CD, VS_PIPELINE_POST_GS, VS_PIPELINE_POST_ALPHA,
                                 VS_PIPELINE_RAYCAST};
    vs_image ray = {0}, cd = {0};
    for (int p = 0; p < 5; p++) {
        s.pipeline = pipes[p];
        s.iso_lo = -500;
        vs_image a = tu_render(ctx, ct, &s, NULL);
        s.iso_lo = 500;
        vs_image b = tu_render(ctx, mr, &s, NULL);
        const double d = tu_max_diff(&a, &b), ps = tu_psnr(ctx, &a, &b);
        const int ca = covered(&a), cb = covered(&b);
        /* the same up to float rounding of the shifted values */
        CHECK(ps >= 60.0 && ca == cb, "%s: air at -1000 vs 0: %.1f dB apart (max %.2g), %d vs %d pixels covered",
              vs_pipeline_name(s.pipeline), ps, d, ca, cb);
        printf("  %-10s air -1000 vs 0: %6.1f dB apart (max diff %.2g), %d vs %d pixels covered\n",
               vs_pipeline_name(s.pipeline), ps, d, ca, cb);
        if (s.pipeline == VS_PIPELINE_RAYCAST) ray = a;
        else if (s.pipeline == VS_PIPELINE_POST_CD) cd = a;
        else vs_image_free(&a);
        vs_image_free(&b);
    }
    /* the ball covers a disc; with the faces drawn the box would cover
     * far more (its projection at 30,20 fills most of the frame) */
    const int disc = covered(&ray);
    CHECK(disc > 0 && disc < 0.45 * 96 * 96, "the ray caster covers %d of %d pixels: the box's faces are drawn", disc,
          96 * 96);
    const double agree = tu_psnr(ctx, &cd, &ray);
    CHECK(agree >= 30.0, "post-cd and the ray caster on the CT ball: %.1f dB", agree);
    printf("  CT ball: ray caster covers %d pixels; post-cd vs ray caster %.1f dB\n", disc, agree);
    vs_image_free(&ray);
    vs_image_free(&cd);

    /* the rule itself: negative minimum only, not constant, float-safe */
    CHECK(vs_volume_base(ct) == -1000.0 && vs_volume_base(mr) == 0.0, "base %g and %g", vs_volume_base(ct),
          vs_volume_base(mr));
    CHECK(vs_volume_set_range(ct, -1000, -1000) == VS_OK && vs_volume_base(ct) == 0.0, "a constant volume's base");
    CHECK(vs_volume_set_range(ct, -FLT_MAX, FLT_MAX) == VS_OK && vs_volume_base(ct) == 0.0, "an unshiftable range");
    vs_volume_release(ct);
    vs_volume_release(mr);
    vs_context_release(ctx);
    TEST_DONE();
}
