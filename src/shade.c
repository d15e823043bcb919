/* Shading: voxels before splatting (pre: classified colour times the
 * Phong terms of the reconstruction's gradient at the voxel,
 * voxel_gradient.h; post-alpha: those terms alone) and
 * sheet pixels after classification (post-shaded: the Phong terms of the
 * sheet's gradient, by the Clyne-Dennis tables or exact, times the colour
 * table, or with pre-integration shade_preint.c's; pre: the splatted colour
 * divided by the splatted opacity; post-alpha: the splatted light terms
 * divided by the splatted opacity, times the classified colour).  The
 * light model is light.c's, the tables shade_lut.c's. */
#include "shade.h"
#include "normal_code.h"

#include <float.h>
#include <stdatomic.h>
#include <math.h>

static inline void lookup_color(const vs_frame *F, float v, float rgb[3])
{
    const vs_classify *c = F->cls;
    float x = (float)((v - c->vmin) * c->scale);
    if (!(x > 0.0f)) x = 0.0f; /* also NaN */
    if (x >= (float)(VS_TF_TABLE - 1)) x = (float)(VS_TF_TABLE - 1); /* also +inf: no int overflow */
    int i = (int)x;
    if (i >= VS_TF_TABLE - 1) {
        rgb[0] = c->color[VS_TF_TABLE - 1][0];
        rgb[1] = c->color[VS_TF_TABLE - 1][1];
        rgb[2] = c->color[VS_TF_TABLE - 1][2];
        return;
    }
    float f = x - (float)i;
    for (int ch = 0; ch < 3; ch++) rgb[ch] = c->color[i][ch] + f * (c->color[i + 1][ch] - c->color[i][ch]);
}

static inline float pre_opacity(const vs_frame *F, float a)
{
    if (!(a > 0.0f)) return 0.0f;
    if (a >= 1.0f) return F->opacity_corr[1024];
    float x = a * 1024.0f;
    int i = (int)x;
    float f = x - (float)i;
    return F->opacity_corr[i] + f * (F->opacity_corr[i + 1] - F->opacity_corr[i]);
}

/* Splat weights of the voxels p[lane], lane in the mask `live` (at most
 * VS_PLACE_BATCH), from their linear index in the volume: density (post),
 * or classified colour times the Phong terms of its gradient
 * (pre-shading: once per voxel and view). */
void vs_weights_density(const vs_frame *F, const pend *p, unsigned live, float w[][4])
{
    const float bscale = (float)(F->fp.b / F->fp.slab);
    for (unsigned m = live; m; m &= m - 1) {
        const int l = __builtin_ctz(m);
        w[l][0] = vs_volume_density_above(F->vol, p[l].v, F->base) * bscale;
        w[l][1] = w[l][2] = w[l][3] = 0.0f;
    }
}

/* The Phong terms of voxel e.  Table normals:
 * the view's terms of its normal code, which a context keeps per voxel
 * once the first frame that splats the voxel has computed it (codes are
 * stored plus one, 0 meaning not yet; every thread computes the same code,
 * so a race only repeats the work); exact normals: the voxel's gradient
 * (voxel_gradient.h) rotated into the eye frame and the light evaluated. */
static inline void voxel_light(const vs_frame *F, const pend *e, float *d, float *sp)
{
    const uint32_t v = e->v;
    if (F->ncode) {
        unsigned c = atomic_load_explicit(&F->ncode[e->c], memory_order_relaxed);
        if (c) {
            *d = F->nterms[c - 1][0];
            *sp = F->nterms[c - 1][1];
            return;
        }
    }
    if (F->nterms) {
        const int c = vs_voxel_normal_code(F->vol, F->nscale, v);
        if (F->ncode) atomic_store_explicit(&F->ncode[e->c], (uint16_t)(c + 1), memory_order_relaxed);
        *d = F->nterms[c][0];
        *sp = F->nterms[c][1];
        return;
    }
    const vs_camera *cam = &F->cam;
    float g[3];
    vs_voxel_gradient(F->vol, v, g);
    double gw[3] = {g[0] / F->spacing[0], g[1] / F->spacing[1], g[2] / F->spacing[2]};
    double n[3] = {gw[0] * cam->right[0] + gw[1] * cam->right[1] + gw[2] * cam->right[2],
                   -(gw[0] * cam->up[0] + gw[1] * cam->up[1] + gw[2] * cam->up[2]),
                   gw[0] * cam->dir[0] + gw[1] * cam->dir[1] + gw[2] * cam->dir[2]};
    double dd, ss;
    vs_light_eval(&F->light, n, &dd, &ss);
    *d = (float)dd;
    *sp = (float)ss;
}

/* Pre-shaded: w[3] is the opacity (pre) or the density (post-alpha, which
 * classifies the splatted density on the sheet). */
static inline void weights_shaded(const vs_frame *F, const pend *p, unsigned live, float w[][4], int opacity)
{
    const float bscale = (float)(F->fp.b / F->fp.slab);
    for (unsigned m = live; m; m &= m - 1) {
        const int l = __builtin_ctz(m);
        const uint32_t v = p[l].v;
        const float val = vs_volume_density(F->vol, v);
        const float alpha = vs_classify_alpha(F->cls, val);
        float d, sp;
        voxel_light(F, &p[l], &d, &sp);
        if (opacity) {
            float rgb[3];
            lookup_color(F, val, rgb);
            for (int c = 0; c < 3; c++) w[l][c] = (rgb[c] * d + sp) * alpha * bscale;
            w[l][3] = alpha * bscale;
        } else { /* post-alpha: the light's terms, opacity-weighted, and the density */
            w[l][0] = d * alpha * bscale;
            w[l][1] = sp * alpha * bscale;
            w[l][2] = alpha * bscale;
            w[l][3] = (float)(val - F->base) * bscale;
        }
    }
}

void vs_weights_pre(const vs_frame *F, const pend *p, unsigned live, float w[][4])
{
    weights_shaded(F, p, live, w, 1);
}

void vs_weights_post_alpha(const vs_frame *F, const pend *p, unsigned live, float w[][4])
{
    weights_shaded(F, p, live, w, 0);
}

/* Perspective: a slab is crossed by the pixel's ray over its thickness
 * times the ray's length per unit depth, so its opacity grows to
 * 1 - (1 - a)^len (the ray caster steps the same way). */
void vs_perspective_opacity(const tile_ctx *t, const spans *r, float *alpha)
{
    const vs_camera *cam = &t->F->cam;
    for (int y = r->y0; y < r->y1; y++)
        for (int x = r->xa[y]; x < r->xb[y]; x++) {
            float *a = alpha + vs_own(t, x, y);
            if (!(*a > 0.0f && *a < 1.0f)) continue;
            const float len = (float)vs_camera_ray_length(cam, x + t->ox, y + t->oy);
            *a = 1.0f - powf(1.0f - *a, len);
        }
}

/* Post-shaded, lookup tables: a kernel per span (simd/kernels.h). */
void vs_shade_post_lut(const tile_ctx *t, const sheet_view *sv, shade_buf sb)
{
    const vs_frame *F = t->F;
    const spans *sp = sv->sp;
    const int ch = F->stages->ch;
    for (int y = sp->y0; y < sp->y1; y++) {
        if (sp->xa[y] == sp->xb[y]) continue;
        int o = vs_own(t, sp->xa[y], y);
        size_t b = (size_t)y * t->stride + sp->xa[y];
        F->kern.shade_lut(sb.g + 3 * o, sb.alpha + o, sv->q + ch * b, ch, sp->xb[y] - sp->xa[y], sv->tabs);
    }
}

/* Post-shaded, exact normals: the light evaluated per pixel. */
void vs_shade_post_exact(const tile_ctx *t, const sheet_view *sv, shade_buf sb)
{
    const vs_frame *F = t->F;
    const spans *sp = sv->sp;
    const int ch = F->stages->ch;
    for (int y = sp->y0; y < sp->y1; y++)
        for (int x = sp->xa[y]; x < sp->xb[y]; x++) {
            int o = vs_own(t, x, y);
            size_t b = (size_t)y * t->stride + x;
            if (!(sb.alpha[o] > 0.0f)) continue;
            float *c = sb.g + 3 * o;
            float d, spec, rgb[3];
            vs_shade_gradient(F, c[0], c[1], c[2], &d, &spec);
            lookup_color(F, sv->q[ch * b] + (float)F->base, rgb);
            c[0] = rgb[0] * d + spec;
            c[1] = rgb[1] * d + spec;
            c[2] = rgb[2] * d + spec;
        }
}

/* Pre-shaded: opacity-weighted colour / interpolated opacity, and the
 * opacity corrected for the slab. */
void vs_shade_pre(const tile_ctx *t, const sheet_view *sv, shade_buf sb)
{
    const vs_frame *F = t->F;
    const spans *sp = sv->sp;
    const float *q = sv->q;
    for (int y = sp->y0; y < sp->y1; y++)
        for (int x = sp->xa[y]; x < sp->xb[y]; x++) {
            int o = vs_own(t, x, y);
            size_t b = (size_t)y * t->stride + x;
            float a = sb.alpha[o];
            if (!(a > 0.0f)) continue;
            float *c = sb.g + 3 * o;
            /* an opacity so small that its inverse overflows (a transfer
             * function whose opacity rises over 1e39 units) shows nothing:
             * colour 0, not inf * 0 = NaN */
            float inv = 1.0f / a;
            if (!(inv <= FLT_MAX)) inv = 0.0f;
            float cr = q[4 * b] * inv, cg = q[4 * b + 1] * inv, cb = q[4 * b + 2] * inv;
            c[0] = cr > 1.0f ? 1.0f : cr;
            c[1] = cg > 1.0f ? 1.0f : cg;
            c[2] = cb > 1.0f ? 1.0f : cb;
            sb.alpha[o] = pre_opacity(F, a);
        }
}

/* Pre-shaded, post-classified opacity (Wittenbrink et al.'s
 * opacity-weighted interpolation): the voxels' diffuse and specular terms
 * were splatted weighted by their opacity, so dividing by the splatted
 * opacity gives the light the opaque voxels see, undarkened where the
 * kernel straddles an edge; the material colour is classified from the
 * splatted density, as the opacity is, so that a thin translucent layer
 * keeps its own colour beside an opaque one. */
void vs_shade_post_alpha(const tile_ctx *t, const sheet_view *sv, shade_buf sb)
{
    const vs_frame *F = t->F;
    const spans *sp = sv->sp;
    const float *q = sv->q;
    float d0, s0;
    vs_post_alpha_eye(F, &d0, &s0);
    for (int y = sp->y0; y < sp->y1; y++)
        for (int x = sp->xa[y]; x < sp->xb[y]; x++) {
            int o = vs_own(t, x, y);
            size_t b = (size_t)y * t->stride + x;
            if (!(sb.alpha[o] > 0.0f)) continue;
            float *c = sb.g + 3 * o;
            float d, spec, rgb[3];
            vs_post_alpha_terms(q + 4 * b, d0, s0, &d, &spec);
            lookup_color(F, q[4 * b + 3] + (float)F->base, rgb);
            for (int i = 0; i < 3; i++) c[i] = rgb[i] * d + spec;
        }
}
