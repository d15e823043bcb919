/* Pre-integrated classification between sheets (Engel, Kraus, Ertl 2001,
 * adapted to sheet buffers): the opacity and colour of a ray segment one
 * slab long whose density runs linearly from the value on one sheet to the
 * value on the next, tabulated over (front, back) (preintegrate.c). */
#ifndef VS_PREINTEGRATE_H
#define VS_PREINTEGRATE_H

#include "classify.h"

/* Entries per axis of the table (over the classification's domain). */
#define VS_PREINT_N 256

typedef struct vs_preint {
    double vmin, scale;   /* coordinate x = (v - vmin) * scale, in [0, N-1] */
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

/* Bilinear look-up at (front, back): out = (opacity, premultiplied r g b). */
static inline void vs_preint_lookup(const vs_preint *p, float f, float b, float out[4])
{
    float x = (float)((f - p->vmin) * p->scale), y = (float)((b - p->vmin) * p->scale);
    const float top = (float)(VS_PREINT_N - 1);
    if (!(x > 0.0f)) x = 0.0f; /* also NaN */
    if (!(y > 0.0f)) y = 0.0f;
    if (x > top) x = top;
    if (y > top) y = top;
    int i = (int)x, j = (int)y;
    if (i > VS_PREINT_N - 2) i = VS_PREINT_N - 2;
    if (j > VS_PREINT_N - 2) j = VS_PREINT_N - 2;
    const float fx = x - (float)i, fy = y - (float)j;
    const float *e00 = p->tab + 4 * ((size_t)i * VS_PREINT_N + j), *e01 = e00 + 4;
    const float *e10 = e00 + 4 * VS_PREINT_N, *e11 = e10 + 4;
    for (int c = 0; c < 4; c++) {
        float a = e00[c] + fy * (e01[c] - e00[c]);
        float b2 = e10[c] + fy * (e11[c] - e10[c]);
        out[c] = a + fx * (b2 - a);
    }
}

/* The opacity-weighted position along the segment at (front, back), in
 * [0, 1]; where the shading gradient is taken between the two sheets. */
static inline float vs_preint_position(const vs_preint *p, float f, float b, float alpha)
{
    if (!(alpha > 0.0f)) return 0.0f;
    float x = (float)((f - p->vmin) * p->scale), y = (float)((b - p->vmin) * p->scale);
    const float top = (float)(VS_PREINT_N - 1);
    if (!(x > 0.0f)) x = 0.0f;
    if (!(y > 0.0f)) y = 0.0f;
    if (x > top) x = top;
    if (y > top) y = top;
    int i = (int)x, j = (int)y;
    if (i > VS_PREINT_N - 2) i = VS_PREINT_N - 2;
    if (j > VS_PREINT_N - 2) j = VS_PREINT_N - 2;
    const float fx = x - (float)i, fy = y - (float)j;
    const float *e = p->pos + (size_t)i * VS_PREINT_N + j;
    float a = e[0] + fy * (e[1] - e[0]);
    float b2 = e[VS_PREINT_N] + fy * (e[VS_PREINT_N + 1] - e[VS_PREINT_N]);
    float t = (a + fx * (b2 - a)) / alpha;
    return t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
}

/* A span's opacities from the table: alpha[i] at (q[i * qs], qn[i * qs]). */
void vs_preint_alpha_row(const vs_preint *p, float *alpha, const float *q, const float *qn, int qs, int n);

#endif
