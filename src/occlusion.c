/* The occlusion map (occlusion.h): the summed-area table of opaque pixels
 * and the spans still open. */
#include "occlusion.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* Early splat elimination.  The paper tests the occlusion map at the
 * projected voxel centre; culling a voxel whose centre is covered but whose
 * footprint still reaches open pixels removes density from their sheets and
 * bends their gradients (visible as rings on an opaque sphere).  So, as in
 * the occlusion test of Mueller et al. [22], we test the footprint's whole
 * extent (plus the seam the in-sheet differences read): a voxel is
 * culled only if every pixel of the tile it can affect is opaque.  A
 * summed-area table of the tile's opaque pixels answers that in O(1); it is
 * rebuilt from row `from` on, the first whose opaque pixels changed. */
void vs_build_sat(const tile_ctx *t, const float *acc, float thr, int *sat, int from)
{
    /* the sizes in locals: sat's stores could alias them */
    const int tw = t->tw, th = t->th, w = tw + 1;
    if (from == 0)
        for (int x = 0; x < w; x++) sat[x] = 0;
    for (int y = from; y < th; y++) {
        int run = 0;
        sat[(y + 1) * w] = 0;
        for (int x = 0; x < tw; x++) {
            run += acc[4 * (y * tw + x) + 3] >= thr;
            sat[(y + 1) * w + x + 1] = sat[y * w + x + 1] + run;
        }
    }
}

/* Pixels whose accumulated opacity is already 1 take nothing more from any
 * sheet (compositing weighs a sample by 1 - opacity = 0), so they need no
 * shading: behind the head's skin, four in five visible pixels of a
 * shaded span are such.  Clearing their opacity skips them in shading and
 * compositing and leaves the image bit-identical. */
uint64_t vs_skip_opaque(const tile_ctx *t, const spans *r, const float *acc, float *alpha)
{
    uint64_t vis = 0;
    for (int y = r->y0; y < r->y1; y++) {
        if (r->xa[y] == r->xb[y]) continue;
        const int o = vs_own(t, r->xa[y], y);
        const float *restrict a = acc + 4 * o + 3;
        float *restrict al = alpha + o;
        const int n = r->xb[y] - r->xa[y];
        int v = 0, i = 0;
#if defined(__SSE2__)
        /* four pixels a step: GCC does not vectorise the strided opacity
         * load, and this pass runs over every classified pixel */
        const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
        __m128i nv = _mm_setzero_si128(); /* per lane, minus the pixels kept */
        for (; i + 4 <= n; i += 4) {
            const __m128 a01 = _mm_shuffle_ps(_mm_loadu_ps(a + 4 * i - 3), _mm_loadu_ps(a + 4 * i + 1),
                                              _MM_SHUFFLE(3, 3, 3, 3)); /* a0 a0 a1 a1 */
            const __m128 a23 = _mm_shuffle_ps(_mm_loadu_ps(a + 4 * i + 5), _mm_loadu_ps(a + 4 * i + 9),
                                              _MM_SHUFFLE(3, 3, 3, 3));
            const __m128 op = _mm_shuffle_ps(a01, a23, _MM_SHUFFLE(2, 0, 2, 0)); /* a0 a1 a2 a3 */
            const __m128 x = _mm_andnot_ps(_mm_cmpge_ps(op, one), _mm_loadu_ps(al + i));
            _mm_storeu_ps(al + i, x);
            nv = _mm_add_epi32(nv, _mm_castps_si128(_mm_cmpgt_ps(x, zero))); /* a true lane is -1 */
        }
        /* no popcount: baseline x86-64 has no instruction for it */
        nv = _mm_add_epi32(nv, _mm_shuffle_epi32(nv, _MM_SHUFFLE(1, 0, 3, 2)));
        nv = _mm_add_epi32(nv, _mm_shuffle_epi32(nv, _MM_SHUFFLE(2, 3, 0, 1)));
        v -= _mm_cvtsi128_si32(nv);
#endif
        for (; i < n; i++) {
            const float x = a[4 * i] >= 1.0f ? 0.0f : al[i];
            al[i] = x;
            v += x > 0.0f;
        }
        vis += (uint64_t)v;
    }
    return vis;
}

uint64_t vs_count_visible(const tile_ctx *t, const spans *r, const float *alpha)
{
    uint64_t vis = 0;
    for (int y = r->y0; y < r->y1; y++) {
        const float *al = alpha + vs_own(t, r->xa[y], y);
        int v = 0;
        for (int i = 0; i < r->xb[y] - r->xa[y]; i++) v += al[i] > 0.0f;
        vis += (uint64_t)v;
    }
    return vis;
}

/* The part of the touched rectangle r that is classified, shaded and
 * composited: in each row, the columns between the first and last pixel
 * not yet fully opaque (live).  Opaque runs at a row's ends are common
 * behind a surface; skip_opaque still drops those inside the span. */
void vs_shaded_spans(const rect *r, const int *live0, const int *live1, int seam, spans *sp)
{
    sp->y0 = r->y0;
    sp->y1 = r->y1;
    for (int y = r->y0; y < r->y1; y++) {
        /* own pixel x is buffer pixel x + seam */
        const int a = live0[y - seam] + seam, b = live1[y - seam] + seam;
        sp->xa[y] = a > r->x0 ? a : r->x0;
        sp->xb[y] = b < r->x1 ? b : r->x1;
        if (sp->xb[y] < sp->xa[y]) sp->xb[y] = sp->xa[y];
    }
}

/* After compositing: the live columns of own row y shrink past pixels
 * whose accumulated opacity reached 1 (a scan from each end that stops at
 * the first pixel still open: each opaque pixel is passed once per tile). */
void vs_shrink_live(const tile_ctx *t, const float *acc, int y, int *live0, int *live1)
{
    const float *a = acc + 4 * (size_t)y * t->tw + 3;
    int x0 = live0[y], x1 = live1[y];
    while (x0 < x1 && a[4 * x0] >= 1.0f) x0++;
    while (x1 > x0 && a[4 * (x1 - 1)] >= 1.0f) x1--;
    live0[y] = x0;
    live1[y] = x1;
}
