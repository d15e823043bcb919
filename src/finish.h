/* The final per-pixel step shared by the ray caster and every splatting
 * pipeline, so that their images agree exactly on background handling. */
#ifndef VS_FINISH_H
#define VS_FINISH_H

/* acc: front-to-back accumulated colour C (premultiplied) and opacity A.
 * bg: straight RGBA background.  The background shows through the remaining
 * transparency (1-A):
 *     out_rgb = C + (1-A) * bg_rgb * bg_a      (premultiplied)
 *     out_a   = A + (1-A) * bg_a
 * and is stored straight: out_rgb / out_a (0 where out_a = 0). */
static inline void vs_finish_pixel(const float acc[4], const float bg[4], float out[4])
{
    float t = 1.0f - acc[3];
    float a = acc[3] + t * bg[3];
    for (int c = 0; c < 3; c++) {
        float rgb = acc[c] + t * bg[c] * bg[3];
        out[c] = a > 0.0f ? rgb / a : 0.0f;
    }
    out[3] = a;
}

#endif
