/* Classification: iso-range with a linear opacity ramp (the paper's model) or
 * a piecewise-linear 1-D colour/opacity function, tabulated for speed. */
#include "classify.h"
#include "context.h"
#include "volume.h"

#include <math.h>
#include <string.h>

static double iso_alpha(const vs_classify *c, double v, double peak)
{
    double a;
    if (c->ramp > 0) {
        a = (v - (c->lo - c->ramp)) / (2.0 * c->ramp);
        if (isfinite(c->hi)) {
            double b = ((c->hi + c->ramp) - v) / (2.0 * c->ramp);
            if (b < a) a = b;
        }
    } else {
        a = (v >= c->lo && v <= c->hi) ? 1.0 : 0.0;
    }
    if (!(a > 0.0)) return 0.0;
    if (a > 1.0) a = 1.0;
    return a * peak;
}

void vs_classify_eval(const vs_classify *c, const vs_settings *s, double v, float rgb[3], float *alpha)
{
    if (!c->use_points) {
        rgb[0] = s->material[0];
        rgb[1] = s->material[1];
        rgb[2] = s->material[2];
        *alpha = (float)iso_alpha(c, v, s->iso_opacity);
        return;
    }
    const vs_tf_point *p = s->tf;
    int n = s->tf_count;
    const vs_tf_point *a = &p[0], *b = &p[0];
    if (v <= p[0].value) {
        a = b = &p[0];
    } else if (v >= p[n - 1].value) {
        a = b = &p[n - 1];
    } else {
        for (int i = 1; i < n; i++)
            if (v <= p[i].value) {
                a = &p[i - 1];
                b = &p[i];
                break;
            }
    }
    double t = (b->value > a->value) ? (v - a->value) / (b->value - a->value) : 0.0;
    rgb[0] = (float)(a->r + t * (b->r - a->r));
    rgb[1] = (float)(a->g + t * (b->g - a->g));
    rgb[2] = (float)(a->b + t * (b->b - a->b));
    *alpha = (float)(a->a + t * (b->a - a->a));
}

vs_status vs_classify_setup(vs_context *ctx, const struct vs_volume *vol, const vs_settings *s,
                            vs_classify *c)
{
    memset(c, 0, sizeof *c);
    double range = vol->vmax - vol->vmin;
    if (s->tf_count < 0)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "transfer function: %d points", s->tf_count);
    if (s->tf_count > 0) {
        if (!s->tf) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "transfer function: NULL points");
        for (int i = 0; i < s->tf_count; i++) {
            const vs_tf_point *p = &s->tf[i];
            if (!isfinite(p->value) || !(p->a >= 0.0f && p->a <= 1.0f) || !(p->r >= 0.0f && p->r <= 1.0f) ||
                !(p->g >= 0.0f && p->g <= 1.0f) || !(p->b >= 0.0f && p->b <= 1.0f))
                return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                                    "transfer function: point %d is not finite or outside [0,1]", i);
            if (i > 0 && p->value < s->tf[i - 1].value)
                return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                                    "transfer function: point %d is out of order", i);
        }
        c->use_points = 1;
        c->lo = s->tf[0].value;
        c->hi = s->tf[s->tf_count - 1].value;
        c->ramp = 0.0;
    } else {
        double lo = s->iso_lo;
        if (!s->has_iso) {
            if (ctx->otsu_serial != vol->serial) {
                ctx->otsu_iso = vs_volume_default_iso(vol);
                ctx->otsu_serial = vol->serial;
            }
            lo = ctx->otsu_iso;
        }
        double hi = s->has_iso ? s->iso_hi : INFINITY;
        if (!s->has_iso && isfinite(vol->default_iso)) lo = vol->default_iso;
        if (isnan(lo) || isnan(hi))
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "iso-range is NaN");
        if (hi < lo)
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "iso-range %g:%g is empty (HI < LO)", lo, hi);
        double ramp = s->ramp;
        if (ramp < 0) ramp = isfinite(vol->default_ramp) && !s->has_iso ? vol->default_ramp : 0.02 * range;
        if (!isfinite(ramp)) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "ramp must be finite");
        if (!(s->iso_opacity >= 0.0f && s->iso_opacity <= 1.0f))
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "iso opacity must lie in [0,1]");
        c->lo = lo;
        c->hi = hi;
        c->ramp = ramp;
    }
    /* Reconstructed values span the data range and, at the edges of the
     * relevant set where the kernel runs out of voxels, fall towards 0, and
     * a normalized kernel overshoots slightly: cover all of that. */
    double lo = vol->vmin < 0.0 ? vol->vmin : 0.0, hi = vol->vmax > 0.0 ? vol->vmax : 0.0;
    double pad = 0.05 * (hi > lo ? hi - lo : 1.0);
    c->vmin = lo - pad;
    c->vmax = hi + pad;
    c->scale = (VS_TF_TABLE - 1) / (c->vmax - c->vmin);
    for (int i = 0; i < VS_TF_TABLE; i++) {
        double v = c->vmin + i / c->scale;
        vs_classify_eval(c, s, v, c->color[i], &c->alpha[i]);
    }
    /* Values whose opacity can be non-zero: the relevant range. */
    if (c->use_points) {
        int first = -1, last = -1;
        for (int i = 0; i < s->tf_count; i++)
            if (s->tf[i].a > 0.0f) {
                if (first < 0) first = i;
                last = i;
            }
        if (first < 0) {
            c->alpha_lo = INFINITY;
            c->alpha_hi = -INFINITY;
        } else {
            c->alpha_lo = first > 0 ? s->tf[first - 1].value : -INFINITY;
            c->alpha_hi = last < s->tf_count - 1 ? s->tf[last + 1].value : INFINITY;
        }
    } else {
        c->alpha_lo = c->lo - c->ramp;
        c->alpha_hi = c->hi + c->ramp;
        if (s->iso_opacity <= 0.0f) {
            c->alpha_lo = INFINITY;
            c->alpha_hi = -INFINITY;
        }
    }
    return VS_OK;
}
