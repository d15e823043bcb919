/* Levels of detail (lod.h): building the pyramid and choosing a level. */
#include "lod.h"
#include "context.h"
#include "lod_keep.h"
#include "pool.h"
#include "relevant.h"
#include "timing.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void vs_lod_cache_free(vs_lod_cache *c)
{
    if (!c) return;
    vs_lod_keep_clear(c);
    for (int l = 0; l <= VS_LOD_MAX; l++) free(c->minmax[l]);
    for (int l = 1; l <= VS_LOD_MAX; l++) {
        vs_volume_release(c->level[l]);
        vs_relevant_cache_free(c->relevant[l]);
    }
    free(c);
}

static int half(int d) { return (d + 1) / 2; }

/* Which axes the next level halves: of the axes that keep at least
 * VS_LOD_MIN_DIM voxels when halved (a few voxels cannot hold a shape; a
 * single slice stays one), those within 1.5x of the finest of them, so
 * anisotropic volumes (CT slices, EM sections) become more isotropic level
 * by level instead of losing their coarse axis first.  Returns 0 when no
 * axis can be halved.  Choosing and building both ask this, from the
 * level's own sizes and spacing, so they agree. */
static int next_axes(const int d[3], const double sp[3], int dec[3])
{
    double m = INFINITY;
    for (int a = 0; a < 3; a++)
        if (half(d[a]) >= VS_LOD_MIN_DIM && sp[a] < m) m = sp[a];
    for (int a = 0; a < 3; a++) dec[a] = half(d[a]) >= VS_LOD_MIN_DIM && sp[a] < 1.5 * m;
    return isfinite(m);
}

int vs_lod_choose(const struct vs_volume *vol, const vs_settings *s, const vs_camera *cam)
{
    if (!(s->lod_pixels > 0.0) || s->has_crop) return 0;
    double scale = 1.0;
    if (cam->persp) {
        /* the nearest corner is seen largest: its scale bounds the frame's */
        scale = 0.0;
        for (int c = 0; c < 8; c++) {
            const double idx[3] = {c & 1 ? vol->dims[0] - 1 : 0, c & 2 ? vol->dims[1] - 1 : 0,
                                   c & 4 ? vol->dims[2] - 1 : 0};
            double v[3];
            vs_camera_index_to_view0(cam, idx, v);
            const double sc = vs_camera_scale(cam, v[2] > cam->near_z ? v[2] : cam->near_z);
            if (sc > scale) scale = sc;
        }
    }
    return vs_lod_choose_at(vol, s, cam, scale);
}

int vs_lod_choose_at(const struct vs_volume *vol, const vs_settings *s, const vs_camera *cam, double scale)
{
    if (!(s->lod_pixels > 0.0) || s->has_crop) return 0;
    /* pre and post-alpha keep one level finer.  Pre has no pre-integrated
     * segments: an iso ramp spans half as many voxels a level up, and one
     * sample a sheet draws its contours as rings (Colin27 pre at 64x64
     * against the full volume at 512x512 box-filtered: level 1 29.1 dB,
     * full resolution 29.4, level 2 21.6).  Post-alpha's light is shaded
     * per voxel and blurs with the wider kernel (the translucent head,
     * colin27-skin-brain.vtf, the same way: level 1 24.2 dB, level 2 20.2) */
    const double limit = s->pipeline == VS_PIPELINE_POST_CD || s->pipeline == VS_PIPELINE_POST_GS
                             ? s->lod_pixels
                             : 0.5 * s->lod_pixels;
    int level = 0, d[3] = {vol->dims[0], vol->dims[1], vol->dims[2]};
    double sp[3] = {vol->spacing[0], vol->spacing[1], vol->spacing[2]};
    while (level < VS_LOD_MAX) {
        int dec[3];
        if (!next_axes(d, sp, dec)) break;
        /* the halved axes' voxels on the image, in pixels (axes that stay,
         * too small to halve, keep their spacing) */
        double m = INFINITY;
        for (int a = 0; a < 3; a++)
            if (dec[a] && 2.0 * sp[a] < m) m = 2.0 * sp[a];
        if (cam->px_per_mm * m * scale > limit) break;
        for (int a = 0; a < 3; a++)
            if (dec[a]) d[a] = half(d[a]), sp[a] *= 2.0;
        level++;
    }
    return level;
}

/* One level from the one before.  Per halved axis the binomial filter
 * [1 3 3 1]/8 centred between voxels 2i and 2i+1 (where level voxel i
 * sits), clamped at the faces; other axes are copied.  z first, then y
 * (whole rows, vectorisable), then x, one output plane a task, each worker
 * with six rows of its own (a 16384-voxel row is 64 KB).  Non-finite values count as empty
 * space, as when splatted.
 *
 * Levels hold plain averages, classified afterwards, so smooth surfaces
 * keep their gradients (averaged opacity instead, the value clamped to
 * the iso ramp, terraces their shading: sphere:256 at 64x64, 43.7 -> 26.7
 * dB against the analytic sphere).  A structure thinner than a level voxel
 * (a CT headrest one voxel thick) is averaged below the iso-value: what
 * the classification loses that way is raised back per classification, in
 * a patched copy (lod_keep.h). */
typedef struct down_job {
    const struct vs_volume *in;
    struct vs_volume *out;
    int dec[3];
    float *scratch; /* per worker: six rows */
    size_t per_worker;
    float base; /* what a non-finite voxel reads as: the value outside the volume */
} down_job;

static const float taps[4] = {0.125f, 0.375f, 0.375f, 0.125f};

static inline int clampi(int v, int hi) { return v < 0 ? 0 : v > hi ? hi : v; }

/* Input row jj of output plane k's z taps, filtered in z into `row`: the
 * taps' sum in order, as float (one tap: the row itself). */
static void z_row(const down_job *J, const int p[4], const float w[4], int n, int jj, float *row)
{
    const int *d = J->in->dims;
    const size_t np = (size_t)d[0] * d[1];
    for (int t = 0; t < n; t++)
        vs_volume_axpy_floats(J->in, (size_t)p[t] * np + (size_t)jj * d[0], (size_t)d[0], w[t], J->base, t == 0, row);
}

static void down_plane(void *arg, int worker, int k)
{
    const down_job *J = arg;
    const int *d = J->in->dims, *o = J->out->dims;
    /* a ring of four z-filtered input rows (row jj in slot jj & 3: the four
     * rows one output row reads are consecutive, and the next output row
     * reuses two), then one y-filtered row and one x-filtered row */
    float *ring = J->scratch + (size_t)worker * J->per_worker, *rv = ring + 4 * (size_t)d[0], *xo = rv + d[0];
    int held[4] = {-1, -1, -1, -1};
    int p[4], n = 1;
    float w[4] = {1.0f, 0.0f, 0.0f, 0.0f};
    if (J->dec[2]) {
        n = 4;
        for (int t = 0; t < 4; t++) p[t] = clampi(2 * k - 1 + t, d[2] - 1), w[t] = taps[t];
    } else {
        p[0] = k;
    }
    for (int j = 0; j < o[1]; j++) {
        const float *r0[4];
        const int m = J->dec[1] ? 4 : 1;
        for (int t = 0; t < m; t++) {
            const int jj = J->dec[1] ? clampi(2 * j - 1 + t, d[1] - 1) : j;
            float *slot = ring + (size_t)(jj & 3) * d[0];
            if (held[jj & 3] != jj) {
                z_row(J, p, w, n, jj, slot);
                held[jj & 3] = jj;
            }
            r0[t] = slot;
        }
        const float *r = r0[0];
        if (J->dec[1]) {
            for (int i = 0; i < d[0]; i++)
                rv[i] = taps[0] * r0[0][i] + taps[1] * r0[1][i] + taps[2] * r0[2][i] + taps[3] * r0[3][i];
            r = rv;
        }
        const float *x = r;
        if (J->dec[0]) {
            /* the faces clamped, the interior without a test */
            for (int i = 0; i < o[0]; i++) {
                if (i == 1 && o[0] > 2) {
                    const int last = (d[0] - 3) / 2; /* 2i + 2 <= d0 - 1 */
                    for (; i <= last; i++)
                        xo[i] = taps[0] * r[2 * i - 1] + taps[1] * r[2 * i] + taps[2] * r[2 * i + 1] +
                                taps[3] * r[2 * i + 2];
                    if (i >= o[0]) break;
                }
                xo[i] = taps[0] * r[clampi(2 * i - 1, d[0] - 1)] + taps[1] * r[2 * i] +
                        taps[2] * r[clampi(2 * i + 1, d[0] - 1)] + taps[3] * r[clampi(2 * i + 2, d[0] - 1)];
            }
            x = xo;
        }
        vs_volume_store_floats(J->out, ((size_t)k * o[1] + j) * o[0], x, o[0]);
    }
}

/* A level's placement from the one before: level voxel i sits at the
 * previous level's 2i + 1/2 on a halved axis (halved: twice the spacing). */
static void place_level(struct vs_volume *v, const struct vs_volume *in)
{
    for (int r = 0; r < 3; r++) {
        v->affine[r][3] = in->affine[r][3];
        for (int a = 0; a < 3; a++) {
            const int dec = v->spacing[a] != in->spacing[a];
            v->affine[r][a] = dec ? 2.0 * in->affine[r][a] : in->affine[r][a];
            if (dec) v->affine[r][3] += 0.5 * in->affine[r][a];
        }
    }
    v->has_orientation = in->has_orientation;
}

static vs_status build_level(vs_context *ctx, struct vs_pool *pool, const struct vs_volume *in,
                             const struct vs_volume *full, struct vs_volume **out)
{
    down_job J = {.in = in, .base = (float)vs_volume_base(full)};
    if (!next_axes(in->dims, in->spacing, J.dec))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "levels of detail: no axis of %dx%dx%d can be halved",
                            in->dims[0], in->dims[1], in->dims[2]);
    int dims[3];
    double sp[3];
    for (int a = 0; a < 3; a++) {
        dims[a] = J.dec[a] ? half(in->dims[a]) : in->dims[a];
        sp[a] = J.dec[a] ? 2.0 * in->spacing[a] : in->spacing[a];
    }
    struct vs_volume *v = NULL;
    vs_status st = vs_volume_alloc(ctx, in->type, dims, sp, &v);
    if (st != VS_OK) return st;
    place_level(v, in);
    vs_volume_share_classification(v, full);
    J.out = v;
    const int nw = pool ? vs_pool_threads(pool) : 1;
    J.per_worker = 6 * (size_t)in->dims[0];
    J.scratch = malloc(J.per_worker * nw * sizeof *J.scratch);
    if (!J.scratch) {
        vs_volume_release(v);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "levels of detail: out of memory");
    }
    if (pool)
        vs_pool_run(pool, dims[2], down_plane, &J);
    else
        for (int k = 0; k < dims[2]; k++) down_plane(&J, 0, k);
    free(J.scratch);
    *out = v;
    return VS_OK;
}

vs_status vs_lod_get(vs_context *ctx, struct vs_pool *pool, vs_lod_cache **cache, const struct vs_volume *vol,
                     int level, const struct vs_volume **out, double *ms)
{
    *ms = 0.0;
    *out = NULL;
    vs_lod_cache *c = *cache;
    /* the spacing decides which axes halve, and non-finite voxels are
     * filtered as the value outside: a new one of either, new levels */
    if (c && !vs_volume_stamp_same_field(&c->from, vol)) {
        vs_lod_cache_free(c);
        c = *cache = NULL;
    }
    if (!c) {
        if (!(c = *cache = calloc(1, sizeof *c)))
            return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "levels of detail: out of memory");
        vs_volume_stamp_take(&c->from, vol);
    } else if (c->from.serial != vol->serial) {
        /* vs_volume_set_range since: the same voxels, classified anew
         * (the range was checked when vol took it) */
        for (int l = 1; l <= VS_LOD_MAX && c->level[l]; l++) vs_volume_set_range(c->level[l], vol->vmin, vol->vmax);
    }
    if (!vs_volume_stamp_same_place(&c->from, vol)) {
        /* vs_volume_set_transform since: the same voxels, placed anew */
        for (int l = 1; l <= VS_LOD_MAX && c->level[l]; l++) place_level(c->level[l], l == 1 ? vol : c->level[l - 1]);
    }
    vs_volume_stamp_take(&c->from, vol);
    for (int l = 1; l <= level; l++) {
        if (c->level[l]) continue;
        const double t0 = vs_now_ms();
        vs_status st = build_level(ctx, pool, l == 1 ? vol : c->level[l - 1], vol, &c->level[l]);
        if (st != VS_OK) return st;
        *ms += vs_now_ms() - t0;
    }
    *out = c->level[level];
    return VS_OK;
}

void vs_lod_settings(const struct vs_volume *vol, const struct vs_volume *lv, const vs_settings *s,
                     vs_settings *out)
{
    /* the pixels per millimetre and the world point at the centre of the
     * full volume's frame */
    vs_camera_settings_for_copy(vol, lv, s, out);
    /* Sheets: a level halved along every axis keeps --slab in its own
     * units, so it halves the sheets too.  One that kept an axis (thick
     * CT/EM slices) keeps the slab's thickness in the volume's units: in
     * its own, the sheets drew bands (EM stack 4x4x50 nm, --slab 4, level
     * 1: 14.9 dB from full resolution, banded; 18.7 dB with the thickness
     * kept; a 64x64x8 ball, 1:1:12.5, 30.2 dB under its 36 dB floor). */
    int iso = 1;
    for (int a = 1; a < 3; a++)
        if (lv->spacing[a] / vol->spacing[a] != lv->spacing[0] / vol->spacing[0]) iso = 0;
    if (!iso) {
        const double slab = s->slab * vs_volume_finest(vol) / vs_volume_finest(lv);
        out->slab = slab < 0.01 ? 0.01 : slab > 64.0 ? 64.0 : slab;
    }
}
