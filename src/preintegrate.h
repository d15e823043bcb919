/* Pre-integrated classification between sheets (Engel, Kraus, Ertl 2001,
 * adapted to sheet buffers): the opacity and colour of a ray segment whose
 * density runs linearly from a front to a back value, tabulated over
 * (front, back) (preintegrate.c).  The segment from one sheet to the next
 * is taken as two such halves, split at a middle value from the sheets'
 * depth derivatives (vs_preint_mid_gs, vs_preint_mid_cd): density along a
 * ray is curved over a slab, and a straight line through the two samples
 * puts a thin layer's opacity at the wrong depth (rings). */
#ifndef VS_PREINTEGRATE_H
#define VS_PREINTEGRATE_H

#include "classify.h"
#include "kernels.h"

#include <stddef.h>
#if defined(__x86_64__) || defined(__SSE__)
#include <xmmintrin.h>
#endif

/* Entries per axis of the table (over the classification's domain). */
#define VS_PREINT_N 256

typedef struct vs_preint {
    double vmin, scale;   /* coordinate x = (v - vmin) * scale, in [0, N-1] */
    /* [front][back] of (opacity of the segment, the colour it emits r g b,
     * premultiplied by that opacity, so that interpolating next to a
     * transparent entry does not darken); four floats an entry, one
     * 16-byte load each */
    float *tab;
    /* what the table was built from (rebuilt only when it changes) */
    float key_alpha[VS_TF_TABLE];
    float key_color[VS_TF_TABLE][3];
    double key_vmin, key_scale, key_slab;
    double ms_build;      /* time of the last build */
    vs_preint_tabs tabs;  /* tab, and vmin, scale in float, for the per-pixel
                             look-ups (those in src/ and the kernels) */
} vs_preint;

struct vs_pool;
/* Make p's table match the classification and a segment `slab` view
 * units long (a frame asks for half its slab); builds only when they
 * changed, on the pool if one is given.  0 when out of memory. */
int vs_preint_update(vs_preint *p, const vs_classify *c, double slab, struct vs_pool *pool);
void vs_preint_free(vs_preint *p);

/* Where (front, back) falls in the table: the entry below it and the
 * bilinear weights; computed once a pixel for every look-up. */
typedef struct vs_preint_at {
    size_t idx;  /* entry (i, j) = i * N + j */
    float fx, fy;
} vs_preint_at;

static inline vs_preint_at vs_preint_locate(const vs_preint *p, float f, float b)
{
    vs_preint_at a;
    const int i = vs_preint_cell(&p->tabs, f, &a.fx), j = vs_preint_cell(&p->tabs, b, &a.fy);
    a.idx = (size_t)i * VS_PREINT_N + (size_t)j;
    return a;
}

/* Channel c of the table at a (0 opacity, 1..3 premultiplied colour). */
static inline float vs_preint_get(const vs_preint *p, const vs_preint_at *a, int c)
{
    return vs_preint_bilerp(&p->tabs, a->idx, a->fx, a->fy, c);
}

/* All four channels at a, the same values as vs_preint_get (the same
 * operations, a lane a channel). */
static inline void vs_preint_get4(const vs_preint *p, const vs_preint_at *a, float out[4])
{
#if defined(__x86_64__) || defined(__SSE__)
    const float *e00 = p->tab + 4 * a->idx, *e10 = e00 + 4 * VS_PREINT_N;
    const __m128 fy = _mm_set1_ps(a->fy), fx = _mm_set1_ps(a->fx);
    const __m128 x00 = _mm_load_ps(e00), x01 = _mm_load_ps(e00 + 4);
    const __m128 x10 = _mm_load_ps(e10), x11 = _mm_load_ps(e10 + 4);
    const __m128 u = _mm_add_ps(x00, _mm_mul_ps(fy, _mm_sub_ps(x01, x00)));
    const __m128 v = _mm_add_ps(x10, _mm_mul_ps(fy, _mm_sub_ps(x11, x10)));
    _mm_storeu_ps(out, _mm_add_ps(u, _mm_mul_ps(fx, _mm_sub_ps(v, u))));
#else
    for (int c = 0; c < 4; c++) out[c] = vs_preint_get(p, a, c);
#endif
}

/* Bilinear look-up at (front, back): out = (opacity, premultiplied r g b). */
static inline void vs_preint_lookup(const vs_preint *p, float f, float b, float out[4])
{
    const vs_preint_at a = vs_preint_locate(p, f, b);
    vs_preint_get4(p, &a, out);
}

/* Both halves of a segment, f to m and m to b: e[0..3] the front half's
 * look-up, e[4..7] the back half's (the middle's cell found once). */
static inline void vs_preint_halves(const vs_preint *p, float f, float m, float b, float e[8])
{
    vs_preint_at a1, a2;
    const int i = vs_preint_cell(&p->tabs, f, &a1.fx), j = vs_preint_cell(&p->tabs, m, &a1.fy),
              k = vs_preint_cell(&p->tabs, b, &a2.fy);
    a1.idx = (size_t)i * VS_PREINT_N + (size_t)j;
    a2.idx = (size_t)j * VS_PREINT_N + (size_t)k;
    a2.fx = a1.fy;
    vs_preint_get4(p, &a1, e);
    vs_preint_get4(p, &a2, e + 4);
}

/* The middle of the segment from sheet k to sheet k + 1 (values without
 * the frame's base).  Post-gs: the cubic with the two sheets' densities
 * and depth derivatives (Hermite), q[3] being the splatted derivative
 * times the slab: (q + qn) / 2 + (q[3] - qn[3]) / 8.  Post-cd and
 * post-alpha, which splat no derivative and whose sheet k + 2 is not
 * splatted yet: the parabola through sheets k - 1, k and k + 1. */
static inline float vs_preint_mid_gs(const float *q4, const float *qn4)
{
    return 0.5f * (q4[0] + qn4[0]) + 0.125f * (q4[3] - qn4[3]);
}
static inline float vs_preint_mid_cd(float qp, float q, float qn)
{
    return 0.125f * ((6.0f * q + 3.0f * qn) - qp);
}

/* Opacity of two halves, front over back. */
static inline float vs_preint_over(float front, float back)
{
    return front + (1.0f - front) * back;
}

/* A span's opacities, sheet k to sheet k + 1 in two halves, by the
 * kernels' preint_alpha; sheet values to which base is added
 * (vs_frame.base).  Post-gs: four channels a pixel (density, the three
 * gradient splats).  Post-cd and post-alpha: the density every qs floats
 * (1; post-alpha 4, from its fourth channel), and the sheet before, qp. */
void vs_preint_alpha_row_gs(const vs_preint *p, const vs_kernels *k, float base, float *alpha, const float *q4,
                            const float *qn4, int n);
void vs_preint_alpha_row_cd(const vs_preint *p, const vs_kernels *k, float base, float *alpha, const float *qp,
                            const float *q, const float *qn, int qs, int n);

#endif
