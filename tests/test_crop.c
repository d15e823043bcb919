/* The crop box (vs_settings.has_crop) and vs_volume_set_range, what
 * vsplat-mpi's sort-last rendering is built on:
 *  - a box that is the whole volume changes nothing (bit-identical);
 *  - two boxes that split the volume, each rendered alone and composited
 *    front over back (the front decided from the view direction, not by
 *    the library), give the whole image back; each alone does not;
 *  - a brick cut out of the volume with ghost layers, rendered with the
 *    zoom scaled by its extent and the centre moved into its index space,
 *    lines up with the whole volume cropped to the same box (up to float
 *    rounding of the scale and the splatting order: a pixel's shift is
 *    below 20 dB).
 * Every splatting pipeline, orthographic and perspective. */
#include "testutil.h"

enum { W = 96 };

/* front over back, both straight with a transparent background; the result
 * straight as the library stores it */
static vs_image over(const vs_image *front, const vs_image *back)
{
    vs_image o = {front->width, front->height, calloc((size_t)front->width * front->height * 4, sizeof(float))};
    for (size_t p = 0; p < (size_t)o.width * o.height; p++) {
        const float *f = front->rgba + 4 * p, *b = back->rgba + 4 * p;
        float a = f[3] + (1 - f[3]) * b[3];
        for (int c = 0; c < 3; c++) {
            float rgb = f[c] * f[3] + (1 - f[3]) * b[c] * b[3];
            o.rgba[4 * p + c] = a > 0 ? rgb / a : 0;
        }
        o.rgba[4 * p + 3] = a;
    }
    return o;
}

static void check_case(vs_context *ctx, const vs_volume *vol, vs_settings s, const char *what)
{
    int d[3];
    vs_volume_dims(vol, d);
    vs_image whole = tu_render(ctx, vol, &s, NULL);

    /* the whole volume as the box: nothing changes */
    vs_settings c = s;
    c.has_crop = 1;
    for (int a = 0; a < 3; a++) {
        c.crop_lo[a] = 0;
        c.crop_hi[a] = d[a];
    }
    vs_image same = tu_render(ctx, vol, &c, NULL);
    CHECK(same.rgba && tu_max_diff(&whole, &same) == 0.0, "%s: whole-volume crop differs by %g", what,
          tu_max_diff(&whole, &same));

    /* split along x at s0; the view travels towards -x when dir.x < 0 (view
     * 0,0 looks along +y; azimuth turns about +z), then the high side is in
     * front.  Perspective: the eye sits on the side the view comes from. */
    const int s0 = d[0] / 2 + 1;
    vs_settings lo = c, hi = c;
    lo.crop_hi[0] = s0;
    hi.crop_lo[0] = s0;
    vs_image il = tu_render(ctx, vol, &lo, NULL), ih = tu_render(ctx, vol, &hi, NULL);
    const double dirx = -sin(s.azimuth * M_PI / 180) * cos(s.elevation * M_PI / 180);
    vs_image comp = dirx < 0 ? over(&ih, &il) : over(&il, &ih);
    double p = tu_psnr(ctx, &whole, &comp), pl = tu_psnr(ctx, &whole, &il), ph = tu_psnr(ctx, &whole, &ih);
    printf("%-28s halves composited %.1f dB (alone %.1f, %.1f)\n", what, p, pl, ph);
    CHECK(p >= 60.0, "%s: halves composited: %.1f dB", what, p);
    CHECK(pl < 40.0 && ph < 40.0, "%s: one half alone is the whole image (%.1f, %.1f dB)", what, pl, ph);

    /* the high half as a brick of its own with ghost layers, as vsplat-mpi cuts it */
    const int g = 4, x0 = s0 - g, bd[3] = {d[0] - x0, d[1], d[2]};
    double sp[3], vlo, vhi;
    vs_volume_spacing(vol, sp);
    vs_volume_range(vol, &vlo, &vhi);
    vs_volume *brick = NULL;
    const vs_type t = vs_volume_type(vol);
    const size_t es = t == VS_U8 ? 1 : t == VS_F32 ? 4 : 2;
    CHECK(vs_volume_create(ctx, t, bd, sp, &brick) == VS_OK, "brick");
    if (brick) {
        const unsigned char *src = vs_volume_data((vs_volume *)vol);
        unsigned char *dst = vs_volume_data(brick);
        for (int k = 0; k < d[2]; k++)
            for (int j = 0; j < d[1]; j++)
                memcpy(dst + (((size_t)k * bd[1] + j) * bd[0]) * es, src + (((size_t)k * d[1] + j) * d[0] + x0) * es,
                       (size_t)bd[0] * es);
        CHECK(vs_volume_set_range(brick, vlo, vhi) == VS_OK, "set_range");
        vs_settings b = hi;
        double ext = 0, bext = 0;
        for (int a = 0; a < 3; a++) {
            if (d[a] * sp[a] > ext) ext = d[a] * sp[a];
            if (bd[a] * sp[a] > bext) bext = bd[a] * sp[a];
            b.center[a] = 0.5 * (d[a] - 1) - (a == 0 ? x0 : 0);
        }
        b.has_center = 1;
        b.zoom = s.zoom * bext / ext;
        b.crop_lo[0] = s0 - x0;
        b.crop_hi[0] = bd[0];
        vs_image ib = tu_render(ctx, brick, &b, NULL);
        double pb = tu_psnr(ctx, &ih, &ib), mb = ib.rgba ? tu_max_diff(&ih, &ib) : 1;
        printf("%-28s brick vs whole-volume crop %.1f dB, max %.2g\n", what, pb, mb);
        /* a gradient on the edge of a normal-LUT bin may land in the next
         * bin (one such pixel is up to 0.017 off, 77.5 dB at this size) */
        CHECK(pb >= 75.0 && mb < 0.02, "%s: the brick does not line up: %.1f dB, max %g", what, pb, mb);
        vs_image_free(&ib);
        vs_volume_release(brick);
    }
    vs_image_free(&whole);
    vs_image_free(&same);
    vs_image_free(&il);
    vs_image_free(&ih);
    vs_image_free(&comp);
}

int main(void)
{
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return 1;
    vs_volume *vol = tu_scene(ctx, "head:64");
    if (!vol) return 1;

    /* the range is what the classification tables span; a bad one is refused */
    CHECK(vs_volume_set_range(vol, 1, 0) == VS_ERR_INVALID_ARGUMENT, "lo > hi accepted");
    CHECK(vs_volume_set_range(vol, 0, NAN) == VS_ERR_INVALID_ARGUMENT, "NaN accepted");

    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = W;
    s.threads = 1;
    s.pin = 0;
    /* the iso-range as the whole volume resolves it, so the brick (another
     * histogram) classifies alike */
    vs_stats st;
    vs_image tmp = tu_render(ctx, vol, &s, NULL);
    vs_image_free(&tmp);
    CHECK(vs_render(ctx, vol, &s, &tmp, &st) == VS_OK, "stats");
    vs_image_free(&tmp);
    s.has_iso = 1;
    s.iso_lo = st.iso_lo;
    s.iso_hi = st.iso_hi;
    s.ramp = st.ramp;

    /* a crop box outside the volume, or empty, is refused */
    vs_settings bad = s;
    bad.has_crop = 1;
    bad.crop_hi[0] = bad.crop_hi[1] = bad.crop_hi[2] = 65;
    CHECK(vs_render(ctx, vol, &bad, &tmp, NULL) == VS_ERR_INVALID_ARGUMENT, "crop past the volume accepted");
    bad.crop_hi[0] = bad.crop_hi[1] = bad.crop_hi[2] = 0;
    CHECK(vs_render(ctx, vol, &bad, &tmp, NULL) == VS_ERR_INVALID_ARGUMENT, "empty crop accepted");

    const vs_pipeline pipes[4] = {VS_PIPELINE_PRE, VS_PIPELINE_POST_CD, VS_PIPELINE_POST_GS, VS_PIPELINE_POST_ALPHA};
    for (int i = 0; i < 4; i++)
        for (int persp = 0; persp < 2; persp++) {
            vs_settings c = s;
            c.pipeline = pipes[i];
            c.azimuth = persp ? 250 : 60;
            c.elevation = 20;
            c.perspective_fov = persp ? 40 : 0;
            char what[64];
            snprintf(what, sizeof what, "%s %s", vs_pipeline_name(pipes[i]), persp ? "perspective" : "orthographic");
            check_case(ctx, vol, c, what);
        }
    vs_volume_release(vol);
    vs_context_release(ctx);
    TEST_DONE();
}
