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

/* With a transfer function that makes value 0 visible, sheet pixels whose
 * slab centre lies outside the volume (where nothing was splatted, so q = 0)
 * must stay transparent, as they are for the ray caster; with a crop box,
 * those outside the box (another brick composites them). */
static void clip_outside(const tile_ctx *t, int k, const spans *r, float *alpha)
{
    const vs_frame *F = t->F;
    const vs_camera *cam = &F->cam;
    const double z = (k + 0.5) * F->fp.slab;
    const double *lo = F->clip_lo, *hi = F->clip_hi;
    const int *open = F->clip_hi_open;
    for (int y = r->y0; y < r->y1; y++)
        for (int x = r->xa[y]; x < r->xb[y]; x++) {
            double v[3] = {x + t->ox, y + t->oy, z}, idx[3];
            vs_camera_view_to_index(cam, v, idx);
            int inside = 1;
            for (int a = 0; a < 3; a++)
                inside &= idx[a] >= lo[a] && (open[a] ? idx[a] < hi[a] : idx[a] <= hi[a]);
            if (!inside) alpha[vs_own(t, x, y)] = 0.0f;
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
