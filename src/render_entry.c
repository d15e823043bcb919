/* vs_render: the settings checked, then the ray caster, or what a
 * splatted frame splats (render.h): the classification, the copy on cubic
 * voxels an anisotropic grid needs, the level of detail, or depth bands of
 * levels under perspective. */
#include "render.h"
#include "abi.h"
#include "raycast.h"
#include "trace.h"
#include "context.h"
#include "lod.h"
#include "lod_keep.h"
#include "pool.h"
#include "resample.h"
#include "timing.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static vs_status check_settings(vs_context *ctx, const vs_settings *s)
{
    if ((int)s->pipeline < 0 || (int)s->pipeline > VS_PIPELINE_RAYCAST)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "unknown pipeline %d", (int)s->pipeline);
    if (s->tile_size < 8 || s->tile_size > 4096)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "tile size %d must lie in [8, 4096]", s->tile_size);
    if (s->threads < 0 || s->threads > 256)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "thread count %d must lie in [0, 256]", s->threads);
    if (!(s->occlusion_threshold > 0.0 && s->occlusion_threshold <= 1.0))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "occlusion threshold %g must lie in (0, 1]",
                            s->occlusion_threshold);
    if (s->seam < -1 || s->seam > 16)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "seam %d must lie in [-1, 16]", s->seam);
    if ((int)s->isa < 0 || (int)s->isa > VS_ISA_AVX512)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "unknown ISA %d", (int)s->isa);
    for (int i = 0; i < 4; i++)
        if (!(s->background[i] >= 0.0f && s->background[i] <= 1.0f))
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "background must lie in [0,1]");
    for (int i = 0; i < 3; i++)
        if (!(s->material[i] >= 0.0f && s->material[i] <= 1.0f))
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "material colour must lie in [0,1]");
    if (!isfinite(s->ambient) || !isfinite(s->diffuse) || !isfinite(s->specular) || !isfinite(s->shininess) ||
        s->ambient < 0 || s->diffuse < 0 || s->specular < 0 || s->shininess < 0 || s->shininess > 1e4)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "lighting coefficients must be finite and >= 0");
    if (s->preintegration < -1 || s->preintegration > 1)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "preintegration must be -1 (auto), 0 or 1");
    if (!(s->lod_pixels >= 0.0 && s->lod_pixels <= 1e6))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "lod_pixels %g must lie in [0, 1e6] (0: full resolution)",
                            s->lod_pixels);
    if (s->resample < -1 || s->resample > 1)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "resample must be -1 (auto), 0 or 1");
    if (s->cd_stencil != 0 && s->cd_stencil != 2 && s->cd_stencil != 4)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "cd_stencil %d must be 0 (auto), 2 or 4", s->cd_stencil);
    if (s->gs_normalize != 0 && s->gs_normalize != 1)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "gs_normalize %d must be 0 or 1", s->gs_normalize);
    return VS_OK;
}

/* Level `level` of base (>= 1) as classification cls needs it, with the
 * settings that frame it and its relevant-voxel slot; on failure (out of
 * memory, or a level the volume's limits refuse) level 0: base itself,
 * rather than no frame.  Returns the level set up. */
static int level_setup(vs_context *ctx, const vs_volume *base, const vs_settings *s, const vs_classify *cls,
                       int level, const vs_volume **lv, vs_settings *ls, struct vs_relevant_cache ***rel,
                       double *ms_lod)
{
    double ms = 0.0;
    const vs_volume *got = NULL;
    if (vs_lod_get(ctx, ctx->pool, &ctx->lod, base, level, &got, &ms) != VS_OK) return 0;
    *lv = got;
    *ms_lod += ms;
    /* what thin structures the level lost raised back (lod_keep.h); out of
     * memory patching, the plain level */
    ms = 0.0;
    if (vs_lod_keep(ctx, ctx->pool, ctx->lod, base, level, cls, lv, &ms) != VS_OK) *lv = ctx->lod->level[level];
    *ms_lod += ms;
    vs_lod_settings(base, *lv, s, ls);
    /* an iso-surface's ramp spans fewer voxels of a coarser level: one
     * sample a sheet draws its contours as rings, which the pre-integrated
     * segments between sheets do not (Colin27 at 64x64, level 2: 21.5 ->
     * 25.7 dB against the full volume rendered at 512x512 and box-filtered) */
    if (ls->preintegration < 0) ls->preintegration = 1;
    *rel = &ctx->lod->relevant[level];
    return level;
}

/* A band's sheet thickness in view units (a level's smallest spacing). */
static double sheet_step(const vs_volume *v, const vs_settings *s) { return s->slab * vs_volume_finest(v); }

/* A band's progress as a share of the whole view's.  The frame ignores the
 * answer to its closing call (1.0), which for a band before the last is a
 * call in the middle of the view: that answer is kept and acted on. */
typedef struct band_progress {
    vs_progress_fn fn;
    void *user;
    double from, share;
    int cancel;
} band_progress;

static int band_progress_fn(void *user, double fraction)
{
    band_progress *b = user;
    const int r = b->fn(b->user, b->from + b->share * fraction);
    if (fraction >= 1.0 && r) b->cancel = 1;
    return r;
}

/* A perspective view in depth bands, each from its level (lod_depth.h),
 * nearest first, each composited behind the picture of those in front;
 * cls is freed. */
static vs_status render_bands(vs_context *ctx, const vs_volume *base, const vs_volume *vol, vs_classify *cls,
                              struct vs_relevant_cache **rel0, const vs_settings *s, vs_lod_band *band, int nband,
                              vs_image *out, vs_stats *st, double *ms_lod)
{
    vs_status rc = VS_OK;
    vs_settings clear = *s; /* each band on nothing: the background once, at the end */
    for (int c = 0; c < 4; c++) clear.background[c] = 0.0f;
    out->rgba = NULL;
    /* every band's level first: a band starts on a whole sheet of its own
     * level, and the band before it ends there */
    const vs_volume *lv[VS_LOD_MAX + 1];
    vs_settings ls[VS_LOD_MAX + 1];
    struct vs_relevant_cache **rel[VS_LOD_MAX + 1];
    for (int b = 0; b < nband; b++) {
        lv[b] = base;
        ls[b] = clear;
        rel[b] = rel0;
        if (band[b].level > 0)
            band[b].level = level_setup(ctx, base, &clear, cls, band[b].level, &lv[b], &ls[b], &rel[b], ms_lod);
        if (b > 0) {
            /* on the coarser of the two bands' sheet grids: band b is the
             * coarser one unless its level fell back to a finer one (out
             * of memory), when band b - 1's last sheet would reach past a
             * boundary on band b's grid and a slab would count twice */
            const double t = fmax(sheet_step(lv[b], &ls[b]), sheet_step(lv[b - 1], &ls[b - 1]));
            band[b].z0 = band[b - 1].z1 = ceil(band[b].z0 / t) * t;
        }
    }
    for (int b = 0; b < nband && rc == VS_OK; b++) {
        if (!(band[b].z0 < band[b].z1)) continue; /* snapped away */
        vs_classify *copy = malloc(sizeof *copy);
        if (!copy) {
            rc = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "out of memory");
            break;
        }
        memcpy(copy, cls, sizeof *copy);
        vs_image img = {0, 0, NULL};
        vs_stats bs;
        band_progress bp = {s->progress, s->progress_user, (double)b / nband, 1.0 / nband, 0};
        if (s->progress) {
            ls[b].progress = band_progress_fn;
            ls[b].progress_user = &bp;
        }
        /* the bands in front are what this one composites behind */
        rc = vs_render_splat(ctx, lv[b], vol, copy, rel[b], &ls[b], &band[b], out->rgba, &img, st ? &bs : NULL, NULL);
        if (rc == VS_OK && bp.cancel && b + 1 < nband) {
            free(img.rgba);
            rc = vs_set_error(ctx, VS_ERR_CANCELLED, "render cancelled by the progress callback");
        }
        if (rc != VS_OK) break;
        if (st && !out->rgba) {
            *st = bs;
            st->lod_level = band[b].level;
        } else if (st) {
            vs_stats_add(st, &bs);
        }
        free(out->rgba);
        *out = img;
    }
    free(cls);
    if (rc != VS_OK) {
        free(out->rgba);
        out->rgba = NULL;
        out->width = out->height = 0;
        return rc;
    }
    vs_image_background(out->rgba, (size_t)out->width * out->height, s->background);
    return VS_OK;
}

/* The classification (one a frame: the levels' patching and the frame
 * share it), the copy on cubic voxels an anisotropic grid needs
 * (resample.h), the level of detail the view asks for (lod.h; by depth
 * band under perspective, lod_depth.h), then the frame. */
static vs_status render_lod(vs_context *ctx, const vs_volume *vol, const vs_settings *s, vs_image *out, vs_stats *st)
{
    int level = 0, resampled = 0;
    double ms_lod = 0.0, ms_resample = 0.0, span[2] = {0.0, 0.0};
    const vs_volume *base = vol;
    struct vs_relevant_cache **rel = &ctx->relevant;
    vs_settings rs, ls;
    vs_classify *cls = malloc(sizeof *cls);
    if (!cls) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "out of memory");
    vs_status rc = vs_classify_setup(ctx, vol, s, cls);
    if (rc != VS_OK) goto fail;
    /* an anisotropic grid: its copy on cubic voxels (resample.h) is what
     * is splatted, at full resolution and as the levels' source, unless it
     * cannot be made (out of memory: the grid as it is) */
    if (vs_resample_wanted(vol, s)) {
        if ((rc = vs_context_pool(ctx, s)) != VS_OK) goto fail;
        span[0] = vs_now_ms();
        if (vs_resample_get(ctx, ctx->pool, &ctx->resample, vol, &base, &ms_resample) == VS_OK) {
            vs_camera_settings_for_copy(vol, base, s, &rs);
            s = &rs;
            rel = &ctx->resample->relevant;
            resampled = 1;
        } else {
            base = vol;
        }
    }
    const vs_volume *lv = base; /* what is splatted: base or a level of it */
    if (s->lod_pixels > 0.0 && !s->has_crop) {
        vs_camera cam;
        vs_lod_band band[VS_LOD_MAX + 1];
        if ((rc = vs_camera_setup(ctx, base, s, &cam)) != VS_OK) goto fail;
        const int nband = vs_lod_bands(base, s, &cam, band);
        level = band[0].level;
        if (level > 0 || nband > 1) {
            if ((rc = vs_context_pool(ctx, s)) != VS_OK) goto fail;
            if (!resampled) span[0] = vs_now_ms();
        }
        if (nband > 1) {
            rc = render_bands(ctx, base, vol, cls, rel, s, band, nband, out, st, &ms_lod);
            if (rc == VS_OK && st) {
                st->ms_lod = ms_lod;
                st->ms_resample = ms_resample;
                st->resampled = resampled;
                st->ms_total += ms_lod + ms_resample;
            }
            return rc;
        }
        if (level > 0) {
            level = level_setup(ctx, base, s, cls, level, &lv, &ls, &rel, &ms_lod);
            if (level > 0) s = &ls;
        }
    }
    span[1] = vs_now_ms();
    rc = vs_render_splat(ctx, lv, vol, cls, rel, s, NULL, NULL, out, st, ms_lod + ms_resample > 0.0 ? span : NULL);
    if (rc == VS_OK && st) {
        st->lod_level = level;
        st->ms_lod = ms_lod;
        st->ms_resample = ms_resample;
        st->resampled = resampled;
        st->ms_total += ms_lod + ms_resample;
    }
    return rc;
fail:
    free(cls);
    return rc;
}

static vs_status render_exclusive(vs_context *ctx, const vs_volume *vol, const vs_settings *settings, vs_image *out,
                                  vs_stats *stats)
{
    if (!vol || !settings || !out) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "vs_render: NULL argument");
    out->width = out->height = 0;
    out->rgba = NULL;
    /* the caller's layouts of settings and stats, whatever header it was
     * built with, to and from the library's own (src/abi.c) */
    vs_settings full;
    vs_status rc = vs_settings_import(ctx, settings, &full);
    if (rc != VS_OK) return rc;
    const vs_settings *s = &full;
    vs_stats st_full, *st = stats ? &st_full : NULL;
    rc = check_settings(ctx, s);
    if (rc != VS_OK) return rc;
    if (s->has_crop) {
        if (s->pipeline == VS_PIPELINE_RAYCAST)
            return vs_set_error(ctx, VS_ERR_UNSUPPORTED, "the crop box is not supported by the ray caster");
        for (int a = 0; a < 3; a++)
            if (!(s->crop_lo[a] >= 0 && s->crop_lo[a] < s->crop_hi[a] && s->crop_hi[a] <= vol->dims[a]))
                return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                                    "crop box %d..%d on axis %d must lie in 0..%d and not be empty", s->crop_lo[a],
                                    s->crop_hi[a], a, vol->dims[a]);
    }
    if (s->pipeline == VS_PIPELINE_RAYCAST) {
        const double t0 = vs_now_ms();
        rc = vs_raycast_render(ctx, vol, s, out, st);
        if (rc == VS_OK && s->trace) { /* one span: its rows are not traced */
            vs_span_buf b = {0};
            const double t1 = vs_now_ms();
            vs_span_add(&b, VS_SPAN_FRAME, 0, -1, t0, t1);
            vs_span_add(&b, VS_SPAN_RAYCAST, 0, -1, t0, t1);
            vs_trace_append(s->trace, &b);
            vs_trace_frame_done(s->trace);
            free(b.s);
        }
    } else if (s->isa > VS_ISA_SCALAR && s->isa > vs_isa_detect())
        /* asking for more than the CPU has is a usage error, not a fallback */
        rc = vs_set_error(ctx, VS_ERR_UNSUPPORTED, "ISA %s is not supported by this CPU (best: %s)",
                          vs_isa_name(s->isa), vs_isa_name(vs_isa_detect()));
    else
        rc = render_lod(ctx, vol, s, out, st);
    if (rc == VS_OK && stats) vs_stats_export(st, stats, s->stats_size);
    return rc;
}

vs_status vs_render(vs_context *ctx, const vs_volume *vol, const vs_settings *settings, vs_image *out,
                    vs_stats *stats)
{
    if (!ctx) return VS_ERR_INVALID_ARGUMENT;
    /* one call at a time per context (vsplat.h): a second thread is told
     * so, without touching the caches or the message the first one uses */
    if (atomic_exchange(&ctx->busy, 1)) {
        if (out) {
            out->width = out->height = 0;
            out->rgba = NULL;
        }
        return VS_ERR_BUSY;
    }
    vs_status rc = render_exclusive(ctx, vol, settings, out, stats);
    atomic_store(&ctx->busy, 0);
    return rc;
}
