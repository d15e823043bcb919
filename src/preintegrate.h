/* Pre-integrated classification between sheets (Engel, Kraus, Ertl 2001,
 * adapted to sheet buffers): the opacity and colour of a ray segment one
 * slab long whose density runs linearly from the value on one sheet to the
 * value on the next, tabulated over (front, back) (preintegrate.c). */
#ifndef VS_PREINTEGRATE_H
#define VS_PREINTEGRATE_H

#include "classify.h"

#include <stddef.h>

/* Entries per axis of the table (over the classification's domain). */
#define VS_PREINT_N 256

typedef struct vs_preint {
    double vmin, scale;   /* coordinate x = (v - vmin) * scale, in [0, N-1] */
    float fvmin, fscale;  /* the same in float, for the per-pixel look-ups  */
    /* [front][back] of (opacity of the segment, the colour it emits r g b,
     * premultiplied by that opacity, so that interpolating next to a
     * transparent entry does not darken); four floats an entry, one
     * 16-byte load each */
    float *tab;
    /* [front][back]: where along the segment (0 front .. 1 back) its
     * opacity lies, the mean weighted by what each part adds, times the
     * opacity (premultiplied, as the colour) */
    float *pos;
    /* what the table was built from (rebuilt only when it changes) */
    float key_alpha[VS_TF_TABLE];
    float key_color[VS_TF_TABLE][3];
    double key_vmin, key_scale, key_slab;
    double ms_build;      /* time of the last build */
} vs_preint;

struct vs_pool;
/* Make p's table match the classification and slab; builds only when they
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
    float x = (f - p->fvmin) * p->fscale, y = (b - p->fvmin) * p->fscale;
    const float top = (float)(VS_PREINT_N - 2);
    if (!(x > 0.0f)) x = 0.0f; /* also NaN */
    if (!(y > 0.0f)) y = 0.0f;
    vs_preint_at a;
    int i = x < top ? (int)x : VS_PREINT_N - 2, j = y < top ? (int)y : VS_PREINT_N - 2;
    a.fx = x < top + 1.0f ? x - (float)i : 1.0f;
    a.fy = y < top + 1.0f ? y - (float)j : 1.0f;
    a.idx = (size_t)i * VS_PREINT_N + (size_t)j;
    return a;
}

/* Channel c of the table at a (0 opacity, 1..3 premultiplied colour). */
static inline float vs_preint_get(const vs_preint *p, const vs_preint_at *a, int c)
{
    const float *e00 = p->tab + 4 * a->idx + c, *e10 = e00 + 4 * VS_PREINT_N;
    const float u = e00[0] + a->fy * (e00[4] - e00[0]);
    const float v = e10[0] + a->fy * (e10[4] - e10[0]);
    return u + a->fx * (v - u);
}

/* Bilinear look-up at (front, back): out = (opacity, premultiplied r g b). */
static inline void vs_preint_lookup(const vs_preint *p, float f, float b, float out[4])
{
    const vs_preint_at a = vs_preint_locate(p, f, b);
    for (int c = 0; c < 4; c++) out[c] = vs_preint_get(p, &a, c);
}

/* The opacity-weighted position along the segment at a, in [0, 1], for
 * the segment's opacity alpha: where the shading gradient is taken
 * between the two sheets. */
static inline float vs_preint_position(const vs_preint *p, const vs_preint_at *a, float alpha)
{
    if (!(alpha > 0.0f)) return 0.0f;
    const float *e = p->pos + a->idx, *e1 = e + VS_PREINT_N;
    const float u = e[0] + a->fy * (e[1] - e[0]);
    const float v = e1[0] + a->fy * (e1[1] - e1[0]);
    const float t = (u + a->fx * (v - u)) / alpha;
    return t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
}

/* A span's opacities from the table: alpha[i] at (q[i * qs], qn[i * qs]),
 * sheet values to which base is added (vs_frame.base). */
void vs_preint_alpha_row(const vs_preint *p, float base, float *alpha, const float *q, const float *qn, int qs, int n);

#endif
