/* Voxel activation: which voxels reach which sheet of a tile.  Bricks of
 * relevant voxels open at their first sheet (culled whole when their
 * footprints can only land on opaque pixels); their voxels are projected,
 * binned to the tile and bucketed by first sheet.  Each sheet then either
 * takes its voxels one at a time into every sheet their kernel reaches
 * (separable and sheared axis-aligned footprints: activate_sheet), or
 * gathers the voxels overlapping it (general footprints: rasterize_sheet).
 * The rasterizers themselves are rasterize.c's. */
#include "activate.h"
#include "normal_code.h"
#include "occlusion.h"
#include "rasterize.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Perspective: the image box of a voxel's section centres over the sheets
 * its kernel reaches (their middle depths lie within half a slab of the
 * kernel's depth extent), (x, y) its depth-0 position, and the largest
 * scale. */
static void voxel_box(const vs_frame *F, float x, float y, float z, float box[4], float *sc)
{
    const double reach = F->fp.rz + 0.5 * F->fp.slab;
    const double zn = z - reach > F->cam.near_z ? z - reach : F->cam.near_z;
    double b[4];
    vs_camera_depth_box(&F->cam, x, x, y, y, zn, z + reach, b);
    for (int i = 0; i < 4; i++) box[i] = (float)b[i];
    *sc = (float)vs_camera_scale(&F->cam, zn);
}

_Static_assert(VS_MAX_VSPAN <= VS_MAX_SHEETS_VOXEL, "the splat_voxel kernels take every sheet a kernel reaches");
_Static_assert(VS_BRICK == 8 && VS_PROJECT_MAX >= VS_BRICK * VS_BRICK * VS_BRICK,
               "project_brick (simd/kernels.h) decodes 3-bit brick offsets of at most 512 voxels");

/* Room for one more voxel in a bucket (a new bucket takes the array an
 * emptied one left last, while it is still in cache); 0 when out of
 * memory. */
static int grow_bucket(tile_state *ts, pend_bucket *bk)
{
    vs_spares *sp = ts->spares;
    if (!bk->p && sp->n > 0) {
        sp->n--;
        bk->p = sp->p[sp->n];
        bk->cap = sp->cap[sp->n];
        sp->bytes -= (size_t)bk->cap * sizeof(pend);
        return 1;
    }
    const int cap = bk->cap ? 2 * bk->cap : 256;
    pend *np = realloc(bk->p, (size_t)cap * sizeof *np);
    if (!np) return 0;
    bk->p = np;
    bk->cap = cap;
    return 1;
}

/* A bucket no sheet reads again gives its array to the next new one. */
static void retire_bucket(tile_state *ts, pend_bucket *bk)
{
    vs_keep_spare(ts->spares, bk->p, bk->cap);
    bk->p = NULL;
    bk->n = bk->cap = 0;
}

/* Open brick b: cull it whole if its footprints can only land on opaque
 * pixels, else project its voxels and bucket those that reach this tile. */
void vs_expand_brick(tile_state *ts, uint32_t b, int opening)
{
    const tile_ctx *t = ts->t;
    const vs_frame *F = t->F;
    const struct vs_brick_view *bv = &F->bview[b];
    const vs_brick *br = &F->rel->bricks[b];
    if (F->s->occlusion && *ts->opaque > 0 && box_occluded(t, ts->sat, bv->x0, bv->x1, bv->y0, bv->y1, bv->sc)) {
        ts->ws->culled += br->count;
        ts->ws->bricks_culled++;
        return;
    }
    ts->ws->projected += br->count;
    const float slab = (float)F->fp.slab, rz = (float)F->fp.rz;
    /* the footprint's reach alone: the buffer bounds below already hold
     * the seam the in-sheet differences read */
    const float px = (float)F->fp.rx, py = (float)F->fp.ry;
    const float bx0 = (float)t->ox, bx1 = (float)(t->ox + t->bw - 1);
    const float by0 = (float)t->oy, by1 = (float)(t->oy + t->bh - 1);
    /* voxel centres from the brick's lowest corner in float: a voxel lies
     * at most a brick from it, so this is as exact as the float result and,
     * depending on the brick alone, the same in every tile */
    float base[3], m[3][3];
    {
        const double idx0[3] = {br->i0, br->j0, br->k0};
        double p0[3];
        vs_camera_index_to_view0(&F->cam, idx0, p0);
        for (int r = 0; r < 3; r++) {
            base[r] = (float)p0[r];
            for (int a = 0; a < 3; a++) m[r][a] = (float)F->cam.M[r][a];
        }
    }
    const float near_z = (float)F->cam.near_z;
    const uint32_t row = (uint32_t)F->vol->dims[0], plane = row * (uint32_t)F->vol->dims[1];
    const uint32_t first = br->i0 + row * br->j0 + plane * br->k0; /* linear index of the brick's corner */
    const uint32_t code0 = F->ncode ? vs_normal_code_slot(F->vol, br->i0, br->j0, br->k0) : 0;
    /* transform and bin (a kernel); with perspective the box test follows
     * per voxel, as its footprint's size depends on its depth */
    vs_project_in P;
    memcpy(P.base, base, sizeof base);
    memcpy(P.m, m, sizeof m);
    P.px = px;
    P.py = py;
    P.bx0 = F->cam.persp ? -INFINITY : bx0;
    P.bx1 = F->cam.persp ? INFINITY : bx1;
    P.by0 = F->cam.persp ? -INFINITY : by0;
    P.by1 = F->cam.persp ? INFINITY : by1;
    uint16_t keep[VS_PROJECT_MAX];
    float xyz[3 * VS_PROJECT_MAX];
    const vs_voxel *vox = F->rel->voxels + br->start;
    const int nkeep = F->kern.project_brick(vox, (int)br->count, &P, keep, xyz);
    for (int q = 0; q < nkeep; q++) {
        const vs_voxel vx = vox[keep[q]];
        const uint32_t v = first + VS_VOXEL_DI(vx) + row * VS_VOXEL_DJ(vx) + plane * VS_VOXEL_DK(vx);
        const float x = xyz[3 * q], y = xyz[3 * q + 1], z = xyz[3 * q + 2];
        if (F->cam.persp) {
            float box[4] = {x, x, y, y}, sc = 1.0f;
            if (z - rz < near_z) continue; /* the kernel crosses the near plane */
            voxel_box(F, x, y, z, box, &sc);
            if (box[1] + px * sc < bx0 || box[0] - px * sc > bx1 || box[3] + py * sc < by0 || box[2] - py * sc > by1)
                continue; /* not this tile */
        }
        int kf = vs_ifloor((z - rz) / slab), kl = vs_ifloor((z + rz) / slab);
        if (kf < opening) kf = opening; /* rounding guard: the brick bound is conservative */
        if (kl > ts->kmax) kl = ts->kmax;
        if (kl < kf) continue;
        pend_bucket *bk = &ts->bk[kf - ts->kmin];
        if (bk->n == bk->cap && !grow_bucket(ts, bk)) {
            ts->failed = 1;
            return;
        }
        pend *e = &bk->p[bk->n++];
        e->x = x;
        e->y = y;
        e->z = z;
        e->v = v;
        e->c = code0 + vx;
        e->kl = kl;
        if (!F->use_blocks) F->stages->weights(F, e, 1u, (float(*)[4])e->w); /* else once it survives culling */
    }
}

/* Sections waiting to be placed together: where every section of a frame
 * (sheared_blocks) or of a sheet (perspective) comes from the same tables
 * and takes the fused kernels (raster_unskewed's case, not post-gs),
 * place_voxels places 16 at a time with their column and row factors, and
 * they are added in the order they came, as raster_unskewed adds them, to
 * the same floats. */
typedef struct section_batch {
    int n;
    float xyz[3 * VS_PLACE_BATCH]; /* the sections' centres */
    float w[VS_PLACE_BATCH][4];    /* weights times the depth integral */
    float *dst[VS_PLACE_BATCH];    /* sheet buffer and its touched box */
    rect *bb[VS_PLACE_BATCH];
} section_batch;

/* The placement input for a batch from tables g: no occlusion test (the
 * voxel's own stays) and no depth integrals (the sections have theirs):
 * a slab table of two rows of zeros stands in for the frame's, which only
 * the voxel-at-a-time paths make. */
static const float no_slab_rows[2 * 8];

static vs_place_in section_place_in(const tile_ctx *t, const vs_block_geom *g)
{
    vs_place_in P;
    memset(&P, 0, sizeof P);
    P.rx0 = g->rx0;
    P.ry0 = g->ry0;
    P.phases = (float)VS_BLOCK_PHASES;
    P.ox = t->ox;
    P.oy = t->oy;
    P.sd = no_slab_rows;
    P.sscale = 1.0f;
    P.sn = 1;
    P.sw = 8;
    P.nd = 1;
    P.colw = g->colw;
    P.roww = g->roww;
    P.bx = g->bx;
    P.ny = g->ny;
    return P;
}

/* Can sections from tables g go through a batch? */
static int sections_batched(const vs_frame *F, const vs_block_geom *g)
{
    return g && F->fp.row_shift == 0.0f && !F->stages->gradient_splats && g->bx <= VS_VOXEL1_MAX &&
           g->ny <= VS_VOXEL1_MAX;
}

static void flush_sections(tile_state *ts, section_batch *sb, const vs_place_in *P, const vs_block_geom *g)
{
    const tile_ctx *t = ts->t;
    const vs_frame *F = t->F;
    const int ch = F->stages->ch, ppv = 8 / ch;
    const int nvec = (g->nx * ch + 7) / 8; /* the footprint's vectors (nx pixels) */
    const ptrdiff_t ds = (ptrdiff_t)t->stride * ch;
    vs_placed pv;
    F->kern.place_voxels(sb->xyz, 3, sb->n, P, &pv);
    for (int l = 0; l < sb->n; l++) {
        const int bx = pv.bx[l], by = pv.by[l];
        int v0, v1, j0, j1;
        vs_clip_cols(t, bx, nvec, ppv, &v0, &v1);
        vs_clip_rows(t, by, g->ny, &j0, &j1);
        if (j0 >= j1 || v0 >= v1) continue;
        float *d = sb->dst[l] + (ptrdiff_t)(by + j0) * ds + (ptrdiff_t)(bx + v0 * ppv) * ch;
        const float *cw = pv.cw[l] + v0 * ppv, *rw = pv.rw[l] + j0;
        if (ch == 1)
            F->kern.splat_voxel1(&d, sb->w[l], 1, ds, cw, rw, j1 - j0, v1 - v0, g->thr);
        else
            F->kern.splat_voxel4(&d, sb->w[l], 1, ds, cw, rw, j1 - j0, v1 - v0, g->thr);
        const rect box = {bx + v0 * ppv, by + j0, bx + v1 * ppv, by + j1};
        rect_merge(sb->bb[l], &box);
        ts->ws->floats += 8 * (uint64_t)(j1 - j0) * (uint64_t)(v1 - v0);
    }
    sb->n = 0;
}

/* Queue a section (flushing a full batch first). */
static inline void queue_section(tile_state *ts, section_batch *sb, const vs_place_in *P, const vs_block_geom *g,
                                 const section *sec, const float *w4, float *dst, rect *bb)
{
    if (sb->n == VS_PLACE_BATCH) flush_sections(ts, sb, P, g);
    const int n = sb->n++, ch = ts->t->F->stages->ch;
    float *c = sb->xyz + 3 * n;
    c[0] = sec->cx;
    c[1] = sec->cy;
    c[2] = 0.0f; /* any depth: the stand-in slab table's rows are alike */
    for (int i = 0; i < ch; i++) sb->w[n][i] = w4[i] * sec->D;
    sb->dst[n] = dst;
    sb->bb[n] = bb;
}

/* Sheet at a time (general footprints): rasterize sheet k into `dst` from
 * the voxels overlapping it; retire those that ended, admit those that start
 * here, cull occluded ones. */
void vs_rasterize_sheet(tile_state *ts, int k, float *dst, rect *bb)
{
    const tile_ctx *t = ts->t;
    const vs_frame *F = t->F;
    const int persp = F->cam.persp;
    const sheet_geom sh = vs_sheet_geom(F, k);
    int keep = 0;
    for (int a = 0; a < ts->nactive; a++)
        if (ts->active[a]->kl >= k) {
            if (persp) memcpy(ts->abox[keep], ts->abox[a], sizeof *ts->abox);
            ts->active[keep++] = ts->active[a];
        }
    ts->nactive = keep;
    /* bucket k is complete (bricks open no later than their first sheet),
     * so its array no longer moves and the pointers stay valid */
    const pend_bucket *bk = &ts->bk[k - ts->kmin];
    for (int i = 0; i < bk->n; i++) {
        if (ts->nactive == ts->cap_active) {
            int cap = ts->cap_active ? 2 * ts->cap_active : 1024;
            pend **na = realloc(ts->active, (size_t)cap * sizeof *na);
            if (!na) {
                ts->failed = 1;
                return;
            }
            ts->active = na;
            ts->cap_active = cap;
        }
        /* the boxes have their own capacity: the lists outlive the frame
         * (vs_tile_scratch), and an orthographic frame grows only `active` */
        if (persp && ts->cap_abox < ts->cap_active) {
            float(*nb)[5] = realloc(ts->abox, (size_t)ts->cap_active * sizeof *nb);
            if (!nb) {
                ts->failed = 1;
                return;
            }
            ts->abox = nb;
            ts->cap_abox = ts->cap_active;
        }
        const pend *e = &bk->p[i];
        if (persp) /* the box of its sections over all its sheets */
            voxel_box(F, e->x, e->y, e->z, ts->abox[ts->nactive], &ts->abox[ts->nactive][4]);
        ts->active[ts->nactive++] = &bk->p[i];
    }
    /* perspective sheets whose sections take the fused kernels place
     * them in batches */
    const vs_block_geom *bg = sh.g;
    const int batched = persp && sections_batched(F, bg);
    section_batch sbat;
    sbat.n = 0;
    const vs_place_in P = batched ? section_place_in(t, bg) : (vs_place_in){0};
    for (int a = 0; a < ts->nactive; a++) {
        pend *e = ts->active[a];
        if (F->s->occlusion && *ts->opaque > 0) {
            float box[4] = {e->x, e->x, e->y, e->y}, sc = 1.0f;
            if (persp) {
                memcpy(box, ts->abox[a], sizeof box);
                sc = ts->abox[a][4];
            }
            ts->ws->tested++;
            if (box_occluded(t, ts->sat, box[0], box[1], box[2], box[3], sc)) {
                ts->ws->culled++;
                e->kl = k - 1; /* dropped at the next update */
                continue;
            }
        }
        section sec;
        if (!make_section(t, &sh, e->x, e->y, e->z, k, &sec)) continue;
        ts->ws->splatted++;
        if (batched) {
            queue_section(ts, &sbat, &P, bg, &sec, e->w, dst, bb);
        } else if (sec.g) {
            vs_raster_skewed(t, &sec, e->w, F->stages->ch, dst, bb, NULL);
        } else {
            F->stages->raster(t, &sec, e->w, dst, bb);
        }
    }
    if (sbat.n) flush_sections(ts, &sbat, &P, bg);
}

/* A voxel on the voxel-at-a-time path, placed in the tile's buffer: what
 * the pipeline's fused kernel needs to add its block to every sheet it
 * reaches (activate.c fills it; its pipeline's fused kernel adds it). */
typedef struct voxel_job {
    const tile_ctx *t;
    const vs_block_geom *g;
    const float *wv;          /* its splat weights before the depth integral  */
    const float *D, *E;       /* depth integrals of its sheets opening + j     */
    float ex, ey;             /* its centre (image pixels)                      */
    int opening, kl;          /* its first and last sheet                       */
    float *const *sheet;      /* the buffer of sheet opening + j (its ring slot) */
    rect *last;               /* by a voxel's last sheet reached (j), the union
                                 of those voxels' boxes: each slot's touched box
                                 grows once a sheet, not once a section        */
    rect box;                 /* the block's part inside the buffer             */
    ptrdiff_t off, ds;        /* its offset in a sheet, floats per buffer row   */
    int j0, j1, v0, v1;       /* its rows and vectors inside the buffer         */
    const vs_block_place *pl; /* its placement (phases, position)              */
    const float *colw, *roww; /* the voxel kernels' factors, or NULL            */
} voxel_job;

/* Voxel at a time: the sheets opening..kl that a voxel's block reaches with
 * a positive depth integral D[j] (j = k - opening): their
 * destinations (the block's offset in their ring slot) and weights wv[c] D
 * (nc channels); the box of the last one grown by the block's.
 * activate_sheet grows each sheet's box by the boxes of that sheet and
 * every later one: that covers every sheet a voxel writes, none lying
 * past its last (a sheet before it with D = 0 gets a box it did not need,
 * never one too small).  Returns how many.  Inlined with nc constant.
 * (Post-gs writes the same loop with its four gradient weights: through
 * this helper it measured 3 % slower.) */
static inline int reached_sheets(const voxel_job *j, int nc, float **dst, float *w)
{
    int ns = 0, last = -1;
    for (int i = 0; i <= j->kl - j->opening; i++) {
        const float Dk = j->D[i];
        if (!(Dk > 0.0f)) continue;
        dst[ns] = j->sheet[i] + j->off;
        for (int c = 0; c < nc; c++) w[nc * ns + c] = j->wv[c] * Dk;
        ns++;
        last = i;
    }
    if (last >= 0) rect_merge(&j->last[last], &j->box);
    return ns;
}

/* Density (post-cd, nc 1) or colour and opacity, or colour and density
 * (pre, post-alpha, nc 4): the block is built in registers and added to
 * every sheet in one kernel call.  Inlined with nc constant. */
static inline int splat_channels(const voxel_job *j, int nc)
{
    const int v0 = j->v0, v1 = j->v1, j0 = j->j0, j1 = j->j1;
    if (8 / nc * (v1 - v0) > VS_VOXEL1_MAX) return -1;
    const vs_block_geom *g = j->g;
    float *dst[VS_MAX_VSPAN], w[4 * VS_MAX_VSPAN];
    float cwb[VS_VOXEL1_MAX + 8], rwb[VS_BLOCK_MAX_SPAN];
    const float *cw = j->colw, *rw = j->roww;
    const int ns = reached_sheets(j, nc, dst, w);
    if (!cw) {
        vs_block_factors(g, j->pl, j0, j1, v0, v1, cwb, rwb);
        if (nc == 4) memset(cwb + 2 * (v1 - v0), 0, 8 * sizeof(float)); /* read up to a multiple of 8 */
        cw = cwb;
        rw = rwb;
    }
    if (nc == 1)
        j->t->F->kern.splat_voxel1(dst, w, ns, j->ds, cw, rw, j1 - j0, v1 - v0, g->thr);
    else
        j->t->F->kern.splat_voxel4(dst, w, ns, j->ds, cw, rw, j1 - j0, v1 - v0, g->thr);
    return ns;
}
static inline int splat_density(const voxel_job *j) { return splat_channels(j, 1); }
static inline int splat_rgba(const voxel_job *j) { return splat_channels(j, 4); }

/* A sheet's gradient-splat weights (raster_gs's, per unit of the layout
 * h, h dx, h dy, h): density, the x and y derivatives, the z one. */
static inline void gradient_weights(const float *wv, float D, float E, float A, float rk, float w[4])
{
    const float wD = wv[0] * D;
    w[0] = wD;
    w[1] = -2.0f * wD * A;
    w[2] = -2.0f * wD * rk;
    w[3] = wv[0] * E;
}

/* Gradient splats (post-gs): the block's rows (h, h dx, h dy, h) built in
 * registers and added to every sheet in one kernel call, with the weights
 * and offsets the block path uses; the depth integrals D and E come from
 * place_voxels.  Only with the voxel kernels' factors. */
static inline int splat_gradient(const voxel_job *j)
{
    const int v0 = j->v0, v1 = j->v1, j0 = j->j0, j1 = j->j1, ppv = 2;
    if (!j->colw || 2 * (v1 - v0) > VS_VOXEL1_MAX) return -1;
    const vs_block_geom *g = j->g;
    const vs_footprint *fp = &j->t->F->fp;
    const float A = fp->A, rk = fp->row_k;
    const float *wv = j->wv;
    float *dst[VS_MAX_VSPAN], w[4 * VS_MAX_VSPAN];
    int ns = 0, last = -1;
    for (int k = j->opening; k <= j->kl; k++) { /* as reached_sheets, with the gradient weights */
        const int i = k - j->opening;
        const float Dk = j->D[i];
        if (!(Dk > 0.0f)) continue;
        dst[ns] = j->sheet[i] + j->off;
        gradient_weights(wv, Dk, j->E[i], A, rk, &w[4 * ns]);
        ns++;
        last = i;
    }
    if (last >= 0) rect_merge(&j->last[last], &j->box);
    /* offsets from the centre (vs_block_build): column i lies
     * i + ux - rx0 away, row j lies j + uy - ry0 away */
    float dx[VS_VOXEL1_MAX + 8], dy[VS_BLOCK_MAX_SPAN];
    const float ux = vs_block_phase(j->ex, g->rx0, j->pl->x) - g->rx0,
                uy = vs_block_phase(j->ey, g->ry0, j->pl->y) - g->ry0;
    const int np = (v1 - v0) * ppv;
    for (int i = 0; i < np; i++) dx[i] = (float)(v0 * ppv + i) + ux;
    for (int i = np; i < np + 8; i++) dx[i] = 0.0f; /* read up to a multiple of 8 */
    for (int r = j0; r < j1; r++) dy[r - j0] = (float)r + uy;
    j->t->F->kern.splat_voxel_gs(dst, w, ns, j->ds, j->colw, j->roww, dx, dy, j1 - j0, v1 - v0, g->thr);
    return ns;
}

/* The block-in-memory fallback's weights for one sheet: eight floats, two
 * pixels of four channels or eight of one. */
static inline void weights8_density(const float wv[4], float D, float E, const vs_footprint *fp, float w8[8])
{
    float w = wv[0] * D;
    for (int c = 0; c < 8; c++) w8[c] = w;
}

static inline void weights8_gradient(const float wv[4], float D, float E, const vs_footprint *fp, float w8[8])
{
    gradient_weights(wv, D, E, fp->A, fp->row_k, w8);
    for (int c = 4; c < 8; c++) w8[c] = w8[c - 4];
}

static inline void weights8_rgba(const float wv[4], float D, float E, const vs_footprint *fp, float w8[8])
{
    for (int c = 0; c < 4; c++) w8[c] = w8[c + 4] = wv[c] * D;
}

/* Voxel at a time (separable footprints, and sheared_blocks below): each
 * voxel starting at sheet `opening` is tested once against the occlusion
 * map, builds its footprint block once (src/block.h) and adds it, weighted
 * by each slab's depth integral, to every sheet its kernel reaches; sheet k
 * lives in ring slot (k - kbase) mod R.  Only the block's rows inside the
 * buffer and its vectors that overlap it are built and added; a vector may
 * spill up to 8/ch - 1 pixels into the apron.  Sheared axis-aligned footprints
 * (sheared_blocks) are tested once the same way, then each section is
 * placed at its own centre and added to its sheet (raster_skewed). */
static inline __attribute__((always_inline)) void activate_sheet(tile_state *ts, int opening, float *const *ring,
                                                                  rect *bbs, int R, int kbase, const int ch,
                                                                  int (*splat_voxel)(const voxel_job *),
                                                                  void (*weights8)(const float *, float, float,
                                                                                   const vs_footprint *, float *))
{
    /* the counts in locals, added to the worker's once per sheet: a store
     * through ts->ws per voxel would make the compiler reload ts's fields */
    uint64_t n_culled = 0, n_tested = 0, n_splatted = 0, n_vec = 0;
    const tile_ctx *t = ts->t;
    const vs_frame *F = t->F;
    const vs_block_geom *g = F->sheared_blocks ? &F->skew : &F->blk;
    const vs_stages *st = F->stages;
    /* ch (the stages' channels) is each instance's constant: every voxel's
     * block bounds are divided by 8 / ch, a shift rather than a division */
    const int ppv = 8 / ch, bs = 8 * g->nvec;
    /* ring slots and buffers of the sheets from `opening` on: every voxel
     * of this bucket starts there (one division per sheet, not per
     * section) */
    int slots[VS_MAX_VSPAN];
    float *sheet[VS_MAX_VSPAN];
    for (int j = 0; j < VS_MAX_VSPAN && j < R; j++) {
        slots[j] = (opening + j - kbase) % R;
        sheet[j] = ring[slots[j]];
    }
    const char *vdata = F->vol->data;
    const size_t vsize = vs_type_size(F->vol->type);
    const size_t plane = (size_t)F->vol->dims[0] * (size_t)F->vol->dims[1], nvox = plane * (size_t)F->vol->dims[2];
    pend_bucket *bk = &ts->bk[opening - ts->kmin];
    /* occlusion test, placement and depth integrals a batch of voxels at a
     * time (a SIMD kernel); the occlusion map does not change while a
     * sheet is activated, so batching culls exactly what one by one did */
    const float slab = (float)F->fp.slab, rz = (float)F->fp.rz;
    const int nd = F->fp.vspan; /* sheets one kernel can reach */
    /* the voxel kernels' factors, for blocks they take whole */
    const float *colw = !F->sheared_blocks && g->bx <= VS_VOXEL1_MAX && g->ny <= VS_VOXEL1_MAX ? g->colw : NULL;
    /* sheared_blocks sections through the fused kernels: placed in batches,
     * their D and E from the voxel's row of the slab tables */
    const int batched = F->sheared_blocks && sections_batched(F, g);
    const vs_place_in P = {.sat = F->s->occlusion && *ts->opaque > 0 ? ts->sat : NULL,
                           .tx0 = t->x0, .ty0 = t->y0, .tw = t->tw, .th = t->th,
                           .pad_x = (float)F->pad_x, .pad_y = (float)F->pad_y,
                           .rx0 = g->rx0, .ry0 = g->ry0, .phases = (float)VS_BLOCK_PHASES,
                           .ox = t->ox, .oy = t->oy, .slab = slab, .rz = rz,
                           .sd = F->fp.slab_d, .se = F->fp.slab_e, .sscale = F->fp.slab_scale,
                           .sn = F->fp.slab_n, .sw = F->fp.slab_w,
                           /* E: post-gs voxels (sheared_blocks sections make their own) */
                           .with_e = (st->gradient_splats && !F->sheared_blocks) || batched,
                           .opening = opening, .nd = nd < VS_MAX_VSPAN ? nd : VS_MAX_VSPAN,
                           .colw = colw,
                           .roww = g->roww, .bx = g->bx, .ny = g->ny};
    const sheet_geom unscaled = {g, 1.0f, 1.0f}; /* sheared_blocks: orthographic sections */
    const vs_place_in Ps = batched ? section_place_in(t, g) : (vs_place_in){0};
    section_batch sbat;
    sbat.n = 0;
    rect last[VS_MAX_VSPAN]; /* voxel_job last */
    for (int j = 0; j < P.nd; j++) rect_clear(&last[j]);
    vs_placed pv;
    for (int i0 = 0; i0 < bk->n; i0 += VS_PLACE_BATCH) {
        const int nb = bk->n - i0 < VS_PLACE_BATCH ? bk->n - i0 : VS_PLACE_BATCH;
        /* a voxel's value is a cache miss in the volume: ask for the batch's
         * values before placing it */
        for (int l = 0; l < nb; l++) __builtin_prefetch(vdata + (size_t)bk->p[i0 + l].v * vsize);
        if (st->pre_shaded) /* and the neighbours its gradient reads in the planes before and after */
            for (int l = 0; l < nb; l++) {
                const size_t v = bk->p[i0 + l].v;
                if (v >= plane) __builtin_prefetch(vdata + (v - plane) * vsize);
                if (v + plane < nvox) __builtin_prefetch(vdata + (v + plane) * vsize);
            }
        unsigned live = F->kern.place_voxels(&bk->p[i0].x, (int)(sizeof(pend) / sizeof(float)), nb, &P, &pv);
        n_culled += (uint64_t)(nb - __builtin_popcount(live));
        if (P.sat) n_tested += (uint64_t)nb;
        /* the splat weights of the batch's live voxels first: pre-shaded
         * ones read the shading tables at random (cache misses), which one
         * voxel at a time waited for between footprint adds */
        float wvs[VS_PLACE_BATCH][4];
        st->weights(F, bk->p + i0, live, wvs);
        for (; live; live &= live - 1) {
            const int lane = __builtin_ctz(live);
            const pend *e = &bk->p[i0 + lane];
            const int kl = e->kl < opening + P.nd - 1 ? e->kl : opening + P.nd - 1;
            if (F->sheared_blocks) {
                /* each section at its own centre (the kernel's centroid in
                 * its slab), placed and added as on the sheet-at-a-time
                 * path, into its sheet of the ring */
                const float *w4 = wvs[lane];
                unskewed_cols uc; /* shared by its sections when only y moves */
                uc.g = NULL;
                for (int k = opening; k <= kl; k++) {
                    section sec;
                    if (batched) {
                        const float D = pv.D[lane][k - opening];
                        if (!(D > 0.0f)) continue;
                        float c0, c1;
                        section_ends(&F->fp, e->z, k, &c0, &c1);
                        place_section(t, &unscaled, e->x, e->y, D, pv.E[lane][k - opening], c0, c1, &sec);
                    } else if (!make_section(t, &unscaled, e->x, e->y, e->z, k, &sec)) {
                        continue;
                    }
                    n_splatted++;
                    const int slot = slots[k - opening];
                    if (batched)
                        queue_section(ts, &sbat, &Ps, g, &sec, w4, sheet[k - opening], &bbs[slot]);
                    else
                        vs_raster_skewed(t, &sec, w4, ch, sheet[k - opening], &bbs[slot], &uc);
                }
                continue;
            }
            /* rows [j0, j1) and vectors [v0, v1) of the block inside the buffer */
            const int by = pv.by[lane], bx = pv.bx[lane];
            int j0, j1, v0, v1;
            vs_clip_rows(t, by, g->ny, &j0, &j1);
            vs_clip_cols(t, bx, g->nvec, ppv, &v0, &v1);
            if (j0 >= j1 || v0 >= v1) continue;
            /* the factor paths read only the phase rows and weights; the
             * gradient layout and the block fallback set the phases too */
            vs_block_place pl_ = {.x = bx + t->ox, .y = by + t->oy, .qx = pv.qx[lane], .qy = pv.qy[lane],
                                  .fx = pv.fx[lane], .fy = pv.fy[lane]};
            const voxel_job job = {.t = t, .g = g, .wv = wvs[lane], .D = pv.D[lane], .E = pv.E[lane],
                                   .ex = e->x, .ey = e->y, .opening = opening, .kl = kl,
                                   .sheet = sheet, .last = last,
                                   .box = {bx + v0 * ppv, by + j0, bx + v1 * ppv, by + j1},
                                   .off = (ptrdiff_t)(by + j0) * ((ptrdiff_t)t->stride * ch) +
                                          (ptrdiff_t)(bx + v0 * ppv) * ch,
                                   .ds = (ptrdiff_t)t->stride * ch, .j0 = j0, .j1 = j1, .v0 = v0, .v1 = v1,
                                   .pl = &pl_,
                                   /* the factors of the block's part inside the buffer */
                                   .colw = P.colw ? pv.cw[lane] + v0 * ppv : NULL,
                                   .roww = P.colw ? pv.rw[lane] + j0 : NULL};
            const int ns = splat_voxel(&job);
            if (ns >= 0) {
                n_splatted += (uint64_t)ns;
                n_vec += (uint64_t)ns * (uint64_t)((j1 - j0) * (v1 - v0));
                continue;
            }
            /* a block too wide for the voxel kernels: built in memory once
             * (vs_block_place_at's phases, for the gradient layout) and
             * added to each sheet */
            pl_.ux = vs_block_phase(e->x, g->rx0, pl_.x);
            pl_.uy = vs_block_phase(e->y, g->ry0, pl_.y);
            vs_block_build(g, &pl_, j0, j1, v0, v1, t->blk);
            const float *src = t->blk + (size_t)j0 * bs + 8 * v0;
            for (int k = opening; k <= kl; k++) {
                const float D = pv.D[lane][k - opening];
                if (!(D > 0.0f)) continue;
                n_splatted++;
                const int slot = slots[k - opening];
                float w8[8];
                weights8(job.wv, D, st->gradient_splats ? pv.E[lane][k - opening] : 0.0f, &F->fp, w8);
                F->kern.splat_block(sheet[k - opening] + job.off, job.ds, src, bs, j1 - j0, v1 - v0, w8);
                n_vec += (uint64_t)((j1 - j0) * (v1 - v0));
                rect_merge(&bbs[slot], &job.box);
            }
        }
    }
    if (sbat.n) flush_sections(ts, &sbat, &Ps, g);
    /* sheet opening + j is touched by the voxels whose last sheet is j or later */
    rect grow;
    rect_clear(&grow);
    for (int j = P.nd - 1; j >= 0; j--) {
        rect_merge(&grow, &last[j]);
        rect_merge(&bbs[slots[j]], &grow);
    }
    vs_worker_stats *ws = ts->ws;
    ws->culled += n_culled;
    ws->tested += n_tested;
    ws->splatted += n_splatted;
    ws->floats += 8 * n_vec; /* 8-float vectors */
    retire_bucket(ts, bk);
}

/* The pipelines' instances, each with its fused kernel inlined. */
void vs_activate_density(tile_state *ts, int opening, float *const *ring, rect *bbs, int R, int kbase)
{
    activate_sheet(ts, opening, ring, bbs, R, kbase, 1, splat_density, weights8_density);
}

void vs_activate_rgba(tile_state *ts, int opening, float *const *ring, rect *bbs, int R, int kbase)
{
    activate_sheet(ts, opening, ring, bbs, R, kbase, 4, splat_rgba, weights8_rgba);
}

void vs_activate_gradient(tile_state *ts, int opening, float *const *ring, rect *bbs, int R, int kbase)
{
    activate_sheet(ts, opening, ring, bbs, R, kbase, 4, splat_gradient, weights8_gradient);
}
