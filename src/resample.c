/* Anisotropic grids on cubic voxels (resample.h): the copy, whom it
 * serves, and its cache. */
#include "resample.h"
#include "camera.h"
#include "context.h"
#include "pool.h"
#include "relevant.h"
#include "timing.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The kernel h(r) = b 2^(-2 r^2) (gaussian.c) as exp(-r^2 / (2 sigma^2)),
 * r in voxel-index units: sigma^2 = 1 / (4 ln 2). */
static double kernel_sigma(void) { return 1.0 / sqrt(4.0 * M_LN2); }

/* Axis a resampled: thicker than the finest axis (not equal up to
 * rounding of the file's spacing). */
static int thick(const struct vs_volume *vol, int a, double fine) { return vol->spacing[a] > fine * (1.0 + 1e-6); }

/* The width (old voxel indices) of the Gaussian between the grids along
 * axis a, and how many new voxels it reaches past the old grid's ends. */
static double between_sigma(const struct vs_volume *vol, int a, double fine)
{
    const double ratio = vol->spacing[a] / fine;
    return thick(vol, a, fine) ? kernel_sigma() * sqrt(ratio * ratio - 1.0) / ratio : 0.0;
}
static double pad_voxels(const struct vs_volume *vol, int a, double fine)
{
    return ceil(4.0 * between_sigma(vol, a, fine) * vol->spacing[a] / fine);
}

/* The copy's size along each axis: the volume's extent between its first
 * and last voxel centres in voxels of the finest spacing, centred on the
 * volume's centre, and past each end as far as the filter between the
 * grids reaches (4 sigma: where the thick kernels still weigh).  0 when
 * a size would not fit an int. */
static int cubic_dims(const struct vs_volume *vol, double fine, int d[3])
{
    for (int a = 0; a < 3; a++) {
        const double n = thick(vol, a, fine)
                             ? nearbyint((vol->dims[a] - 1) * vol->spacing[a] / fine) + 1.0 + 2.0 * pad_voxels(vol, a, fine)
                             : vol->dims[a];
        if (!(n <= INT_MAX)) return 0;
        d[a] = (int)n;
    }
    return 1;
}

int vs_resample_wanted(const struct vs_volume *vol, const vs_settings *s)
{
    if (s->resample == 0 || s->has_crop || s->pipeline == VS_PIPELINE_RAYCAST) return 0;
    const double fine = vs_volume_finest(vol);
    int any = 0;
    for (int a = 0; a < 3; a++) {
        if (!thick(vol, a, fine)) continue;
        /* an axis only a little thicker would need a Gaussian between the
         * grids narrower than the new voxels, which sampling aliases */
        if (vol->spacing[a] < VS_RESAMPLE_MIN_RATIO * fine) return 0;
        any = 1;
    }
    if (!any || !vs_camera_grid_orthonormal(vol)) return 0; /* a sheared grid stays sheared */
    int d[3];
    if (!cubic_dims(vol, fine, d)) return 0;
    double n = 1.0, n0 = 1.0;
    for (int a = 0; a < 3; a++) n *= d[a], n0 *= vol->dims[a];
    const double bytes = n * (double)vs_type_size(vol->type), bytes0 = n0 * (double)vs_type_size(vol->type);
    /* auto: a copy of at most the volume's size plus 64 MB (it is kept
     * beside the caller's volume) */
    return s->resample > 0 || bytes <= bytes0 + 64.0 * (1 << 20);
}

/* One axis's filter: new voxel j reads old voxels first[j] .. first[j] +
 * taps - 1 with weights w[j taps ..] (outside the volume: its base value,
 * as splatting reconstructs there); a kept axis has one tap of weight 1. */
typedef struct axis_filter {
    int taps;
    int *first;
    float *w;
} axis_filter;

static int axis_setup(const struct vs_volume *vol, int a, double fine, int n, axis_filter *f)
{
    const int n0 = vol->dims[a];
    const double ratio = vol->spacing[a] / fine;
    const double sig = between_sigma(vol, a, fine); /* under 0.61: at most 8 taps */
    const int reach = (int)ceil(4.0 * sig);
    f->taps = sig > 0.0 ? 2 * reach + 2 : 1;
    f->first = malloc((size_t)n * sizeof *f->first);
    f->w = malloc((size_t)n * f->taps * sizeof *f->w);
    if (!f->first || !f->w) return 0;
    for (int j = 0; j < n; j++) {
        float *w = f->w + (size_t)j * f->taps;
        if (f->taps == 1) {
            f->first[j] = j;
            w[0] = 1.0f;
            continue;
        }
        /* the new voxel's position in old voxel indices, both grids
         * centred on the volume's centre */
        const double x = 0.5 * (n0 - 1) + (j - 0.5 * (n - 1)) / ratio;
        const int i0 = (int)floor(x) - reach;
        double sum = 0.0, wd[2 * 64 + 2];
        for (int t = 0; t < f->taps; t++) {
            const double u = (i0 + t - x) / sig;
            wd[t] = fabs(u) <= 4.0 ? exp(-0.5 * u * u) : 0.0;
            sum += wd[t];
        }
        f->first[j] = i0;
        for (int t = 0; t < f->taps; t++) w[t] = (float)(wd[t] / sum);
    }
    return 1;
}

static void axis_free(axis_filter *f)
{
    free(f->first);
    free(f->w);
}

typedef struct resample_job {
    const struct vs_volume *in;
    struct vs_volume *out;
    axis_filter f[3];
    float *scratch; /* per worker: a z-filtered plane, a y-filtered one, a row */
    size_t per_worker;
    float base; /* what a non-finite voxel reads as: the value outside the volume */
} resample_job;

/* Output plane k: z taps into a plane of input rows, y taps into a plane
 * of output rows, x taps a row at a time. */
static void resample_plane(void *arg, int worker, int k)
{
    const resample_job *J = arg;
    const int *d = J->in->dims, *o = J->out->dims;
    const axis_filter *fx = &J->f[0], *fy = &J->f[1], *fz = &J->f[2];
    float *zp = J->scratch + (size_t)worker * J->per_worker;
    float *yp = zp + (size_t)d[0] * d[1], *xr = yp + (size_t)d[0] * o[1];
    memset(zp, 0, (size_t)d[0] * d[1] * sizeof *zp);
    float out_w = 0.0f; /* the weight of the taps outside the volume */
    for (int t = 0; t < fz->taps; t++) {
        const float w = fz->w[(size_t)k * fz->taps + t];
        const int p = fz->first[k] + t;
        if (p < 0 || p >= d[2]) out_w += w;
        else if (w != 0.0f)
            vs_volume_axpy_floats(J->in, (size_t)p * d[0] * d[1], (size_t)d[0] * d[1], w, J->base, 0, zp);
    }
    if (out_w != 0.0f)
        for (size_t i = 0; i < (size_t)d[0] * d[1]; i++) zp[i] += out_w * J->base;
    for (int j = 0; j < o[1]; j++) {
        float *yr = yp + (size_t)j * d[0];
        if (fy->taps == 1) {
            memcpy(yr, zp + (size_t)j * d[0], (size_t)d[0] * sizeof *yr);
            continue;
        }
        float out_wy = 0.0f;
        memset(yr, 0, (size_t)d[0] * sizeof *yr);
        for (int t = 0; t < fy->taps; t++) {
            const float w = fy->w[(size_t)j * fy->taps + t];
            const int r = fy->first[j] + t;
            if (r < 0 || r >= d[1]) out_wy += w;
            else if (w != 0.0f)
                for (int i = 0; i < d[0]; i++) yr[i] += w * zp[(size_t)r * d[0] + i];
        }
        if (out_wy != 0.0f)
            for (int i = 0; i < d[0]; i++) yr[i] += out_wy * J->base;
    }
    for (int j = 0; j < o[1]; j++) {
        const float *yr = yp + (size_t)j * d[0];
        const float *row = yr;
        if (fx->taps > 1) {
            for (int i = 0; i < o[0]; i++) {
                float s = 0.0f;
                const float *w = fx->w + (size_t)i * fx->taps;
                for (int t = 0; t < fx->taps; t++) {
                    const int c = fx->first[i] + t;
                    s += w[t] * (c < 0 || c >= d[0] ? J->base : yr[c]);
                }
                xr[i] = s;
            }
            row = xr;
        }
        vs_volume_store_floats(J->out, ((size_t)k * o[1] + j) * o[0], row, o[0]);
    }
}

/* The copy's placement: its axes the volume's, scaled to the finest
 * spacing, and both grids' centres at the same world point. */
static void place_cubic(struct vs_volume *cv, const struct vs_volume *vol)
{
    for (int r = 0; r < 3; r++) {
        double t = vol->affine[r][3];
        for (int a = 0; a < 3; a++) {
            const double f = cv->spacing[a] / vol->spacing[a];
            cv->affine[r][a] = vol->affine[r][a] * f;
            t += vol->affine[r][a] * (0.5 * (vol->dims[a] - 1) - f * 0.5 * (cv->dims[a] - 1));
        }
        cv->affine[r][3] = t;
    }
    cv->has_orientation = vol->has_orientation;
}

static vs_status build_cubic(vs_context *ctx, struct vs_pool *pool, const struct vs_volume *vol,
                             struct vs_volume **out)
{
    const double fine = vs_volume_finest(vol);
    int d[3];
    double sp[3];
    if (!cubic_dims(vol, fine, d))
        return vs_set_error(ctx, VS_ERR_TOO_LARGE, "resampling to cubic voxels: the copy would be too large");
    for (int a = 0; a < 3; a++) sp[a] = thick(vol, a, fine) ? fine : vol->spacing[a];
    resample_job J = {.in = vol, .base = (float)vs_volume_base(vol)};
    struct vs_volume *cv = NULL;
    vs_status st = vs_volume_alloc(ctx, vol->type, d, sp, &cv);
    if (st != VS_OK) return st;
    place_cubic(cv, vol);
    vs_volume_share_classification(cv, vol);
    J.out = cv;
    int ok = 1;
    for (int a = 0; a < 3; a++) ok &= axis_setup(vol, a, fine, d[a], &J.f[a]);
    const int nw = pool ? vs_pool_threads(pool) : 1;
    J.per_worker = (size_t)vol->dims[0] * vol->dims[1] + (size_t)vol->dims[0] * d[1] + (size_t)d[0];
    J.scratch = ok ? malloc(J.per_worker * nw * sizeof *J.scratch) : NULL;
    if (!J.scratch) {
        for (int a = 0; a < 3; a++) axis_free(&J.f[a]);
        vs_volume_release(cv);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "resampling to cubic voxels: out of memory");
    }
    if (pool)
        vs_pool_run(pool, d[2], resample_plane, &J);
    else
        for (int k = 0; k < d[2]; k++) resample_plane(&J, 0, k);
    free(J.scratch);
    for (int a = 0; a < 3; a++) axis_free(&J.f[a]);
    *out = cv;
    return VS_OK;
}

void vs_resample_cache_free(vs_resample_cache *c)
{
    if (!c) return;
    vs_volume_release(c->cubic);
    vs_relevant_cache_free(c->relevant);
    free(c);
}

vs_status vs_resample_get(vs_context *ctx, struct vs_pool *pool, vs_resample_cache **cache,
                          const struct vs_volume *vol, const struct vs_volume **out, double *ms)
{
    *ms = 0.0;
    *out = NULL;
    vs_resample_cache *c = *cache;
    /* new voxels, a new spacing (the copy's size follows it) or a new
     * value outside the volume (its padding and NaN hold it: a new range
     * can move it): a new copy */
    if (c && !vs_volume_stamp_same_field(&c->from, vol)) {
        vs_resample_cache_free(c);
        c = *cache = NULL;
    }
    if (!c) {
        const double t0 = vs_now_ms();
        if (!(c = calloc(1, sizeof *c)))
            return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "resampling to cubic voxels: out of memory");
        vs_status st = build_cubic(ctx, pool, vol, &c->cubic);
        if (st != VS_OK) {
            free(c);
            return st;
        }
        *cache = c;
        *ms = vs_now_ms() - t0;
    } else {
        /* vs_volume_set_range since: the same voxels, classified anew
         * (the range was checked when vol took it) */
        if (c->from.serial != vol->serial) vs_volume_set_range(c->cubic, vol->vmin, vol->vmax);
        /* vs_volume_set_transform since: the same voxels, placed anew */
        if (!vs_volume_stamp_same_place(&c->from, vol)) place_cubic(c->cubic, vol);
    }
    vs_volume_stamp_take(&c->from, vol);
    *out = c->cubic;
    return VS_OK;
}
