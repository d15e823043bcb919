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
 * way.  Perspective views too (lighting each segment by sheet k's
 * gradient alone there measured 2.6 dB worse for post-cd, 4.5 post-gs, on
 * the translucent head at 30 degrees).
 *
 * A row is taken CHUNK pixels at a time: the live ones are listed, their
 * middle's and sheet k + 1's gradients lit together (one shade_terms call
 * through the normal LUT, kernels.h, or the exact light model), then each
 * pixel's table look-ups and mix.  Sheet k's terms are those shading
 * sheet k - 1 took for its k + 1, where that pixel was live there (97 % of
 * them on the translucent head; the others' are lit in a second call), so
 * most pixels light two gradients, not three.  (The middle's terms cannot be the mean
 * of the ends': 2.7 dB worse for post-cd on the translucent head, 2.3
 * post-gs.) */
#include "shade.h"
#include "preintegrate.h"
#include "sheet_classify.h"
#include "gs_ripple.h"

#include <float.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* Phong terms d, s of n gradients g (3 floats each): the normal LUT by
 * the kernels, or the exact light model one gradient at a time */
static void light_terms(const vs_frame *F, const sheet_view *sv, float *d, float *s, const float *g, int n)
{
    if (!n) return;
    if (!F->s->exact_normals) {
        F->kern.shade_terms(d, s, g, n, sv->tabs);
        return;
    }
    for (int i = 0; i < n; i++) vs_shade_gradient(F, g[3 * i], g[3 * i + 1], g[3 * i + 2], &d[i], &s[i]);
}

/* 1 over the joint opacity of two halves (0 where it emits nothing: an
 * opacity of 0, or under 1/FLT_MAX) */
static inline float inv_opacity(float a1, float a2)
{
    const float A = vs_preint_over(a1, a2);
    const float inv = A > 0.0f ? 1.0f / A : 0.0f;
    return inv <= FLT_MAX ? inv : 0.0f;
}

/* A pixel's colour from its two halves e (front: opacity, premultiplied
 * r g b; back: the same), each lit by Phong terms d, s: the halves front
 * over back, over their joint opacity. */
static inline void emit_halves(const float e[8], float d1, float s1, float d2, float s2, float c[3])
{
    const float a1 = e[0], a2 = e[4], inv = inv_opacity(a1, a2);
#if defined(__SSE2__)
    /* the same operations, a lane a channel (lane 0, the opacity's, unused) */
    const __m128 f = _mm_add_ps(_mm_mul_ps(_mm_loadu_ps(e), _mm_set1_ps(d1)), _mm_set1_ps(a1 * s1));
    const __m128 b = _mm_add_ps(_mm_mul_ps(_mm_loadu_ps(e + 4), _mm_set1_ps(d2)), _mm_set1_ps(a2 * s2));
    __m128 v = _mm_mul_ps(_mm_add_ps(f, _mm_mul_ps(_mm_set1_ps(1.0f - a1), b)), _mm_set1_ps(inv));
    v = _mm_shuffle_ps(v, v, _MM_SHUFFLE(0, 3, 2, 1));
    _mm_storel_pi((__m64 *)(void *)c, v); /* c[3] is the next pixel's */
    _mm_store_ss(c + 2, _mm_movehl_ps(v, v));
#else
    for (int i = 0; i < 3; i++) c[i] = ((e[1 + i] * d1 + a1 * s1) + (1.0f - a1) * (e[5 + i] * d2 + a2 * s2)) * inv;
#endif
}

/* Each half lit by the mean of the terms at its ends: the front half by
 * sheet k's (d[0], s[0]) and the middle's (d[1], s[1]), the back half by
 * the middle's and sheet k + 1's (d[2], s[2]). */
static inline void emit_mixed(const float e[8], const float d[3], const float s[3], float c[3])
{
    emit_halves(e, 0.5f * (d[0] + d[1]), 0.5f * (s[0] + s[1]), 0.5f * (d[1] + d[2]), 0.5f * (s[1] + s[2]), c);
}

/* A row's pixels are taken CHUNK at a time: first, for all of them, the
 * values at the segment's ends and middle, their table cells and sheet
 * k + 1's gradient, in loops the compiler vectorises; then the live ones
 * are listed and lit. */
enum { CHUNK = 64 };

/* vs_preint_cell of v[i] + base for a run of values: the same cells and
 * fractions, four at a time (the coordinate clamped before its
 * conversion) */
static inline void cells(const vs_preint_tabs *T, float base, const float *v, int *c, float *f, int n)
{
    int i = 0;
#if defined(__SSE2__)
    const __m128 vb = _mm_set1_ps(base), vmin = _mm_set1_ps(T->vmin), scale = _mm_set1_ps(T->scale);
    const __m128 top = _mm_set1_ps((float)(T->n - 2)), top1 = _mm_set1_ps((float)(T->n - 1)), one = _mm_set1_ps(1.0f);
    for (; i + 4 <= n; i += 4) {
        __m128 x = _mm_mul_ps(_mm_sub_ps(_mm_add_ps(_mm_loadu_ps(v + i), vb), vmin), scale);
        x = _mm_and_ps(x, _mm_cmpgt_ps(x, _mm_setzero_ps())); /* NaN and below: 0 */
        const __m128i k = _mm_cvttps_epi32(_mm_min_ps(x, top));
        const __m128 inside = _mm_cmplt_ps(x, top1);
        const __m128 fr = _mm_sub_ps(x, _mm_cvtepi32_ps(k));
        _mm_storeu_si128((__m128i *)(void *)(c + i), k);
        _mm_storeu_ps(f + i, _mm_or_ps(_mm_and_ps(inside, fr), _mm_andnot_ps(inside, one)));
    }
#endif
    for (; i < n; i++) c[i] = vs_preint_cell(T, v[i] + base, &f[i]);
}

void vs_shade_post_preint(const tile_ctx *t, const sheet_view *sv, shade_buf sb)
{
    const vs_frame *F = t->F;
    const vs_camera *cam = &F->cam;
    const vs_preint *P = F->preint;
    const vs_preint_tabs *T = &P->tabs;
    const spans *sp = sv->sp;
    const int gs = F->stages->gradient_splats;
    /* post-cd with perspective: its differences are per pixel of their
     * sheet and along the ray, brought to one frame as classification
     * does (post-gs splats them there) */
    const int persp = cam->persp && !gs;
    const float sk1 = persp ? (float)vs_camera_sheet_scale(cam, sv->k + 1, F->fp.slab) : 1.0f;
    const float cz = persp ? (float)(cam->px_per_mm / (cam->focal_px * cam->z_per_mm)) : 0.0f;
    const float slab = (float)F->fp.slab, base = (float)F->base;
    const ptrdiff_t st = t->stride;
    for (int y = sp->y0; y < sp->y1; y++)
        for (int x0 = sp->xa[y]; x0 < sp->xb[y]; x0 += CHUNK) {
            const int n = sp->xb[y] - x0 < CHUNK ? sp->xb[y] - x0 : CHUNK;
            const int o0 = vs_own(t, x0, y);
            const size_t b0 = (size_t)y * t->stride + x0;
            const float *al = sb.alpha + o0;
            int live = 0;
            for (int i = 0; i < n; i++) live |= al[i] > 0.0f;
            if (!live) continue;
            /* the values at the front, middle and back (post-cd reads its
             * sheets' rows in place) */
            float vf4[CHUNK], vm[CHUNK], vb4[CHUNK], ff[CHUNK], fm[CHUNK], fb[CHUNK];
            const float *vf = vf4, *vb = vb4;
            /* sheet k + 1's gradient by the kernel its classification
             * runs (the pipeline's opacity table is off with
             * pre-integration: gradients only), so that its terms can be
             * kept; post-cd's central differences read sheets k and k + 2
             * and, at the middle, the difference across the segment: each
             * depth difference centred where it is used (one-sided ones,
             * or the ends' mean at the middle, measured 0.7 dB worse on the
             * translucent head) */
            float g1[CHUNK][3], gmz[CHUNK], unused[CHUNK];
            int cf[CHUNK], cm[CHUNK], cb[CHUNK];
            if (gs) {
                const float *q4 = sv->q + 4 * b0, *n4 = sv->next + 4 * b0;
                for (int i = 0; i < n; i++) {
                    vf4[i] = q4[4 * i];
                    vb4[i] = n4[4 * i];
                    vm[i] = vs_preint_mid_gs(q4 + 4 * i, n4 + 4 * i);
                }
                vs_ripple_row rr; /* sheet k + 1's */
                const vs_ripple_row *R =
                    t->ripple ? vs_gs_ripple_at(F, sv->k + 1, x0 + t->ox, y + t->oy, &rr, t->ripple) : NULL;
                F->kern.classify_gs(unused, g1[0], n4, n, sv->tabs, R);
            } else {
                const float *q = sv->q + b0, *qp = sv->prev + b0, *qn = sv->next + b0;
                vf = q;
                vb = qn;
                for (int i = 0; i < n; i++) {
                    vm[i] = vs_preint_mid_cd(qp[i], q[i], qn[i]);
                    gmz[i] = (qn[i] - q[i]) / slab;
                }
                F->kern.classify_cd(unused, g1[0], qn, q, sv->next2 + b0, NULL, NULL, st, n, sv->tabs);
            }
            cells(T, base, vf, cf, ff, n);
            cells(T, base, vm, cm, fm, n);
            cells(T, base, vb, cb, fb, n);
            const float v = (float)((y + t->oy) - cam->cy);
            /* the live pixels, in order */
            int idx[CHUNK], nl = 0;
            for (int i = 0; i < n; i++) {
                idx[nl] = i;
                nl += al[i] > 0.0f;
            }
            /* their middle's and sheet k + 1's gradients, lit together */
            float gl[2 * CHUNK * 3], dl[2 * CHUNK], sl[2 * CHUNK];
            for (int j = 0; j < nl; j++) {
                const int i = idx[j];
                const float *g0 = sb.g + 3 * (o0 + i);
                float *gm = gl + 6 * j, *gn = gm + 3;
                for (int c = 0; c < 3; c++) gn[c] = g1[i][c];
                const float u = persp ? (float)((x0 + i + t->ox) - cam->cx) : 0.0f;
                if (persp) vs_perspective_gradient(gn, sk1, u, v, cz);
                gm[0] = 0.5f * (g0[0] + gn[0]);
                gm[1] = 0.5f * (g0[1] + gn[1]);
                gm[2] = gs ? 0.5f * (g0[2] + gn[2]) : gmz[i];
                if (persp) gm[2] -= (gm[0] * u + gm[1] * v) * cz; /* along view z, as the ends */
            }
            light_terms(F, sv, dl, sl, gl, 2 * nl);
            /* sheet k's terms: taken when sheet k - 1 was shaded, or now
             * for the pixels (miss) that were not live there */
            int miss[CHUNK], nm = 0;
            float gk[CHUNK * 3], dk[CHUNK], sk[CHUNK];
            for (int j = 0; j < nl; j++) {
                const int o = o0 + idx[j];
                if (sb.term_k[o] == sv->k) continue;
                for (int c = 0; c < 3; c++) gk[3 * nm + c] = sb.g[3 * o + c];
                miss[nm++] = j;
            }
            light_terms(F, sv, dk, sk, gk, nm);
            for (int j = 0, mi = 0; j < nl; j++) {
                const int i = idx[j], o = o0 + i;
                const vs_preint_at a1 = {(size_t)cf[i] * VS_PREINT_N + (size_t)cm[i], ff[i], fm[i]},
                                   a2 = {(size_t)cm[i] * VS_PREINT_N + (size_t)cb[i], fm[i], fb[i]};
                float e[8];
                vs_preint_get4(P, &a1, e);
                vs_preint_get4(P, &a2, e + 4);
                float d[3] = {0.0f, dl[2 * j], dl[2 * j + 1]}, sp3[3] = {0.0f, sl[2 * j], sl[2 * j + 1]};
                if (mi < nm && miss[mi] == j) {
                    d[0] = dk[mi];
                    sp3[0] = sk[mi++];
                } else {
                    d[0] = sb.term[2 * o];
                    sp3[0] = sb.term[2 * o + 1];
                }
                emit_mixed(e, d, sp3, sb.g + 3 * o);
                /* sheet k + 1's terms, for when it is shaded */
                sb.term[2 * o] = d[2];
                sb.term[2 * o + 1] = sp3[2];
                sb.term_k[o] = sv->k + 1;
            }
        }
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
            const int o = vs_own(t, x, y);
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
