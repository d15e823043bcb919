/* The per-tile sheet loop (paper §2 and §4): for each image-aligned sheet,
 * front to back, the voxels that reach it are splatted into the tile's
 * sheet buffer (which has a seam of the pixels central differences read), then
 * the touched part of the sheet is classified, shaded and composited, and
 * the tile's occlusion map (its accumulated opacity) updated.  The stages
 * live in their own files (activate.c, rasterize.c, sheet_classify.c,
 * shade.c, composite.c, occlusion.c); what differs between the pipelines
 * is the frame's stage table (pipeline.c).
 *
 * A tile only reads shared, read-only frame data and writes its own pixels,
 * so tiles run in any order on any thread and the image is bit-identical for
 * every thread count. */
#include "timing.h"
#include "activate.h"
#include "face_cover.h"
#include "gs_ripple.h"
#include "composite.h"
#include "occlusion.h"
#include "shade.h"
#include "trace.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void clear_rect(float *buf, int stride, int ch, const rect *r)
{
    if (rect_empty(r)) return;
    for (int y = r->y0; y < r->y1; y++)
        memset(buf + ((ptrdiff_t)y * stride + r->x0) * ch, 0, (size_t)(r->x1 - r->x0) * ch * sizeof(float));
}

void vs_tile_scratch_release(vs_tile_scratch *s, int n)
{
    for (int i = 0; i < n; i++) {
        free(s[i].arena);
        vs_spares_free(&s[i].spares);
        free(s[i].active);
        free(s[i].abox);
    }
    free(s);
}

/* Carving the arena: each piece on its own cache lines. */
typedef struct carve {
    size_t off;
} carve;
static size_t take(carve *c, size_t bytes)
{
    const size_t at = c->off;
    c->off += (bytes + 63) & ~(size_t)63;
    return at;
}

/* The arena holds at least `bytes`, with its first `zero` bytes zero
 * outside what the previous tile left dirty (it cleared those); 0 when
 * out of memory. */
static int scratch_reserve(vs_tile_scratch *s, size_t bytes, size_t zero)
{
    /* grown on demand; given back when a large arena is four times what a
     * tile needs (a frame with huge tiles is not paid for ever after) */
    if (bytes > s->cap || (s->cap > ((size_t)64 << 20) && bytes < s->cap / 4)) {
        const size_t cap = bytes + bytes / 4;
        free(s->arena);
        s->arena = aligned_alloc(64, (cap + 63) & ~(size_t)63);
        s->cap = s->arena ? cap : 0;
        s->zeroed = 0;
        if (!s->arena) return 0;
    }
    if (zero > s->zeroed) memset(s->arena + s->zeroed, 0, zero - s->zeroed);
    s->zeroed = zero; /* what lies past it is the other pieces' */
    return 1;
}

/* The first sheet of the tile's brick e (its kernels reach no earlier). */
static inline int first_sheet(const vs_frame *F, const uint32_t *ent, int e) { return F->bview[ent[e]].kf; }

void vs_tile_progress(void *arg)
{
    vs_frame *F = arg;
    if (atomic_load(&F->cancel) || !F->s->progress) return;
    const double frac = (double)atomic_load(&F->tiles_done) / F->ntiles;
    if (F->s->progress(F->s->progress_user, frac)) atomic_store(&F->cancel, 1);
}

void vs_tile_render(void *arg, int worker, int task)
{
    vs_frame *F = arg;
    const vs_settings *s = F->s;
    const vs_stages *st = F->stages;
    vs_worker_stats *ws = &F->wstats[worker];
    vs_tile_scratch *scr = &F->scratch[worker];
    vs_span_buf *tr = F->spans ? &F->spans[worker] : NULL; /* tracing */
    if (atomic_load_explicit(&F->cancel, memory_order_relaxed)) return;
    if (worker == 0) vs_tile_progress(F);
    task = F->tile_order[task];
    const int W = F->cam.width, T = F->tile;
    const int tx = task % F->tiles_x, ty = task / F->tiles_x;
    const double t_tile = tr ? vs_now_ms() : 0.0;
    tile_ctx t;
    t.F = F;
    t.ws = ws;
    t.fp = &F->fp;
    t.x0 = tx * T;
    t.y0 = ty * T;
    t.tw = (t.x0 + T > W ? W : t.x0 + T) - t.x0;
    t.th = (t.y0 + T > F->cam.height ? F->cam.height : t.y0 + T) - t.y0;
    t.seam = F->seam_px;
    t.bw = t.tw + 2 * t.seam;
    t.bh = t.th + 2 * t.seam;
    t.ox = t.x0 - t.seam;
    t.oy = t.y0 - t.seam;
    {
        double det = (double)F->fp.A * F->fp.C - (double)F->fp.B * F->fp.B;
        t.ry0 = (float)sqrt(F->fp.emax * F->fp.A / det);
    }
    t.stride = t.bw + 2 * VS_APRON;
    const int npix = t.tw * t.th;
    const uint32_t *ent = F->tile_entries + F->tile_start[task];
    const int nbr = (int)(F->tile_start[task + 1] - F->tile_start[task]);
    const int ch = st->ch;
    const float slab = (float)F->fp.slab;
    const float thr = (float)s->occlusion_threshold;

    /* the sheets the bricks span */
    int kmin = 1 << 30, kmax = -(1 << 30);
    for (int e = 0; e < nbr; e++) {
        const struct vs_brick_view *bv = &F->bview[ent[e]];
        if (bv->kf < kmin) kmin = bv->kf;
        if (bv->kl > kmax) kmax = bv->kl;
    }
    const int span = nbr > 0 ? kmax - kmin + 1 : 0;

    /* Sheet buffers: voxel-at-a-time for separable and sheared_blocks
     * footprints (a ring that holds every sheet a kernel reaches, plus the
     * neighbours central differences read), else sheet-at-a-time with three
     * buffers. */
    const int multi = F->use_blocks;
    const int lead = st->ahead > 1 ? st->ahead : 1; /* sheets the ring holds past the shaded one */
    const int behind = 1 + st->behind; /* sheets the ring holds before the shaded one */
    const int R = (multi ? F->fp.vspan + lead : 1 + lead) + behind;
    const size_t sheet_floats = (size_t)ch * t.stride * t.bh;
    const size_t nblk = F->use_skewed   ? (size_t)F->skew_maxrows * 8 * F->skew_maxvec
                        : F->use_blocks ? (size_t)F->blk.ny * 8 * F->blk.nvec
                                        : 0;
    carve c = {0};
    const size_t o_sheets = take(&c, (size_t)R * sheet_floats * sizeof(float));
    const size_t zero = c.off;
    const size_t o_acc = take(&c, (size_t)npix * 4 * sizeof(float));
    /* colours padded by one float: SIMD compositing reads 4 floats a pixel */
    const size_t o_g = take(&c, ((size_t)npix * 3 + 1) * sizeof(float));
    const size_t o_alpha = take(&c, (size_t)npix * sizeof(float));
    const int terms = F->preint && !st->pre_shaded; /* shade_preint.c keeps terms */
    const size_t o_term = take(&c, terms ? (size_t)npix * 2 * sizeof(float) : 0);
    const size_t o_term_k = take(&c, terms ? (size_t)npix * sizeof(int) : 0);
    const size_t o_sat = take(&c, (size_t)(t.tw + 1) * (t.th + 1) * sizeof(int));
    const size_t o_live = take(&c, (size_t)(2 * t.th + 2 * t.bh) * sizeof(int));
    const size_t o_order = take(&c, (size_t)nbr * sizeof(int));
    const size_t o_bucket = take(&c, ((size_t)span + 1) * sizeof(int));
    const size_t o_bk = take(&c, (size_t)span * sizeof(pend_bucket));
    const size_t o_ring = take(&c, (size_t)R * sizeof(float *));
    const size_t o_bbox = take(&c, (size_t)R * sizeof(rect));
    const size_t o_blk = take(&c, nblk * sizeof(float));
    const size_t o_ex = take(&c, (size_t)t.bw * sizeof(float));
    const size_t o_rip = take(&c, F->ripple.on ? sizeof(vs_gs_ripple_tile) : 0);
    const size_t o_ript = take(&c, F->ripple.on ? vs_gs_ripple_tile_floats(t.tw, t.th) * sizeof(float) : 0);
    if (!scratch_reserve(scr, c.off, zero)) {
        atomic_store(&F->error, 1);
        atomic_fetch_add(&F->tiles_done, 1);
        return;
    }
    unsigned char *A = scr->arena;
    float *sheets = (float *)(A + o_sheets);
    float *acc = (float *)(A + o_acc);
    shade_buf sb = {(float *)(A + o_alpha), (float *)(A + o_g), NULL, NULL};
    if (terms) {
        sb.term = (float *)(A + o_term);
        sb.term_k = (int *)(A + o_term_k);
        for (int i = 0; i < npix; i++) sb.term_k[i] = INT_MIN;
    }
    int *sat = (int *)(A + o_sat);
    /* per own row, the columns [live0, live1) not yet fully opaque; per
     * buffer row, a sheet's shaded span */
    int *live0 = (int *)(A + o_live), *live1 = live0 + t.th;
    int *span_xa = live0 + 2 * t.th, *span_xb = span_xa + t.bh;
    int *order = (int *)(A + o_order), *bucket = (int *)(A + o_bucket);
    float **ring = (float **)(A + o_ring);
    rect *bbox = (rect *)(A + o_bbox);
    t.blk = nblk ? (float *)(A + o_blk) : NULL;
    t.ex = (float *)(A + o_ex);
    t.ripple = NULL;
    if (F->ripple.on) {
        t.ripple = (vs_gs_ripple_tile *)(A + o_rip);
        vs_gs_ripple_tile_init(t.ripple, (float *)(A + o_ript), t.x0, t.y0, t.tw, t.th);
    }
    memset(acc, 0, (size_t)npix * 4 * sizeof(float));
    /* sb.g needs no clearing: a pixel's colour is read only where its
     * opacity is not 0, and then shading wrote it on this sheet; only the
     * padding float the SIMD compositing reads past the last pixel is
     * zeroed */
    sb.g[(size_t)npix * 3] = 0.0f;
    memset(sat, 0, (size_t)(t.tw + 1) * (t.th + 1) * sizeof(int));
    memset(bucket, 0, ((size_t)span + 1) * sizeof(int));

    int opaque = 0;
    int sat_from = 1 << 30; /* first tile row whose opaque pixels changed since the table was built */
    tile_state ts;
    memset(&ts, 0, sizeof ts);
    ts.t = &t;
    ts.acc = acc;
    ts.sat = sat;
    ts.opaque = &opaque;
    ts.ws = ws;
    ts.spares = &scr->spares;
    ts.active = scr->active;
    ts.abox = scr->abox;
    ts.cap_active = scr->cap_active;
    ts.cap_abox = scr->cap_abox;
    for (int y = 0; y < t.th; y++) {
        live0[y] = 0;
        live1[y] = t.tw;
    }
    if (F->under) {
        /* a depth band behind nearer ones: compositing goes on from their
         * picture, and what they made opaque culls this band's voxels */
        for (int y = 0; y < t.th; y++)
            for (int x = 0; x < t.tw; x++) {
                const float *u = F->under + 4 * ((size_t)(t.y0 + y) * W + (t.x0 + x));
                float *a = acc + 4 * ((size_t)y * t.tw + x);
                for (int i = 0; i < 3; i++) a[i] = u[i] * u[3];
                a[3] = u[3];
                opaque += u[3] >= thr;
            }
        if (s->occlusion && opaque > 0) {
            vs_build_sat(&t, acc, thr, sat, 0);
            for (int y = 0; y < t.th; y++) vs_shrink_live(&t, acc, y, live0, live1);
        }
    }
    for (int i = 0; i < R; i++) {
        ring[i] = sheets + (size_t)i * sheet_floats + (size_t)VS_APRON * ch;
        rect_clear(&bbox[i]);
    }

    /* a counting sort of the bricks by their first sheet */
    if (nbr > 0) {
        ts.bk = (pend_bucket *)(A + o_bk);
        memset(ts.bk, 0, (size_t)span * sizeof *ts.bk);
        for (int e = 0; e < nbr; e++) bucket[first_sheet(F, ent, e) - kmin + 1]++;
        for (int b = 0; b < span; b++) bucket[b + 1] += bucket[b];
        for (int e = 0; e < nbr; e++) order[bucket[first_sheet(F, ent, e) - kmin]++] = e; /* stable */
        ts.kmin = kmin;
        ts.kmax = kmax;
    }
    /* slot of sheet k: (k - kbase) % R, never negative from the first
     * sheet the loop opens */
    const int kbase = kmin - lead - st->behind;
    const rect own = {t.seam, t.seam, t.tw + t.seam, t.th + t.seam};
    int next_brick = 0;

    /* sheet k is shaded once sheet k + ahead is complete */
    const int ahead = st->ahead;
    const int covered = s->occlusion && opaque >= npix; /* nearer bands hid the whole tile */
    for (int k = kmin - ahead; nbr > 0 && !covered && k <= kmax && k < F->show1; k++) {
        if (atomic_load_explicit(&F->cancel, memory_order_relaxed)) break;
        const int cur = (k - kbase) % R, prev = (k - 1 - kbase + R) % R, nxt = (k + 1 - kbase) % R;
        const int opening = k + ahead;
        if (opening <= kmax) {
            const double t0 = vs_now_ms();
            while (next_brick < nbr && first_sheet(F, ent, order[next_brick]) == opening)
                vs_expand_brick(&ts, ent[order[next_brick++]], opening);
            const double tp = tr ? vs_now_ms() : 0.0;
            const int os = (opening - kbase) % R;
            if (multi)
                st->activate(&ts, opening, ring, bbox, R, kbase);
            else
                vs_rasterize_sheet(&ts, opening, ring[os], &bbox[os]);
            /* sheet `opening` is complete: no later voxel reaches it */
            if (F->cover) vs_face_norm_sheet(&t, opening, ring[os], &bbox[os], ch, st->gradient_splats);
            const double t1 = vs_now_ms();
            ws->ms_rasterize += t1 - t0;
            if (tr) {
                vs_span_add(tr, VS_SPAN_PROJECT, worker, task, t0, tp);
                vs_span_add(tr, VS_SPAN_SPLAT, worker, task, tp, t1);
            }
            if (ts.failed) {
                atomic_store(&F->error, 1);
                break;
            }
        }
        if (k < kmin) continue;
        /* the sheet no later sheet reads */
        const int done_slot = ahead ? (k - behind - kbase + R) % R : cur;
        if (k < F->show0) { /* before the band: splatted only for the band's gradients */
            clear_rect(ring[done_slot], t.stride, ch, &bbox[done_slot]);
            rect_clear(&bbox[done_slot]);
            continue;
        }
        ws->tiles_total++;
        ws->sheets++;
        /* tile counter: only the touched part of the sheet is shaded */
        rect r = own;
        if (s->tile_counters) {
            r = bbox[cur];
            if (r.x0 < own.x0) r.x0 = own.x0;
            if (r.y0 < own.y0) r.y0 = own.y0;
            if (r.x1 > own.x1) r.x1 = own.x1;
            if (r.y1 > own.y1) r.y1 = own.y1;
        }
        if (!rect_empty(&r)) {
            ws->tiles_shaded++;
            spans sp = {.xa = span_xa, .xb = span_xb};
            vs_shaded_spans(&r, live0, live1, t.seam, &sp);
            /* the tables the post-shaded kernels read (a few stores a sheet) */
            /* pre-integration classifies the segment (sheet_classify.c):
             * the kernels then take the gradients only */
            const vs_shade_tabs tabs = {.vmin = F->cls->vmin - F->base, .scale = F->cls->scale,
                                        .alpha = F->preint ? NULL : F->alpha_corr, .alpha_zero_x = F->alpha_zero_x,
                                        .color = &F->cls->color[0][0], .slab = slab, .two_slab = 2.0f * slab,
                                        .cd_wide = F->cd_wide, .cd_wide_z = F->cd_wide_z,
                                        .ppm = (float)F->cam.px_per_mm, .zpm = (float)F->cam.z_per_mm,
                                        .nl = F->lut.nl, .lambda_bin = F->lut.lambda_bin, .radius = F->lut.radius,
                                        .phi_bin = F->lut.phi_bin, .diffuse = F->lut.diffuse,
                                        .specular = F->lut.specular};
            const sheet_view sv = {.k = k, .q = ring[cur], .prev = ring[prev], .next = ring[nxt],
                                   .next2 = ahead > 1 ? ring[(k + 2 - kbase) % R] : NULL,
                                   .prev2 = behind > 1 ? ring[(k - 2 - kbase) % R] : NULL, .sp = &sp,
                                   .tabs = &tabs, .acc = acc};
            /* 1. classification + gradients */
            const double t0 = vs_now_ms();
            ws->px_shaded += st->classify(&t, &sv, sb);
            const double t1 = vs_now_ms();
            for (int y = sp.y0; y < sp.y1; y++) ws->px_classified += (uint64_t)(sp.xb[y] - sp.xa[y]);
            /* 2. shading: colour per pixel */
            st->shade(&t, &sv, sb);
            if (F->cam.persp) vs_perspective_opacity(&t, &sp, sb.alpha);
            const double t2 = vs_now_ms();
            /* 3. front-to-back compositing; the accumulated opacity is the
             * tile's occlusion map */
            opaque += vs_composite_sheet(&t, &sp, acc, sb, thr, &sat_from);
            const double tc = tr ? vs_now_ms() : 0.0;
            if (s->occlusion) {
                for (int y = sp.y0; y < sp.y1; y++)
                    if (sp.xa[y] != sp.xb[y]) vs_shrink_live(&t, acc, y - t.seam, live0, live1);
                if (sat_from < t.th) {
                    /* rows above the first changed one keep their sums */
                    vs_build_sat(&t, acc, thr, sat, sat_from);
                    sat_from = 1 << 30;
                }
            }
            const double t3 = vs_now_ms();
            if (tr) {
                vs_span_add(tr, VS_SPAN_CLASSIFY, worker, task, t0, t1);
                vs_span_add(tr, VS_SPAN_SHADE, worker, task, t1, t2);
                vs_span_add(tr, VS_SPAN_COMPOSITE, worker, task, t2, tc);
                vs_span_add(tr, VS_SPAN_OCCLUSION, worker, task, tc, t3);
            }
            ws->ms_gradient += t1 - t0;
            ws->ms_shade += t2 - t1;
            ws->ms_composite += t3 - t2;
        }
        /* retire sheet k - behind (done_slot) */
        clear_rect(ring[done_slot], t.stride, ch, &bbox[done_slot]);
        rect_clear(&bbox[done_slot]);
        if (s->occlusion && opaque >= npix) break; /* tile early termination */
    }

    vs_composite_finish(&t, acc);
    /* leave the sheet buffers zero for the next tile, and the lists to it */
    for (int i = 0; i < R; i++) clear_rect(ring[i], t.stride, ch, &bbox[i]);
    for (int b = 0; b < span && ts.bk; b++) vs_keep_spare(&scr->spares, ts.bk[b].p, ts.bk[b].cap);
    scr->active = ts.active;
    scr->abox = ts.abox;
    scr->cap_active = ts.cap_active;
    scr->cap_abox = ts.cap_abox;
    if (tr) vs_span_add(tr, VS_SPAN_TILE, worker, task, t_tile, vs_now_ms());
    atomic_fetch_add(&F->tiles_done, 1);
}
