/* Shading with pre-integration (post-cd, post-gs, post-alpha;
 * preintegrate.h): a pixel of sheet k stands for the ray segment to sheet
 * k + 1, taken as two halves split at a middle density.  Each half emits
 * the table's colour (premultiplied by its opacity) times the Phong terms
 * of the gradients at its ends (sheet k's and the middle's, the middle's
 * and sheet k + 1's), averaged; the halves are composited front over back.
 * Lighting each half from both its ends, rather than the whole segment
 * from sheet k, keeps a thin layer from showing as rings.  (Mixing the
 * gradients instead of their terms measured 0.5-0.6 dB worse on the
 * translucent head; weighting each half's ends by where its opacity lies
 * measured within 0.2 dB of the mean on the heads and the engine and cost
 * a second table.)  Post-alpha mixes its splatted light terms the same
 * way.
 *
 * The live pixels of a span are gathered into batches: table look-ups and
 * the three gradients per pixel, then their Phong terms through the normal
 * LUT in one SIMD call (kernels.h shade_terms), then the mix. */
#include "shade.h"
#include "preintegrate.h"

#include <float.h>

enum { BATCH = 64 };

typedef struct batch {
    int n;
    int per;                   /* gradients a pixel: 3, or 1 where the ends
                                  are not mixed (perspective)              */
    int o[BATCH];              /* pixel in the tile's shade buffers          */
    float e[BATCH][8];         /* front half, back half: opacity, r g b      */
    float g[3 * BATCH * 3];    /* gradients at sheet k, the middle, sheet k + 1 */
    float d[3 * BATCH], s[3 * BATCH];
} batch;

/* The exact-normals path: the light model on each gradient (as shade.c's
 * shade_gradient: view space to the eye frame per mm, in float). */
static void terms_exact(const vs_frame *F, batch *B)
{
    const float ppm = (float)F->cam.px_per_mm, zpm = (float)F->cam.z_per_mm;
    for (int i = 0; i < B->per * B->n; i++) {
        const float *g = B->g + 3 * i;
        double n[3] = {g[0] * ppm, g[1] * ppm, g[2] * zpm}, dd, ss;
        vs_light_eval(&F->light, n, &dd, &ss);
        B->d[i] = (float)dd;
        B->s[i] = (float)ss;
    }
}

/* A pixel's colour from its two halves e (front: opacity, premultiplied
 * r g b; back: the same), each lit by Phong terms d, s: the halves front
 * over back, over their joint opacity. */
static inline void emit_halves(const float e[8], float d1, float s1, float d2, float s2, float c[3])
{
    const float a1 = e[0], a2 = e[4], A = vs_preint_over(a1, a2);
    float inv = A > 0.0f ? 1.0f / A : 0.0f;
    if (!(inv <= FLT_MAX)) inv = 0.0f; /* an opacity under 1/FLT_MAX emits nothing */
    for (int i = 0; i < 3; i++) c[i] = ((e[1 + i] * d1 + a1 * s1) + (1.0f - a1) * (e[5 + i] * d2 + a2 * s2)) * inv;
}

/* Each half lit by the mean of the terms at its ends: the front half by
 * sheet k's (d[0], s[0]) and the middle's (d[1], s[1]), the back half by
 * the middle's and sheet k + 1's (d[2], s[2]). */
static inline void emit_mixed(const float e[8], const float d[3], const float s[3], float c[3])
{
    emit_halves(e, 0.5f * (d[0] + d[1]), 0.5f * (s[0] + s[1]), 0.5f * (d[1] + d[2]), 0.5f * (s[1] + s[2]), c);
}

static void flush(const vs_frame *F, const sheet_view *sv, batch *B, float *out)
{
    if (!B->n) return;
    if (F->s->exact_normals)
        terms_exact(F, B);
    else
        F->kern.shade_terms(B->d, B->s, B->g, B->per * B->n, sv->tabs);
    for (int j = 0; j < B->n; j++) {
        const float *d = B->d + B->per * j, *sp = B->s + B->per * j;
        if (B->per == 3)
            emit_mixed(B->e[j], d, sp, out + 3 * B->o[j]);
        else
            emit_halves(B->e[j], d[0], sp[0], d[0], sp[0], out + 3 * B->o[j]);
    }
    B->n = 0;
}

void vs_shade_post_preint(const tile_ctx *t, const sheet_view *sv, shade_buf sb)
{
    const vs_frame *F = t->F;
    const vs_preint *P = F->preint;
    const spans *sp = sv->sp;
    const int gs = F->stages->gradient_splats;
    /* with perspective the sheets' gradients are not on one scale along
     * the ray: each sheet is lit by its own, one gradient a pixel */
    const int mix = !F->cam.persp;
    const float slab = (float)F->fp.slab, base = (float)F->base;
    const ptrdiff_t st = t->stride;
    batch B;
    B.n = 0;
    B.per = mix ? 3 : 1;
    for (int y = sp->y0; y < sp->y1; y++)
        for (int x = sp->xa[y]; x < sp->xb[y]; x++) {
            const int o = (y - 1) * t->tw + (x - 1);
            const size_t b = (size_t)y * t->stride + x;
            if (!(sb.alpha[o] > 0.0f)) continue;
            const float *g0 = sb.g + 3 * o;
            float qf, qb, m;
            if (gs) {
                qf = sv->q[4 * b];
                qb = sv->next[4 * b];
                m = vs_preint_mid_gs(sv->q + 4 * b, sv->next + 4 * b);
            } else {
                qf = sv->q[b];
                qb = sv->next[b];
                m = vs_preint_mid_cd(sv->prev[b], qf, qb);
            }
            float *e = B.e[B.n], *gk = B.g + 3 * B.per * B.n;
            vs_preint_halves(P, qf + base, m + base, qb + base, e);
            for (int i = 0; i < 3; i++) gk[i] = g0[i];
            if (mix) {
                float *gm = gk + 3, *g1 = gk + 6;
                /* sheet k + 1's gradient: post-gs splatted it; post-cd takes
                 * central differences there too (sheets k and k + 2), and at
                 * the middle the difference across the segment, each depth
                 * difference centred where it is used (one-sided ones, or
                 * the ends' mean at the middle, measured 0.7 dB worse on the
                 * translucent head) */
                if (gs) {
                    for (int i = 0; i < 3; i++) g1[i] = sv->next[4 * b + 1 + i] / slab;
                    for (int i = 0; i < 3; i++) gm[i] = 0.5f * (g0[i] + g1[i]);
                } else {
                    const float *n = sv->next + b;
                    g1[0] = 0.5f * (n[1] - n[-1]);
                    g1[1] = 0.5f * (n[st] - n[-st]);
                    g1[2] = (sv->next2[b] - qf) / (2.0f * slab);
                    gm[0] = 0.5f * (g0[0] + g1[0]);
                    gm[1] = 0.5f * (g0[1] + g1[1]);
                    gm[2] = (qb - qf) / slab;
                }
            }
            B.o[B.n++] = o;
            if (B.n == BATCH) flush(F, sv, &B, sb.g);
        }
    flush(F, sv, &B, sb.g);
}

/* Post-alpha with pre-integration: the segment to the next sheet in two
 * halves as above, lit by the splatted light terms of sheet k, of sheet
 * k + 1 and their mean at the middle, each half by the mean of its two. */
void vs_shade_post_alpha_preint(const tile_ctx *t, const sheet_view *sv, shade_buf sb)
{
    const vs_frame *F = t->F;
    const vs_preint *P = F->preint;
    const spans *sp = sv->sp;
    const float base = (float)F->base;
    float d0, s0;
    vs_post_alpha_eye(F, &d0, &s0);
    for (int y = sp->y0; y < sp->y1; y++)
        for (int x = sp->xa[y]; x < sp->xb[y]; x++) {
            const int o = (y - 1) * t->tw + (x - 1);
            const size_t b = 4 * ((size_t)y * t->stride + x);
            if (!(sb.alpha[o] > 0.0f)) continue;
            const float *q = sv->q + b, *qn = sv->next + b;
            const float m = vs_preint_mid_cd(sv->prev[b + 3], q[3], qn[3]);
            float e[8], dk, sk, dn, sn;
            vs_preint_halves(P, q[3] + base, m + base, qn[3] + base, e);
            vs_post_alpha_terms(q, d0, s0, &dk, &sk);
            vs_post_alpha_terms(qn, d0, s0, &dn, &sn);
            const float d[3] = {dk, 0.5f * (dk + dn), dn}, s[3] = {sk, 0.5f * (sk + sn), sn};
            emit_mixed(e, d, s, sb.g + 3 * o);
        }
}
