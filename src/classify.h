/* Classification: the transfer function as tables of colour and opacity
 * per unit length over the volume's value range. */
#ifndef VS_CLASSIFY_H
#define VS_CLASSIFY_H

#include "volume.h"
#include <math.h>

#define VS_TF_TABLE 4096
typedef struct vs_classify {
    double lo, hi, ramp;   /* iso-range in use (hi may be +INF)               */
    double vmin, vmax;     /* domain of the table                             */
    double scale;          /* (VS_TF_TABLE-1)/(vmax-vmin)                     */
    float color[VS_TF_TABLE][3];
    float alpha[VS_TF_TABLE]; /* opacity per view unit                        */
    double alpha_lo, alpha_hi; /* values outside which alpha is 0: relevant range */
    int use_points;        /* piecewise-linear function given                 */
} vs_classify;

/* Build from settings and the volume (iso from histogram if not given). */
vs_status vs_classify_setup(vs_context *ctx, const struct vs_volume *vol,
                            const vs_settings *s, vs_classify *c);
/* Exact evaluation (no table): opacity per unit length and colour. */
void vs_classify_eval(const vs_classify *c, const vs_settings *s, double value,
                      float rgb[3], float *alpha);
/* Table lookup (linear interpolation; clamps outside the domain). */
/* Any table over the classification's domain (the opacity, or the
 * frame's slab-corrected copy of it) at a value. */
static inline float vs_classify_lookup(const vs_classify *c, const float *table, float value)
{
    float x = (float)((value - c->vmin) * c->scale);
    if (!(x > 0.0f)) x = 0.0f; /* also catches NaN */
    if (x >= (float)(VS_TF_TABLE - 1)) return table[VS_TF_TABLE - 1];
    int i = (int)x;
    float f = x - (float)i;
    return table[i] + f * (table[i + 1] - table[i]);
}
static inline float vs_classify_alpha(const vs_classify *c, float value)
{
    return vs_classify_lookup(c, c->alpha, value);
}
/* Opacity for a sample of length `len` view units: 1-(1-a)^len. */
static inline double vs_opacity_correct(double a, double len)
{
    if (a <= 0.0) return 0.0;
    if (a >= 1.0) return 1.0;
    return 1.0 - pow(1.0 - a, len);
}

#endif
