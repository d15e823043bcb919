/* A splatted frame (render.h): set up the frame (camera, lighting, kernel
 * tables, relevant voxels), transform and bin the voxels into tiles, run
 * the tiles on the worker pool, and sum the workers' statistics.  The
 * settings' checks and the choice of what is splatted: render_entry.c. */
#include "context.h"
#include "timing.h"
#include "finish.h"
#include "normal_code.h"
#include "render.h"
#include "gs_ripple.h"
#include "pool.h"
#include "preintegrate.h"
#include "resample.h"
#include "tile.h"
#include "trace.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct bin_job {
    vs_frame *F;
    int nchunks;
    uint32_t *counts;  /* nchunks * ntiles */
    int fill;          /* 0: transform + count, 1: fill */
} bin_job;

/* Tiles that a box of voxel centres [x0,x1] x [y0,y1] can reach with its
 * footprints (and the seam the in-sheet differences read), footprints
 * scaled by at most sc (perspective). */
static inline int tile_range(const vs_frame *F, float x0, float x1, float y0, float y1, float sc, int *tx0,
                             int *tx1, int *ty0, int *ty1)
{
    const int W = F->cam.width, H = F->cam.height;
    float px, py;
    vs_frame_reach(F, sc, &px, &py);
    if (!(x1 + px >= 0.0f) || !(x0 - px <= (float)(W - 1)) || !(y1 + py >= 0.0f) || !(y0 - py <= (float)(H - 1)))
        return 0; /* off screen (also rejects NaN) */
    int a = (int)floorf((x0 - px) / (float)F->tile);
    int b = (int)floorf((x1 + px) / (float)F->tile);
    int c = (int)floorf((y0 - py) / (float)F->tile);
    int d = (int)floorf((y1 + py) / (float)F->tile);
    *tx0 = a < 0 ? 0 : a;
    *tx1 = b >= F->tiles_x ? F->tiles_x - 1 : b;
    *ty0 = c < 0 ? 0 : c;
    *ty1 = d >= F->tiles_y ? F->tiles_y - 1 : d;
    return 1;
}

static void bin_task(void *arg, int worker, int c)
{
    bin_job *J = arg;
    vs_frame *F = J->F;
    size_t n = F->rel->nbricks;
    size_t b0 = n * (size_t)c / J->nchunks, b1 = n * (size_t)(c + 1) / J->nchunks;
    uint32_t *cnt = J->counts + (size_t)c * F->ntiles;
    const vs_camera *cam = &F->cam;
    for (size_t b = b0; b < b1; b++) {
        struct vs_brick_view *bv = &F->bview[b];
        if (!J->fill) {
            /* the view-space box of the brick's corner voxel centres (the
             * depth-0 image box when perspective) */
            const vs_brick *br = &F->rel->bricks[b];
            double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
            for (int corner = 0; corner < 8; corner++) {
                double idx[3] = {corner & 1 ? br->i1 : br->i0, corner & 2 ? br->j1 : br->j0,
                                 corner & 4 ? br->k1 : br->k0},
                       p[3];
                vs_camera_index_to_view0(cam, idx, p);
                for (int a = 0; a < 3; a++) {
                    if (p[a] < lo[a]) lo[a] = p[a];
                    if (p[a] > hi[a]) hi[a] = p[a];
                }
            }
            /* perspective: a section's centre moves with its sheet's depth,
             * over the depths the kernels reach; voxels whose kernel crosses
             * the near plane are dropped (src/activate.c), and so is a brick of
             * only such voxels */
            const double rz = F->fp.rz, reach = rz + 0.5 * F->fp.slab; /* sheet middles */
            double zn = lo[2] - reach > cam->near_z ? lo[2] - reach : cam->near_z, box[4];
            vs_camera_depth_box(cam, lo[0], hi[0], lo[1], hi[1], zn, hi[2] + reach, box);
            bv->sc = (float)vs_camera_scale(cam, zn);
            /* widen by float rounding so that every voxel centre, computed
             * in the tile, lies inside */
            bv->x0 = (float)box[0] - 1e-3f;
            bv->x1 = (float)box[1] + 1e-3f;
            bv->y0 = (float)box[2] - 1e-3f;
            bv->y1 = (float)box[3] + 1e-3f;
            bv->z0 = (float)lo[2] - 1e-3f;
            bv->z1 = (float)hi[2] + 1e-3f;
            /* the sheets its kernels reach, for every tile it is binned to */
            const float fslab = (float)F->fp.slab, frz = (float)F->fp.rz;
            bv->kf = (int)floorf((bv->z0 - frz) / fslab);
            bv->kl = (int)floorf((bv->z1 + frz) / fslab);
            if (hi[2] - rz < cam->near_z) bv->x0 = bv->x1 = bv->y0 = bv->y1 = NAN;
        }
        /* a depth band: bricks no shown sheet reads are not binned */
        if (bv->kl < F->show0 - 2 || bv->kf > F->show1 + 1) continue;
        int tx0, tx1, ty0, ty1;
        if (!tile_range(F, bv->x0, bv->x1, bv->y0, bv->y1, bv->sc, &tx0, &tx1, &ty0, &ty1)) continue;
        for (int ty = ty0; ty <= ty1; ty++)
            for (int tx = tx0; tx <= tx1; tx++) {
                int t = ty * F->tiles_x + tx;
                if (J->fill)
                    F->tile_entries[cnt[t]++] = (uint32_t)b;
                else
                    cnt[t]++;
            }
    }
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}


/* Perspective: skewed tables for sheet sheet_k0 + i, the footprint scaled
 * by the sheet's depth.  A sheet whose footprint is too large for tables,
 * or whose tables cannot be allocated, keeps ny = 0 and is splatted with an
 * exponential per pixel. */
static void sheet_skew_task(void *arg, int worker, int i)
{
    (void)worker;
    vs_frame *F = arg;
    const float s = (float)vs_camera_sheet_scale(&F->cam, F->sheet_k0 + i, F->fp.slab);
    const vs_footprint f = vs_footprint_scaled(&F->fp, s);
    vs_block_geom *g = &F->sheet_skew[i];
    if (!vs_block_setup_skewed(g, &f)) {
        vs_block_free(g);
        memset(g, 0, sizeof *g);
    }
}

/* Perspective: a sheet's footprints all share its depth's scale, so each
 * sheet the bricks reach gets skewed tables of its own (after the bricks'
 * view boxes are known), built on the pool.  All of them together stay
 * within 4 M floats (16 MB, and as many entries to compute a frame); a
 * close-up beyond that keeps the exponential per pixel.  Without tables
 * nothing changes: use_skewed stays as it was. */
/* A skewed block is built whole for each section, then clipped to its
 * tile: worth it while a footprint is not much larger than the image.  A
 * close-up far beyond that (fuzz_render: 6x9 pixels at zoom 185, slab
 * 0.027, took 417 s building 10^4 blocks of ~10^6 floats for a few pixels
 * each) keeps the exponential per pixel, which costs the clipped area. */
static int skewed_block_fits(const vs_camera *cam, double nx, double ny)
{
    return nx * ny <= 4.0 * cam->width * cam->height + 4096.0;
}

static void setup_sheet_tables(vs_frame *F, struct vs_pool *pool, int ch)
{
    int k0 = INT_MAX, k1 = INT_MIN;
    for (size_t b = 0; b < F->rel->nbricks; b++) {
        if (isnan(F->bview[b].x0)) continue; /* behind the near plane */
        if (F->bview[b].kf < k0) k0 = F->bview[b].kf;
        if (F->bview[b].kl > k1) k1 = F->bview[b].kl;
    }
    if (k0 > k1 || (long)k1 - k0 >= 65536) return;
    const double det = (double)F->fp.A * F->fp.C - (double)F->fp.B * F->fp.B;
    const double rx = sqrt(F->fp.emax / F->fp.A), ry = sqrt(F->fp.emax * F->fp.A / det); /* at scale 1 */
    double floats = 0.0;
    for (int k = k0; k <= k1; k++) {
        const double sc = vs_camera_sheet_scale(&F->cam, k, F->fp.slab);
        floats += (VS_BLOCK_PHASES + 1) * (2.0 * (rx + ry) * sc + 10); /* columns (8-padded) + rows */
        if (!skewed_block_fits(&F->cam, 2.0 * rx * sc + 1, 2.0 * ry * sc + 1)) return;
    }
    if (floats > 4.0 * (1 << 20)) return;
    F->sheet_skew = calloc((size_t)(k1 - k0 + 1), sizeof *F->sheet_skew);
    if (!F->sheet_skew) return;
    F->sheet_k0 = k0;
    F->nsheet_skew = k1 - k0 + 1;
    vs_pool_run(pool, F->nsheet_skew, sheet_skew_task, F);
    for (int i = 0; i < F->nsheet_skew; i++) {
        const vs_block_geom *g = &F->sheet_skew[i];
        if (g->ny <= 0) continue;
        const int gv = vs_block_skewed_nvec(g, F->fp.row_shift, ch);
        if (gv > F->skew_maxvec) F->skew_maxvec = gv;
        if (g->ny > F->skew_maxrows) F->skew_maxrows = g->ny;
        F->use_skewed = 1;
    }
}

/* One tile scratch per worker, kept by the context across frames. */
static vs_tile_scratch *ensure_scratch(vs_context *ctx, int nthreads)
{
    if (ctx->nscratch < nthreads) {
        vs_tile_scratch *a = realloc(ctx->scratch, (size_t)nthreads * sizeof *a);
        if (!a) return NULL;
        memset(a + ctx->nscratch, 0, (size_t)(nthreads - ctx->nscratch) * sizeof *a);
        ctx->scratch = a;
        ctx->nscratch = nthreads;
    }
    return ctx->scratch;
}

/* The bytes each stage reads and writes by construction, from the work
 * counts (px: pixels classified, vis: of those with opacity):
 *   rasterize   every footprint float added is read and written;
 *   gradient    post-cd reads the density of three sheets and writes opacity
 *               and gradient (16 B); post-gs reads its four channels and
 *               writes the same; pre and post-alpha read one channel and
 *               write the opacity;
 *   shade       reads every pixel's opacity and, where it is not 0, the
 *               gradient and density (post) or the splatted colour (pre,
 *               post-alpha), and writes a colour (pre: and the opacity);
 *   composite   reads every pixel's opacity and, where it is not 0, the
 *               accumulator and colour, and writes the accumulator. */
static void stage_bytes(const vs_frame *F, vs_stats *st)
{
    const uint64_t px = st->pixels_classified, vis = st->pixels_shaded;
    st->bytes_read.rasterize = 4 * st->footprint_floats;
    st->bytes_written.rasterize = 4 * st->footprint_floats;
    switch (F->pipeline) {
    case VS_PIPELINE_POST_CD:
    case VS_PIPELINE_POST_GS:
        st->bytes_read.gradient = (F->pipeline == VS_PIPELINE_POST_CD ? 12 : 16) * px;
        st->bytes_written.gradient = 16 * px;
        st->bytes_read.shade = 4 * px + 16 * vis;
        st->bytes_written.shade = 12 * vis;
        break;
    default: /* pre-shaded */
        st->bytes_read.gradient = 4 * px;
        st->bytes_written.gradient = 4 * px;
        st->bytes_read.shade = 4 * px + 12 * vis;
        st->bytes_written.shade = (F->pipeline == VS_PIPELINE_PRE ? 16 : 12) * vis;
        break;
    }
    st->bytes_read.composite = 4 * px + 28 * vis;
    st->bytes_written.composite = 16 * vis;
}

static void free_frame(vs_frame *F, int nspans)
{
    for (int w = 0; F->spans && w < nspans; w++) free(F->spans[w].s);
    free(F->spans);
    vs_footprint_free(&F->fp);
    vs_block_free(&F->blk);
    vs_block_free(&F->skew);
    for (int i = 0; i < F->nsheet_skew; i++) vs_block_free(&F->sheet_skew[i]);
    free(F->sheet_skew);
    free(F->cls);
    free(F->bview);
    free(F->tile_start);
    free(F->tile_entries);
    free(F->tile_order);
    free(F->wstats);
}

vs_status vs_render_splat(vs_context *ctx, const struct vs_volume *vol, const struct vs_volume *full,
                          vs_classify *cls, struct vs_relevant_cache **rel_slot, const vs_settings *s,
                          const vs_lod_band *band, const float *under, vs_image *out, vs_stats *st,
                          const double *lod_span)
{
    double t_start = vs_now_ms();
    vs_frame F;
    memset(&F, 0, sizeof F);
    F.cls = cls;
    F.s = s;
    F.pipeline = s->pipeline;
    for (int i = 0; i < 3; i++) F.spacing[i] = vol->spacing[i];
    vs_status rc;
    float *image = NULL;
    bin_job J = {0};

    if ((rc = vs_camera_setup(ctx, vol, s, &F.cam)) != VS_OK) goto fail;
    vs_light_setup(s, &F.cam, &F.light);
    {
        /* the settings and VSPLAT_ISA both cap the instruction set */
        vs_isa cap = s->isa, env = vs_isa_from_env();
        if (env != VS_ISA_AUTO && (cap == VS_ISA_AUTO || env < cap)) cap = env;
        vs_kernels_init(&F.kern, cap);
    }
    if ((rc = vs_footprint_setup(ctx, s, &F.cam, &F.fp)) != VS_OK) goto fail;
    F.show0 = -(1 << 30);
    F.show1 = 1 << 30;
    if (band) vs_lod_band_sheets(band, F.cam.z_per_mm, F.fp.slab, &F.show0, &F.show1);
    if (F.cam.persp) { /* the sheets near the near plane miss the voxels dropped there */
        const int k0 = (int)lrint(vs_camera_near_cut(&F.cam, F.fp.R, F.fp.slab) / F.fp.slab);
        if (k0 > F.show0) F.show0 = k0;
    }
    F.under = under;
    {
        /* separable footprints go voxel at a time with footprint blocks
         * (and sheared axis-aligned ones with a section per sheet, below),
         * when a ring of sheets holds every sheet one kernel reaches and a
         * block stays small (else the general sheet-at-a-time path, which
         * also serves perspective, where a footprint's size varies with
         * its depth) */
        const int vspan = F.fp.vspan;
        int ch = s->pipeline == VS_PIPELINE_POST_CD ? 1 : 4;
        double det = (double)F.fp.A * F.fp.C - (double)F.fp.B * F.fp.B;
        double nx = 2.0 * sqrt(F.fp.emax * F.fp.C / det) + 1, ny = 2.0 * sqrt(F.fp.emax * F.fp.A / det) + 1;
        if (F.fp.separable && !F.cam.persp && vspan <= VS_MAX_VSPAN && nx <= VS_BLOCK_MAX_SPAN && ny <= VS_BLOCK_MAX_SPAN &&
            nx * ny * ch <= (double)(1 << 20)) {
            if (!vs_block_setup(&F.blk, &F.fp, ch, s->pipeline == VS_PIPELINE_POST_GS)) {
                rc = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "footprint blocks: out of memory");
                goto fail;
            }
            F.use_blocks = 1;
        } else if (!F.cam.persp && nx <= VS_BLOCK_MAX_SPAN && ny <= VS_BLOCK_MAX_SPAN && skewed_block_fits(&F.cam, nx, ny)) {
            /* sheet at a time, one block per section from skewed phase
             * tables instead of an exponential per pixel (without the
             * tables, e.g. when out of memory, the exponential path serves) */
            F.use_skewed = vs_block_setup_skewed(&F.skew, &F.fp);
            F.skew_maxvec = vs_block_skewed_nvec(&F.skew, F.fp.row_shift,
                                                 s->pipeline == VS_PIPELINE_POST_CD ? 1 : 4);
            F.skew_maxrows = F.skew.ny;
            /* an axis-aligned ellipse whose centre only moves with depth
             * (anisotropic voxels turned about their odd axis, the CT head's
             * case): voxel at a time too, one occlusion test a voxel and
             * each section added to its sheet of the ring at once, instead
             * of an active list walked and tested sheet by sheet (CT head,
             * 2 threads: post-cd 179 -> 168 ms, post-alpha 272 -> 256 ms,
             * pre the same; post-gs lost more to the coarser culling than it
             * saved while each section built a block, 418 -> 430 ms, and
             * gains since splat_rows_mix builds none: 1 thread 517 -> 469 ms) */
            F.sheared_blocks = F.use_skewed && F.fp.sheared && F.fp.B == 0.0f && vspan <= VS_MAX_VSPAN;
            F.use_blocks = F.sheared_blocks;
        }
        if (F.use_blocks && (rc = vs_footprint_slab_tables(ctx, s, &F.fp)) != VS_OK) goto fail;
    }
    if (!s->exact_normals) {
        /* the context's tables (kept across frames); the frame reads a copy
         * of their pointers */
        if (!ctx->shade_lut && !(ctx->shade_lut = calloc(1, sizeof *ctx->shade_lut))) {
            rc = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "shading tables: out of memory");
            goto fail;
        }
        if ((rc = vs_shade_lut_setup(ctx, s->normal_lut_size, &F.light, ctx->shade_lut)) != VS_OK) goto fail;
        F.lut = *ctx->shade_lut;
        if (s->pipeline == VS_PIPELINE_PRE || s->pipeline == VS_PIPELINE_POST_ALPHA) {
            if (!ctx->normal_table && !(ctx->normal_table = calloc(1, sizeof *ctx->normal_table))) {
                rc = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "shading tables: out of memory");
                goto fail;
            }
            if ((rc = vs_normal_table_setup(ctx, &F.light, F.cam.right, F.cam.up, F.cam.dir, ctx->normal_table)) != VS_OK)
                goto fail;
            F.nterms = (const float(*)[2])ctx->normal_table->terms;
        }
    }
    /* opacity is per unit of the full volume's finest spacing; a level's
     * view unit is its own finest spacing, so a slab is that much longer */
    const double slab_len = s->slab * (vs_volume_finest(vol) / vs_volume_finest(full));
    for (int i = 0; i < VS_TF_TABLE; i++)
        F.alpha_corr[i] = (float)vs_opacity_correct(F.cls->alpha[i], slab_len);
    F.alpha_zero_x = vs_alpha_zero_x(F.alpha_corr);
    for (int i = 0; i <= 1024; i++) F.opacity_corr[i] = (float)vs_opacity_correct(i / 1024.0, slab_len);

    /* relevant voxels: pre-shaded splatting needs only the in-range voxels;
     * the post-classified pipelines need the seam layer too (paper §4.3) */
    int seam = s->seam >= 0 ? s->seam : (int)ceil(s->kernel_radius);
    if (s->pipeline == VS_PIPELINE_PRE && s->seam < 0) seam = 0;
    /* a crop face inside the volume clips; the volume's own faces clip only
     * when the fall-off to the value outside would show (vs_classify_faces),
     * as without a crop box */
    F.base = s->pipeline == VS_PIPELINE_PRE ? 0.0 : vs_volume_base(full);
    const int faces = s->pipeline != VS_PIPELINE_PRE && vs_classify_faces(F.cls, F.base, full->vmax);
    F.clip_to_volume = faces || s->has_crop;
    /* there sheets are divided near the faces by the share of the voxels
     * inside them (face_cover.h); the cubic copy and its levels reach past
     * the faces (their voxels there hold the fall-off), so the volume's own
     * grid's, with the kernel as wide as the splatted grid's voxels */
    double lo_faces[3], hi_faces[3];
    int past = 0;
    for (int a = 0; a < 3; a++) {
        /* the full volume's faces (index -0.5 and dims - 0.5) in the
         * splatted volume's index (a level or the cubic copy) */
        lo_faces[a] = vs_volume_index_in(full, vol, a, -0.5);
        hi_faces[a] = vs_volume_index_in(full, vol, a, full->dims[a] - 0.5);
        past |= lo_faces[a] > 0.0 || hi_faces[a] < vol->dims[a] - 1;
    }
    F.cover = faces ? (past ? full : vol) : NULL;
    for (int a = 0; a < 3; a++) {
        const int cut_lo = s->has_crop && s->crop_lo[a] > 0, cut_hi = s->has_crop && s->crop_hi[a] < vol->dims[a];
        const double lo_face = lo_faces[a], hi_face = hi_faces[a];
        F.clip_lo[a] = cut_lo ? s->crop_lo[a] - 0.5 : faces ? lo_face : -INFINITY;
        F.clip_hi[a] = cut_hi ? s->crop_hi[a] - 0.5 : faces ? hi_face : INFINITY;
        F.clip_hi_open[a] = cut_hi;
        if (F.cover) { /* its voxels inside the faces */
            const double lo = past ? 0.0 : ceil(lo_face), hi = past ? full->dims[a] - 1 : floor(hi_face);
            F.cover_in0[a] = lo > 0.0 ? (int)lo : 0;
            F.cover_in1[a] = hi < F.cover->dims[a] - 1 ? (int)hi : F.cover->dims[a] - 1;
            F.cover_scale[a] = past ? fmax(1.0, vol->spacing[a] / full->spacing[a]) : 1.0;
        }
    }
    int rebuilt = 0;
    if ((rc = vs_context_pool(ctx, s)) != VS_OK) goto fail;
    {
        /* pre-integration pays where the classification is translucent:
         * there opacity changes within a slab faster than one sample a slab
         * follows (rings); an opaque iso-range stops at its first sheets */
        const int post = s->pipeline == VS_PIPELINE_POST_CD || s->pipeline == VS_PIPELINE_POST_GS ||
                         s->pipeline == VS_PIPELINE_POST_ALPHA;
        const int want = s->preintegration >= 0 ? s->preintegration : (s->tf_count > 0 || s->iso_opacity < 1.0f);
        if (post && want) {
            /* the table of this slab (halves), else the next one replaced */
            int slot = -1;
            for (int i = 0; i < VS_PREINT_KEEP; i++)
                if (ctx->preint[i] && ctx->preint[i]->key_slab == 0.5 * slab_len) slot = i;
            if (slot < 0) {
                slot = ctx->preint_next;
                ctx->preint_next = (slot + 1) % VS_PREINT_KEEP;
            }
            if (!ctx->preint[slot] && !(ctx->preint[slot] = calloc(1, sizeof *ctx->preint[slot]))) {
                rc = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "pre-integration table: out of memory");
                goto fail;
            }
            if (!vs_preint_update(ctx->preint[slot], F.cls, 0.5 * slab_len, ctx->pool)) {
                rc = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "pre-integration table: out of memory");
                goto fail;
            }
            F.preint = ctx->preint[slot];
        }
        /* post-cd's differences within and across sheets (footprint.c);
         * across, plain sheets alone (vsplat-mpi's ghosts then reach two
         * sheets), and not in depth bands, where it is not measured */
        F.cd_wide = s->pipeline != VS_PIPELINE_POST_CD ? 0.0f
                    : s->cd_stencil == 2      ? 0.0f
                    : s->cd_stencil == 4      ? 1.0f / 12.0f
                                              : vs_cd_wide(&F.fp);
        F.cd_wide_z = s->pipeline != VS_PIPELINE_POST_CD || F.preint || band || s->cd_stencil == 2
                          ? 0.0f
                      : s->cd_stencil == 4 ? 1.0f / 12.0f
                                           : vs_cd_wide_z(&F.fp, s->slab);
        F.stages = vs_pipeline_stages(s->pipeline, s->exact_normals, F.preint != NULL, F.cd_wide_z > 0.0f);
        vs_gs_ripple_setup(&F);
    }
    double t_rel = vs_now_ms();
    if ((rc = vs_relevant_get(ctx, rel_slot, ctx->pool, vol, F.cls, seam, &F.rel, &rebuilt)) != VS_OK) goto fail;
    const double t_rel_end = vs_now_ms();
    double ms_relevant = rebuilt ? t_rel_end - t_rel : 0.0;
    F.vol = vol;
    if (F.nterms) {
        F.ncode = vs_normal_codes_get(ctx, vol);
        vs_normal_code_scale(vol, F.nscale);
    }
    int nthreads = vs_pool_threads(ctx->pool);
    if (s->trace) {
        F.spans = calloc((size_t)nthreads, sizeof *F.spans);
        if (!F.spans) {
            rc = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "out of memory for the trace");
            goto fail;
        }
        if (lod_span) vs_span_add(&F.spans[0], VS_SPAN_LOD, 0, -1, lod_span[0], lod_span[1]);
        vs_span_add(&F.spans[0], VS_SPAN_SETUP, 0, -1, t_start, t_rel);
        if (rebuilt) vs_span_add(&F.spans[0], VS_SPAN_RELEVANT, 0, -1, t_rel, t_rel_end);
    }

    double t_setup = vs_now_ms();
    const int W = s->width, H = s->height;
    size_t nv = F.rel->count;
    F.tile = s->tile_size;
    F.tiles_x = (W + F.tile - 1) / F.tile;
    F.tiles_y = (H + F.tile - 1) / F.tile;
    F.ntiles = F.tiles_x * F.tiles_y;
    F.seam_px = F.cd_wide > 0.0f ? 2 : 1;
    F.pad_x = F.fp.rx + F.seam_px; /* + the seam the in-sheet differences read */
    F.pad_y = F.fp.ry + F.seam_px;
    size_t nb = F.rel->nbricks;
    F.bview = malloc((nb ? nb : 1) * sizeof *F.bview);
    F.tile_start = calloc((size_t)F.ntiles + 1, sizeof(uint32_t));
    F.wstats = aligned_alloc(_Alignof(vs_worker_stats), (size_t)nthreads * sizeof *F.wstats);
    if (F.wstats) memset(F.wstats, 0, (size_t)nthreads * sizeof *F.wstats);
    F.scratch = ensure_scratch(ctx, nthreads);
    image = malloc((size_t)W * H * 4 * sizeof(float));
    J.F = &F;
    J.nchunks = nb < 256 ? 1 : nthreads * 4;
    J.counts = calloc((size_t)J.nchunks * F.ntiles, sizeof(uint32_t));
    if (!F.bview || !F.tile_start || !F.wstats || !F.scratch || !image ||
        !J.counts) {
        rc = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "out of memory for a %dx%d frame of %zu voxels", W, H, nv);
        goto fail;
    }
    /* project bricks + count, prefix sums (tile-major, chunk-minor keeps
     * brick order inside each tile for any thread count), fill */
    J.fill = 0;
    vs_pool_run(ctx->pool, J.nchunks, bin_task, &J);
    if (F.cam.persp && !F.use_blocks) setup_sheet_tables(&F, ctx->pool, s->pipeline == VS_PIPELINE_POST_CD ? 1 : 4);
    uint64_t total = 0;
    for (int t = 0; t < F.ntiles; t++) {
        F.tile_start[t] = (uint32_t)total;
        for (int c = 0; c < J.nchunks; c++) {
            uint32_t k = J.counts[(size_t)c * F.ntiles + t];
            J.counts[(size_t)c * F.ntiles + t] = (uint32_t)total;
            total += k;
        }
    }
    if (total > UINT32_MAX) {
        rc = vs_set_error(ctx, VS_ERR_TOO_LARGE, "too many voxel-tile entries (%llu)", (unsigned long long)total);
        goto fail;
    }
    F.tile_start[F.ntiles] = (uint32_t)total;
    F.tile_entries = malloc((total ? total : 1) * sizeof(uint32_t));
    if (!F.tile_entries) {
        rc = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "out of memory for %llu tile entries",
                          (unsigned long long)total);
        goto fail;
    }
    J.fill = 1;
    vs_pool_run(ctx->pool, J.nchunks, bin_task, &J);
    const double t_bin_end = vs_now_ms();
    double ms_setup = t_bin_end - t_setup;

    /* tiles with the most bricks first, so the last tasks handed out are
     * short ones and the workers finish together; order never changes a
     * pixel (tiles are independent) */
    F.tile_order = malloc((size_t)F.ntiles * sizeof(int));
    if (!F.tile_order) {
        rc = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "out of memory");
        goto fail;
    }
    {
        /* sort (work, index) pairs: heaviest first, ties by index */
        uint64_t *key = malloc((size_t)F.ntiles * sizeof *key);
        if (!key) {
            rc = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "out of memory");
            goto fail;
        }
        for (int t = 0; t < F.ntiles; t++)
            key[t] = ((uint64_t)(UINT32_MAX - (F.tile_start[t + 1] - F.tile_start[t])) << 32) | (uint32_t)t;
        qsort(key, (size_t)F.ntiles, sizeof *key, cmp_u64);
        for (int t = 0; t < F.ntiles; t++) F.tile_order[t] = (int)(uint32_t)key[t];
        free(key);
    }
    F.image = image;
    const double t_tiles = vs_now_ms();
    vs_pool_run_watched(ctx->pool, F.ntiles, vs_tile_render, &F, s->progress ? vs_tile_progress : NULL, &F);
    if (F.spans) {
        vs_span_add(&F.spans[0], VS_SPAN_BIN, 0, -1, t_setup, t_bin_end);
        vs_span_add(&F.spans[0], VS_SPAN_TILES, 0, -1, t_tiles, vs_now_ms());
    }
    if (atomic_load(&F.error)) {
        rc = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "out of memory in a tile");
        goto fail;
    }
    if (atomic_load(&F.cancel)) {
        rc = vs_set_error(ctx, VS_ERR_CANCELLED, "render cancelled by the progress callback");
        goto fail;
    }
    if (s->progress) s->progress(s->progress_user, 1.0);

    out->width = W;
    out->height = H;
    out->rgba = image;
    image = NULL;
    if (st) {
        memset(st, 0, sizeof *st);
        st->pipeline = vs_pipeline_name(s->pipeline);
        st->isa = vs_isa_name(F.kern.isa);
        st->threads = nthreads;
        st->width = W;
        st->height = H;
        st->voxels_total = (uint64_t)full->dims[0] * full->dims[1] * full->dims[2];
        st->voxels_relevant = nv;
        for (int w = 0; w < nthreads; w++) {
            const vs_worker_stats *ws = &F.wstats[w];
            st->voxels_splatted += ws->splatted;
            st->voxels_culled += ws->culled;
            st->sheets += ws->sheets;
            st->tiles_total += ws->tiles_total;
            st->tiles_shaded += ws->tiles_shaded;
            st->ms_stage.rasterize += ws->ms_rasterize;
            st->ms_stage.gradient += ws->ms_gradient;
            st->ms_stage.shade += ws->ms_shade;
            st->ms_stage.composite += ws->ms_composite;
            st->bricks_culled += ws->bricks_culled;
            st->voxels_projected += ws->projected;
            st->voxels_tested += ws->tested;
            st->footprint_floats += ws->floats;
            st->pixels_classified += ws->px_classified;
            st->pixels_shaded += ws->px_shaded;
        }
        stage_bytes(&F, st);
        st->ms_stage.setup = (t_setup - t_start - ms_relevant) + ms_setup;
        st->ms_relevant = ms_relevant;
        st->iso_lo = F.cls->lo;
        st->iso_hi = F.cls->hi;
        st->ramp = F.cls->ramp;
        st->pin_warning = vs_pool_pin_failed(ctx->pool);
        st->ms_total = vs_now_ms() - t_start;
    }
    if (F.spans) {
        vs_span_add(&F.spans[0], VS_SPAN_FRAME, 0, -1, lod_span ? lod_span[0] : t_start, vs_now_ms());
        for (int w = 0; w < nthreads; w++)
            if (!vs_trace_append(s->trace, &F.spans[w])) break;
        vs_trace_frame_done(s->trace);
    }
    free(J.counts);
    free_frame(&F, nthreads);
    return VS_OK;
fail:
    free(J.counts);
    free(image);
    free_frame(&F, F.spans ? vs_pool_threads(ctx->pool) : 0);
    return rc;
}
