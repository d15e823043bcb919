/* The shading stage (shade.c, shade_preint.c): splat weights of voxels, and per sheet the
 * colours of the classified pixels; one function per pipeline, chosen by
 * pipeline.c. */
#ifndef VS_SHADE_H
#define VS_SHADE_H

#include "tile.h"

#include <float.h>

/* Splat weights (the pipeline table's `weights`). */
void vs_weights_density(const vs_frame *F, const pend *p, unsigned live, float w[][4]);
void vs_weights_pre(const vs_frame *F, const pend *p, unsigned live, float w[][4]);
void vs_weights_post_alpha(const vs_frame *F, const pend *p, unsigned live, float w[][4]);

/* Per sheet (the pipeline table's `shade`). */
void vs_shade_post_lut(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
void vs_shade_post_exact(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
void vs_shade_post_preint(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
void vs_shade_pre(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
void vs_shade_post_alpha(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
void vs_shade_post_alpha_preint(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
/* The Phong terms of a view-space gradient (per pixel, per pixel, per view
 * unit): brought to the eye frame per mm, then the exact light model
 * (--exact-normals) or the normal LUT. */
static inline void vs_shade_gradient(const vs_frame *F, float gx, float gy, float gz, float *d, float *sp)
{
    const float ppm = (float)F->cam.px_per_mm, zpm = (float)F->cam.z_per_mm;
    gx *= ppm;
    gy *= ppm;
    gz *= zpm;
    if (F->s->exact_normals) {
        double n[3] = {gx, gy, gz}, dd, ss;
        vs_light_eval(&F->light, n, &dd, &ss);
        *d = (float)dd;
        *sp = (float)ss;
    } else {
        vs_shade_lut_eval(&F->lut, gx, gy, gz, d, sp);
    }
}

/* Post-alpha's light terms at a sheet pixel q4 (splatted diffuse and
 * specular times opacity, the opacity, the density): the splatted terms
 * over the splatted opacity, or (d0, s0), the light facing the eye, where
 * no opaque voxel is near (vs_post_alpha_eye gives them once a sheet). */
static inline void vs_post_alpha_terms(const float *q4, float d0, float s0, float *d, float *s)
{
    const float a = q4[2];
    if (a > 1e-30f && a <= FLT_MAX) {
        *d = q4[0] / a;
        *s = q4[1] / a;
    } else {
        *d = d0;
        *s = s0;
    }
}
static inline void vs_post_alpha_eye(const vs_frame *F, float *d0, float *s0)
{
    double n[3] = {0.0, 0.0, 0.0}, dd, ss;
    vs_light_eval(&F->light, n, &dd, &ss);
    *d0 = (float)dd;
    *s0 = (float)ss;
}

/* After any of them, with perspective: each pixel's opacity for the
 * length of its ray through the slab. */
void vs_perspective_opacity(const tile_ctx *t, const spans *r, float *alpha);

#endif
