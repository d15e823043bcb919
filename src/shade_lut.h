/* Normalisation and shading through lookup tables (paper §4.2): Clyne-Dennis
 * spherical angles (eqs. 10-11) from a gradient quantised to signed bytes,
 * and a shading table indexed by the two angles.  No square root, no pow. */
#ifndef VS_SHADE_LUT_H
#define VS_SHADE_LUT_H

#include "light.h"

#include <float.h>
#if defined(__x86_64__) || defined(__SSE__)
#include <xmmintrin.h>
#endif

/* lrintf for |v| <= 127 (never NaN): round to nearest, ties to even, in
 * the current rounding mode.  With errno-setting maths lrintf is a library
 * call; on x86 this is one cvtss2si, the same result. */
static inline int vs_round_byte(float v)
{
#if defined(__x86_64__) || defined(__SSE__)
    return _mm_cvtss_si32(_mm_set_ss(v));
#else
    return (int)lrintf(v);
#endif
}

typedef struct vs_shade_lut {
    int nl, np;              /* longitude bins (lambda), latitude bins (phi) */
    uint16_t *lambda_bin;    /* [255*255]: (gy+127, gx+127) -> lambda bin     */
    uint8_t *radius;         /* [255*255]: sqrt(gx^2+gy^2) rounded, 0..180   */
    uint16_t *phi_bin;       /* [255*181]: (gz+127, r) -> phi bin             */
    float *diffuse;          /* [np*nl]                                        */
    float *specular;         /* [np*nl]                                        */
    vs_light light;          /* what diffuse and specular were built for       */
} vs_shade_lut;

/* Builds the tables into `lut`, which is zeroed or holds earlier tables:
 * those are kept when nl is the same, and the shading table too when the
 * light is (a context keeps one lut across frames, see vs_context). */
vs_status vs_shade_lut_setup(vs_context *ctx, int nl, const vs_light *light, vs_shade_lut *lut);
void vs_shade_lut_free(vs_shade_lut *lut);

/* The first step of vs_shade_lut_eval: the gradient quantised to signed
 * bytes, as the (gy, gx) cell of lambda_bin and radius (returned) and the
 * gz row of phi_bin (*zrow).  Split out so that a batch can issue each
 * level of the dependent table look-ups for all its members at once. */
static inline int vs_shade_lut_cell(float gx, float gy, float gz, int *zrow)
{
    float ax = gx < 0 ? -gx : gx, ay = gy < 0 ? -gy : gy, az = gz < 0 ? -gz : gz;
    float m = ax > ay ? ax : ay;
    if (az > m) m = az;
    /* As in vs_light_eval: a NaN or infinite component (densities that
     * overflowed float) has no direction, and a gradient under 1e-30 counts
     * as zero (127/m would overflow to inf below 3.7e-37); both face the
     * eye.  Without this, lrintf gets NaN or inf, whose result is
     * unspecified and would index outside the tables. */
    if (!(ax <= FLT_MAX && ay <= FLT_MAX && az <= FLT_MAX) || !(m >= 1e-30f)) m = 0.0f;
    int ix = 0, iy = 0, iz = 0;
    if (m > 0.0f) { /* quantise to signed bytes by the largest component */
        float k = 127.0f / m;
        ix = vs_round_byte(gx * k);
        iy = vs_round_byte(gy * k);
        iz = vs_round_byte(gz * k);
    }
    if (ix == 0 && iy == 0 && iz == 0) iz = -127; /* zero gradient: faces the eye */
    *zrow = (iz + 127) * 181;
    return (iy + 127) * 255 + (ix + 127);
}

/* Shade a gradient (eye frame, any scale) through the tables. */
static inline void vs_shade_lut_eval(const vs_shade_lut *lut, float gx, float gy, float gz,
                                     float *diffuse, float *specular)
{
    int zrow;
    const int cell = vs_shade_lut_cell(gx, gy, gz, &zrow);
    int li = lut->lambda_bin[cell];
    int r = lut->radius[cell];
    int pi = lut->phi_bin[zrow + r];
    *diffuse = lut->diffuse[pi * lut->nl + li];
    *specular = lut->specular[pi * lut->nl + li];
}

#endif
