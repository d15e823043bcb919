/* Classification and gradients of a sheet (the first per-sheet stage):
 * each pixel of the shaded spans gets its opacity from the transfer
 * function and, post-shaded, its gradient (central differences across the
 * sheets before and after, or the gradient splats); pixels outside the
 * volume and pixels already opaque are cleared so that shading and
 * compositing skip them.  One function per pipeline (pipeline.c). */
#include "sheet_classify.h"
#include "gs_ripple.h"
#include "occlusion.h"
#include "preintegrate.h"

#include <math.h>

/* Where the fall-off to the value outside would show (vs_classify_faces),
 * sheet pixels whose slab centre lies outside the volume must stay
 * transparent, as they are for the ray caster; with a crop box, those
 * outside the box (another brick composites them). */
static inline int clip_inside(const vs_frame *F, const double idx[3])
{
    int inside = 1;
    for (int a = 0; a < 3; a++)
        inside &= idx[a] >= F->clip_lo[a] && (F->clip_hi_open[a] ? idx[a] < F->clip_hi[a] : idx[a] <= F->clip_hi[a]);
    return inside;
}

static void clip_outside(const tile_ctx *t, int k, const spans *r, float *alpha)
{
    const vs_frame *F = t->F;
    const vs_camera *cam = &F->cam;
    const double z = (k + 0.5) * F->fp.slab;
    /* the bounds a hair inside: a row running along one is tested point by
     * point */
    double b0[3], b1[3];
    for (int a = 0; a < 3; a++) {
        b0[a] = F->clip_lo[a] + 1e-6;
        b1[a] = F->clip_hi[a] - 1e-6;
    }
    for (int y = r->y0; y < r->y1; y++) {
        if (r->xa[y] >= r->xb[y]) continue;
        /* A sheet point's index is affine in x along a row (perspective
         * too: the sheet's scale is one number).  The pixels more than two
         * from where that line crosses a bound are inside without a test;
         * the others are tested point by point, as the ray caster's and a
         * neighbouring brick's tests are, so that rounding decides alike. */
        double i0[3], i1[3];
        const double v0[3] = {t->ox, y + t->oy, z}, v1[3] = {t->ox + 1.0, y + t->oy, z};
        vs_camera_view_to_index(cam, v0, i0);
        vs_camera_view_to_index(cam, v1, i1);
        double di[3], lo, hi; /* x where every bound holds */
        for (int a = 0; a < 3; a++) di[a] = i1[a] - i0[a];
        vs_camera_row_within(i0, di, b0, b1, &lo, &hi);
        /* clamped before converting (a near-parallel axis puts them far
         * off); [ra, rb): two pixels or more inside every crossing */
        lo = lo < r->xa[y] - 3 ? r->xa[y] - 3 : lo > r->xb[y] ? r->xb[y] : lo;
        hi = hi > r->xb[y] + 3 ? r->xb[y] + 3 : hi < r->xa[y] - 1 ? r->xa[y] - 1 : hi;
        int ra = (int)ceil(lo) + 2, rb = (int)floor(hi) - 1;
        ra = ra < r->xa[y] ? r->xa[y] : ra;
        rb = rb > r->xb[y] ? r->xb[y] : rb;
        if (rb <= ra) ra = rb = r->xb[y];
        for (int x = r->xa[y]; x < r->xb[y]; x++) {
            if (x == ra) x = rb;
            if (x >= r->xb[y]) break;
            double v[3] = {x + t->ox, y + t->oy, z}, idx[3];
            vs_camera_view_to_index(cam, v, idx);
            if (!clip_inside(F, idx)) alpha[vs_own(t, x, y)] = 0.0f;
        }
    }
}

/* Perspective, post-cd: sheet k's central differences are per pixel of
 * that sheet, which lie 1/s_k depth-0 pixels apart, and the difference
 * across sheets runs along the pixel's ray, not along view z.  With the
 * world point P = (u Z/f, v Z/f, Z) of pixel offset (u, v) from the image
 * centre (f the focal length in pixels), dF/dZ at a fixed pixel is
 * Fx u/f + Fy v/f + Fz; solved for Fz.  Units out as in the orthographic
 * case: x, y per depth-0 pixel, z per view unit. */
static void perspective_gradients(const tile_ctx *t, int k, const spans *r, const float *alpha, float *g)
{
    const vs_camera *cam = &t->F->cam;
    const float sk = (float)vs_camera_sheet_scale(cam, k, t->F->fp.slab);
    const float cz = (float)(cam->px_per_mm / (cam->focal_px * cam->z_per_mm));
    for (int y = r->y0; y < r->y1; y++) {
        const float v = (float)((y + t->oy) - cam->cy);
        for (int x = r->xa[y]; x < r->xb[y]; x++) {
            int o = vs_own(t, x, y);
            if (!(alpha[o] > 0.0f)) continue;
            vs_perspective_gradient(g + 3 * o, sk, (float)((x + t->ox) - cam->cx), v, cz);
        }
    }
}

/* What every pipeline does after its own classification. */
static inline uint64_t classify_finish(const tile_ctx *t, const sheet_view *sv, shade_buf sb)
{
    const vs_frame *F = t->F;
    if (F->clip_to_volume) clip_outside(t, sv->k, sv->sp, sb.alpha);
    return F->s->occlusion ? vs_skip_opaque(t, sv->sp, sv->acc, sb.alpha) : vs_count_visible(t, sv->sp, sb.alpha);
}

/* Post-cd: density classified, (FH)D central differences across the
 * sheets before and after (or the four-point stencil over two each side).
 * With pre-integration (post-cd, -gs, -alpha) the opacity is the
 * segment's from this sheet to the next instead. */
uint64_t vs_classify_post_cd(const tile_ctx *t, const sheet_view *sv, shade_buf sb)
{
    const vs_frame *F = t->F;
    const spans *sp = sv->sp;
    for (int y = sp->y0; y < sp->y1; y++) {
        if (sp->xa[y] == sp->xb[y]) continue;
        int o = vs_own(t, sp->xa[y], y);
        size_t b = (size_t)y * t->stride + sp->xa[y];
        /* the four-point stencil across sheets (tabs cd_wide_z) reads k - 2 and k + 2 */
        const float *qp2 = sv->prev2 ? sv->prev2 + b : NULL, *qn2 = sv->prev2 ? sv->next2 + b : NULL;
        F->kern.classify_cd(sb.alpha + o, sb.g + 3 * o, sv->q + b, sv->prev + b, sv->next + b, qp2, qn2, t->stride,
                            sp->xb[y] - sp->xa[y], sv->tabs);
        if (F->preint)
            vs_preint_alpha_row_cd(F->preint, &F->kern, (float)F->base, sb.alpha + o, sv->prev + b, sv->q + b, sv->next + b,
                                   1, sp->xb[y] - sp->xa[y]);
    }
    if (F->clip_to_volume) clip_outside(t, sv->k, sp, sb.alpha);
    if (F->cam.persp) perspective_gradients(t, sv->k, sp, sb.alpha, sb.g);
    return F->s->occlusion ? vs_skip_opaque(t, sp, sv->acc, sb.alpha) : vs_count_visible(t, sp, sb.alpha);
}

/* Post-gs: density classified, the gradient splatted with it. */
uint64_t vs_classify_post_gs(const tile_ctx *t, const sheet_view *sv, shade_buf sb)
{
    const vs_frame *F = t->F;
    const spans *sp = sv->sp;
    vs_ripple_row rr;
    for (int y = sp->y0; y < sp->y1; y++) {
        if (sp->xa[y] == sp->xb[y]) continue;
        int o = vs_own(t, sp->xa[y], y);
        size_t b = (size_t)y * t->stride + sp->xa[y];
        const vs_ripple_row *R =
            t->ripple ? vs_gs_ripple_at(F, sv->k, sp->xa[y] + t->ox, y + t->oy, &rr, t->ripple) : NULL;
        F->kern.classify_gs(sb.alpha + o, sb.g + 3 * o, sv->q + 4 * b, sp->xb[y] - sp->xa[y], sv->tabs, R);
        if (F->preint)
            vs_preint_alpha_row_gs(F->preint, &F->kern, (float)F->base, sb.alpha + o, sv->q + 4 * b, sv->next + 4 * b,
                                   sp->xb[y] - sp->xa[y]);
    }
    return classify_finish(t, sv, sb);
}

/* Pre: the splatted opacity. */
uint64_t vs_classify_pre(const tile_ctx *t, const sheet_view *sv, shade_buf sb)
{
    const spans *sp = sv->sp;
    for (int y = sp->y0; y < sp->y1; y++)
        for (int x = sp->xa[y]; x < sp->xb[y]; x++) {
            int o = vs_own(t, x, y);
            size_t b = (size_t)y * t->stride + x;
            sb.alpha[o] = sv->q[4 * b + 3];
        }
    return classify_finish(t, sv, sb);
}

/* Post-alpha: the splatted density classified, corrected for the slab;
 * with pre-integration, the segment to the next sheet in two halves. */
uint64_t vs_classify_post_alpha(const tile_ctx *t, const sheet_view *sv, shade_buf sb)
{
    const vs_frame *F = t->F;
    const spans *sp = sv->sp;
    if (F->preint) {
        for (int y = sp->y0; y < sp->y1; y++) {
            if (sp->xa[y] == sp->xb[y]) continue;
            const int o = vs_own(t, sp->xa[y], y);
            const size_t b = 4 * ((size_t)y * t->stride + sp->xa[y]) + 3; /* the density */
            vs_preint_alpha_row_cd(F->preint, &F->kern, (float)F->base, sb.alpha + o, sv->prev + b, sv->q + b,
                                   sv->next + b, 4, sp->xb[y] - sp->xa[y]);
        }
        return classify_finish(t, sv, sb);
    }
    for (int y = sp->y0; y < sp->y1; y++)
        for (int x = sp->xa[y]; x < sp->xb[y]; x++) {
            int o = vs_own(t, x, y);
            size_t b = (size_t)y * t->stride + x;
            sb.alpha[o] = vs_classify_lookup(F->cls, F->alpha_corr, sv->q[4 * b + 3] + (float)F->base);
        }
    return classify_finish(t, sv, sb);
}
