/* Levels of detail that keep what the classification shows (lod_keep.h).
 *
 * For level l (coarse) and the level it was made from (fine: the volume
 * itself, or level l-1 as patched), brick by brick of the coarse grid:
 *
 *  - both grids' reconstructions at their voxels, the splatting kernel
 *    2^(-2 r^2) sampled at the voxels, per axis [1 4 1]/6 (its taps past
 *    one voxel weigh 1/256), classified: opacity a_f on the fine grid,
 *    a_c on the coarse;
 *  - A, a_f filtered down as the level's values are ([1 3 3 1]/8 on the
 *    halved axes): the opacity the finer level shows around each coarse
 *    voxel;
 *  - a coarse voxel is lost where A exceeds 1/256 of the table's peak and
 *    every coarse voxel around it (3x3x3) is under half of A.  A smooth
 *    surface always has a visible coarse voxel next to its outermost ones,
 *    so it is never touched; a sheet thinner than a level voxel, averaged
 *    into the empty space on both sides, is;
 *  - the lost voxels are raised (never lowered, never above the largest
 *    fine value under them) so that the reconstruction there reaches T,
 *    the least value from the reconstruction upwards whose opacity is A:
 *    a first step divides what is missing by the kernel's weight over the
 *    lost voxels (exact for a uniform sheet, line or point), three Jacobi
 *    steps of the same kind settle uneven ones.
 *
 * Each brick reads the plain level and the fine grid and writes only its
 * own voxels of the copy, so the copy is the same for any thread count. */
#include "lod_keep.h"
#include "context.h"
#include "pool.h"
#include "relevant_bricks.h"
#include "relevant_class.h"
#include "timing.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define KEEP_JACOBI 3
/* a brick and a ring of one coarse voxel are worked out (the ring so that
 * the brick's edge sees its neighbours raised too): the fine block covers
 * their taps and the kernel around those, the coarse one a ring of 3 */
#define FB (2 * VS_BRICK + 8)
#define CB (VS_BRICK + 6)

void vs_lod_keep_clear(vs_lod_cache *c)
{
    if (!c) return;
    for (int l = 1; l <= VS_LOD_MAX; l++) {
        vs_volume_release(c->kept[l]);
        c->kept[l] = NULL;
        c->kept_done[l] = 0;
    }
    free(c->kept_alpha);
    c->kept_alpha = NULL;
}

typedef struct keep_job {
    const struct vs_volume *fine, *coarse;
    struct vs_volume *out;
    const vs_classify *c;
    const float *fine_mm; /* min-max per brick of the fine grid */
    int fnb[3], nb[3];    /* brick grids: fine, coarse */
    int dec[3];           /* axes the level halved */
    float base;           /* what non-finite voxels and the outside read */
    float eps;            /* least opacity worth keeping */
    const uint16_t *first; /* lift's table */
    float peak;           /* the table's greatest opacity */
    float *scratch;       /* per worker */
    size_t per_worker;
    size_t *patched;      /* per slab of bricks */
} keep_job;

static inline int clampi(int v, int hi) { return v < 0 ? 0 : v > hi ? hi : v; }

/* Block n[0] x n[1] x n[2] of v from index o (clamped to the volume), as
 * floats, non-finite values read as base. */
static void read_block(const struct vs_volume *v, const int o[3], const int n[3], float base, float *b)
{
    const int *d = v->dims;
    const int x0 = o[0] < 0 ? 0 : o[0], x1 = o[0] + n[0] > d[0] ? d[0] : o[0] + n[0];
    for (int z = 0; z < n[2]; z++)
        for (int y = 0; y < n[1]; y++) {
            const size_t row = ((size_t)clampi(o[2] + z, d[2] - 1) * d[1] + clampi(o[1] + y, d[1] - 1)) * d[0];
            float *out = b + ((size_t)z * n[1] + y) * n[0];
            if (x1 > x0) {
                vs_volume_axpy_floats(v, row + x0, (size_t)(x1 - x0), 1.0f, base, 1, out + (x0 - o[0]));
            } else { /* the block lies past a face: the face's voxel */
                const double val = vs_volume_at(v, row + clampi(o[0], d[0] - 1));
                for (int x = 0; x < n[0]; x++) out[x] = isfinite(val) ? (float)val : base;
                continue;
            }
            for (int x = 0; x < x0 - o[0]; x++) out[x] = out[x0 - o[0]];
            for (int x = x1 - o[0]; x < n[0]; x++) out[x] = out[x1 - 1 - o[0]];
        }
}

/* The kernel [1 4 1]/6 along every axis of a block, in place (tmp: a block
 * of the same size); the faces repeat their voxel. */
static void kernel3(float *b, float *tmp, const int n[3])
{
    const size_t sy = (size_t)n[0], sz = (size_t)n[0] * n[1];
    const float q = 1.0f / 6.0f;
    /* x into tmp */
    for (size_t r = 0; r < sz * n[2]; r += sy) {
        const float *in = b + r;
        float *out = tmp + r;
        if (n[0] == 1) {
            out[0] = in[0];
            continue;
        }
        out[0] = (5.0f * in[0] + in[1]) * q;
        for (int x = 1; x < n[0] - 1; x++) out[x] = (in[x - 1] + 4.0f * in[x] + in[x + 1]) * q;
        out[n[0] - 1] = (in[n[0] - 2] + 5.0f * in[n[0] - 1]) * q;
    }
    /* y into b */
    for (int z = 0; z < n[2]; z++)
        for (int y = 0; y < n[1]; y++) {
            const float *m = tmp + z * sz + y * sy, *l = y > 0 ? m - sy : m, *h = y < n[1] - 1 ? m + sy : m;
            float *out = b + z * sz + y * sy;
            for (int x = 0; x < n[0]; x++) out[x] = (l[x] + 4.0f * m[x] + h[x]) * q;
        }
    /* z into tmp, then back */
    for (int z = 0; z < n[2]; z++) {
        const float *m = b + z * sz, *l = z > 0 ? m - sz : m, *h = z < n[2] - 1 ? m + sz : m;
        float *out = tmp + z * sz;
        for (size_t x = 0; x < sz; x++) out[x] = (l[x] + 4.0f * m[x] + h[x]) * q;
    }
    memcpy(b, tmp, sz * n[2] * sizeof *b);
}

/* lift's table: for LIFT_Q + 1 steps q of the peak opacity and each entry
 * i of the opacity table, the first entry from i on whose opacity reaches
 * peak q / LIFT_Q (VS_TF_TABLE: none). */
#define LIFT_Q 64
static uint16_t *lift_table(const vs_classify *c, float peak)
{
    uint16_t *f = malloc((size_t)(LIFT_Q + 1) * VS_TF_TABLE * sizeof *f);
    if (!f) return NULL;
    for (int q = 0; q <= LIFT_Q; q++) {
        const float thr = peak * (float)q / LIFT_Q;
        uint16_t *row = f + (size_t)q * VS_TF_TABLE, next = VS_TF_TABLE;
        for (int i = VS_TF_TABLE - 1; i >= 0; i--) row[i] = next = c->alpha[i] >= thr ? (uint16_t)i : next;
    }
    return f;
}

/* The least value at or above r whose opacity reaches a (0 < a <= peak),
 * from the table; NAN when none.  Entries before first[q][i] lie under
 * peak q / LIFT_Q <= a: the search starts there. */
static float lift(const keep_job *J, float r, float a)
{
    const vs_classify *c = J->c;
    const double x = (r - c->vmin) * c->scale;
    if (!(x < VS_TF_TABLE - 1)) return NAN;
    int q = (int)(a / J->peak * LIFT_Q);
    q = q < 0 ? 0 : q > LIFT_Q ? LIFT_Q : q;
    int i = J->first[(size_t)q * VS_TF_TABLE + (x <= 0.0 ? 0 : (int)ceil(x))];
    for (; i < VS_TF_TABLE; i++)
        if (c->alpha[i] >= a) return (float)(c->vmin + i / c->scale);
    return NAN;
}

/* Can the fine grid show anything over fine box [lo, hi] (inclusive)?  Not
 * when every value there lies on one side of the relevant range. */
static int fine_can_show(const keep_job *J, const int lo[3], const int hi[3])
{
    int b0[3], b1[3];
    for (int a = 0; a < 3; a++) {
        b0[a] = clampi(lo[a], J->fine->dims[a] - 1) / VS_BRICK;
        b1[a] = clampi(hi[a], J->fine->dims[a] - 1) / VS_BRICK;
    }
    float mn = INFINITY, mx = -INFINITY;
    for (int k = b0[2]; k <= b1[2]; k++)
        for (int j = b0[1]; j <= b1[1]; j++)
            for (int i = b0[0]; i <= b1[0]; i++) {
                const float *m = J->fine_mm + 2 * (((size_t)k * J->fnb[1] + j) * J->fnb[0] + i);
                if (m[0] < mn) mn = m[0];
                if (m[1] > mx) mx = m[1];
            }
    if (!isfinite(mn)) return 1; /* a NaN reads as base */
    return !(mx < J->c->alpha_lo || mn > J->c->alpha_hi);
}

/* Along axis a of block `in` (sizes n, updated to len there), output
 * voxel x the taps [1 3 3 1]/8 on in[2x + 1 .. 2x + 4] (halved) or
 * in[x + 1] (kept). */
static void down_axis(const float *in, int n[3], int a, int halved, int len, float *out)
{
    const size_t is[3] = {1, (size_t)n[0], (size_t)n[0] * n[1]}, sa = is[a];
    int no[3] = {n[0], n[1], n[2]};
    no[a] = len;
    float *o = out;
    for (int z = 0; z < no[2]; z++)
        for (int y = 0; y < no[1]; y++) {
            if (a == 0) {
                const float *r = in + z * is[2] + y * is[1];
                if (halved)
                    for (int x = 0; x < len; x++)
                        o[x] = 0.125f * (r[2 * x + 1] + r[2 * x + 4]) + 0.375f * (r[2 * x + 2] + r[2 * x + 3]);
                else
                    for (int x = 0; x < len; x++) o[x] = r[x + 1];
            } else {
                const int q = a == 1 ? y : z;
                const float *r = in + (a == 1 ? z * is[2] : y * is[1]) + (size_t)((halved ? 2 * q : q) + 1) * sa;
                if (halved)
                    for (int x = 0; x < no[0]; x++)
                        o[x] = 0.125f * (r[x] + r[x + 3 * sa]) + 0.375f * (r[x + sa] + r[x + 2 * sa]);
                else
                    for (int x = 0; x < no[0]; x++) o[x] = r[x];
            }
            o += no[0];
        }
    n[a] = len;
}

static size_t keep_brick(const keep_job *J, float *s, int bi, int bj, int bk)
{
    const vs_classify *c = J->c;
    const int *cd = J->coarse->dims;
    int o[3], n[3], fo[3], fn[3], co[3], cn[3], flo[3], fhi[3];
    const int bo[3] = {bi, bj, bk};
    for (int a = 0; a < 3; a++) {
        o[a] = bo[a] * VS_BRICK;
        n[a] = o[a] + VS_BRICK <= cd[a] ? VS_BRICK : cd[a] - o[a];
        fo[a] = J->dec[a] ? 2 * o[a] - 4 : o[a] - 2;
        fn[a] = J->dec[a] ? 2 * n[a] + 8 : n[a] + 4;
        co[a] = o[a] - 3;
        cn[a] = n[a] + 6;
        flo[a] = fo[a];
        fhi[a] = fo[a] + fn[a] - 1;
    }
    if (!fine_can_show(J, flo, fhi)) return 0;
    const size_t fsz = (size_t)fn[0] * fn[1] * fn[2], csz = (size_t)cn[0] * cn[1] * cn[2];
    float *fv = s, *fa = fv + FB * FB * FB, *tmp = fa + FB * FB * FB, *cv = tmp + FB * FB * FB,
          *cr = cv + CB * CB * CB, *ca = cr + CB * CB * CB, *tgt = ca + CB * CB * CB, *gain = tgt + CB * CB * CB,
          *nv = gain + CB * CB * CB, *top = nv + CB * CB * CB;

    /* the coarse reconstruction and its opacity first: most bricks are
     * visible or empty throughout */
    read_block(J->coarse, co, cn, J->base, cv);
    memcpy(cr, cv, csz * sizeof *cr);
    kernel3(cr, tmp, cn);
    const float alo = (float)c->alpha_lo, ahi = (float)c->alpha_hi;
    for (size_t i = 0; i < csz; i++) ca[i] = cr[i] > alo && cr[i] < ahi ? vs_classify_alpha(c, cr[i]) : 0.0f;

    /* the most opaque coarse voxel around each (in gain, for now): where
     * it passes half the peak, none is lost; a brick without others stops */
    size_t open = 0;
    for (int z = -1; z <= n[2]; z++)
        for (int y = -1; y <= n[1]; y++)
            for (int x = -1; x <= n[0]; x++) {
                float around = 0.0f;
                for (int dz = 2; dz <= 4; dz++)
                    for (int dy = 2; dy <= 4; dy++)
                        for (int dx = 2; dx <= 4; dx++) {
                            const float a = ca[((size_t)(z + dz) * cn[1] + y + dy) * cn[0] + x + dx];
                            if (a > around) around = a;
                        }
                gain[((size_t)(z + 3) * cn[1] + y + 3) * cn[0] + x + 3] = around;
                open += around < 0.5f * J->peak;
            }
    if (!open) return 0;

    /* the fine grid's opacity, filtered down as the level is: A */
    read_block(J->fine, fo, fn, J->base, fv);
    memcpy(fa, fv, fsz * sizeof *fa);
    kernel3(fa, tmp, fn);
    for (size_t i = 0; i < fsz; i++) fa[i] = fa[i] > alo && fa[i] < ahi ? vs_classify_alpha(c, fa[i]) : 0.0f;
    /* A for the brick and its ring, axis by axis: fa -> tmp -> fa -> tmp */
    int na[3] = {fn[0], fn[1], fn[2]};
    float *const A = tmp;
    for (int a = 0; a < 3; a++)
        down_axis(a == 1 ? tmp : fa, na, a, J->dec[a], n[a] + 2, a == 1 ? fa : tmp);
    size_t lost = 0;
    for (size_t i = 0; i < csz; i++) tgt[i] = NAN;
    for (int z = -1; z <= n[2]; z++)
        for (int y = -1; y <= n[1]; y++)
            for (int x = -1; x <= n[0]; x++) {
                const size_t ci = ((size_t)(z + 3) * cn[1] + y + 3) * cn[0] + x + 3;
                const float around = gain[ci];
                const size_t ai = ((size_t)(z + 1) * (n[1] + 2) + y + 1) * (n[0] + 2) + x + 1;
                const float a = A[ai];
                if (!(a > J->eps) || !(around < 0.5f * a)) continue;
                /* the greatest fine value under it: no higher */
                const int p[3] = {J->dec[0] ? 2 * x + 3 : x + 2, J->dec[1] ? 2 * y + 3 : y + 2,
                                  J->dec[2] ? 2 * z + 3 : z + 2};
                float vmax = -INFINITY;
                for (int tz = 0; tz < (J->dec[2] ? 4 : 1); tz++)
                    for (int ty = 0; ty < (J->dec[1] ? 4 : 1); ty++)
                        for (int tx = 0; tx < (J->dec[0] ? 4 : 1); tx++) {
                            const float v = fv[((size_t)(p[2] + tz) * fn[1] + p[1] + ty) * fn[0] + p[0] + tx];
                            if (v > vmax) vmax = v;
                        }
                const float t = lift(J, cr[ci], a);
                if (!(t > cr[ci]) || !(vmax > cv[ci])) continue;
                tgt[ci] = t;
                top[ci] = vmax;
                lost += x >= 0 && x < n[0] && y >= 0 && y < n[1] && z >= 0 && z < n[2];
            }
    if (!lost) return 0;

    /* the kernel's weight over the lost voxels */
    for (size_t i = 0; i < csz; i++) gain[i] = isnan(tgt[i]) ? 0.0f : 1.0f;
    kernel3(gain, tmp, cn);
    memcpy(nv, cv, csz * sizeof *nv);
    for (int it = 0; it <= KEEP_JACOBI; it++) {
        if (it > 0) {
            memcpy(cr, nv, csz * sizeof *cr);
            kernel3(cr, tmp, cn);
        }
        for (size_t i = 0; i < csz; i++) {
            if (isnan(tgt[i])) continue;
            float v = nv[i] + (tgt[i] - cr[i]) / gain[i];
            v = v < cv[i] ? cv[i] : v > top[i] ? top[i] : v;
            nv[i] = v;
        }
    }
    const int *od = J->out->dims;
    for (int z = 0; z < n[2]; z++)
        for (int y = 0; y < n[1]; y++)
            for (int x = 0; x < n[0]; x++) {
                const size_t ci = ((size_t)(z + 3) * cn[1] + y + 3) * cn[0] + x + 3;
                if (isnan(tgt[ci])) continue;
                vs_volume_store_floats(J->out, ((size_t)(o[2] + z) * od[1] + o[1] + y) * od[0] + o[0] + x, &nv[ci], 1);
            }
    return lost;
}

static void keep_slab(void *arg, int worker, int bk)
{
    const keep_job *J = arg;
    float *s = J->scratch + (size_t)worker * J->per_worker;
    size_t lost = 0;
    for (int bj = 0; bj < J->nb[1]; bj++)
        for (int bi = 0; bi < J->nb[0]; bi++) lost += keep_brick(J, s, bi, bj, bk);
    J->patched[bk] = lost;
}

/* The copy of lv patched against fine for c: *out NULL when nothing is lost. */
static vs_status keep_level(vs_context *ctx, struct vs_pool *pool, const struct vs_volume *fine,
                            const float *fine_mm, const struct vs_volume *lv, const struct vs_volume *vol,
                            const vs_classify *c, struct vs_volume **out)
{
    *out = NULL;
    keep_job J = {.fine = fine, .coarse = lv, .c = c, .fine_mm = fine_mm, .base = (float)vs_volume_base(vol)};
    float peak = 0.0f;
    for (int i = 0; i < VS_TF_TABLE; i++)
        if (c->alpha[i] > peak) peak = c->alpha[i];
    if (!(peak > 0.0f)) return VS_OK;
    J.eps = peak / 256.0f;
    J.peak = peak;
    for (int a = 0; a < 3; a++) J.dec[a] = lv->dims[a] != fine->dims[a] || lv->spacing[a] != fine->spacing[a];
    vs_relevant_grid(fine->dims, J.fnb);
    vs_relevant_grid(lv->dims, J.nb);
    struct vs_volume *v = NULL;
    vs_status st = vs_volume_alloc(ctx, lv->type, lv->dims, lv->spacing, &v);
    if (st != VS_OK) return st;
    const size_t nvox = (size_t)lv->dims[0] * lv->dims[1] * lv->dims[2];
    memcpy(v->data, lv->data, nvox * vs_type_size(lv->type));
    J.out = v;
    const int nw = vs_pool_threads(pool);
    J.per_worker = 3 * (size_t)FB * FB * FB + 7 * (size_t)CB * CB * CB;
    J.scratch = malloc(J.per_worker * nw * sizeof *J.scratch);
    J.patched = calloc((size_t)J.nb[2], sizeof *J.patched);
    uint16_t *first = lift_table(c, peak);
    J.first = first;
    if (!J.scratch || !J.patched || !first) {
        free(first);
        free(J.scratch);
        free(J.patched);
        vs_volume_release(v);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "levels of detail: out of memory");
    }
    vs_pool_run(pool, J.nb[2], keep_slab, &J);
    size_t lost = 0;
    for (int k = 0; k < J.nb[2]; k++) lost += J.patched[k];
    free(first);
    free(J.scratch);
    free(J.patched);
    if (!lost) {
        vs_volume_release(v);
        return VS_OK;
    }
    vs_volume_share_classification(v, lv);
    *out = v;
    return VS_OK;
}

static const struct vs_volume *shown(const vs_lod_cache *c, int l, const struct vs_volume *vol)
{
    return l == 0 ? vol : c->kept[l] ? c->kept[l] : c->level[l];
}

vs_status vs_lod_keep(vs_context *ctx, struct vs_pool *pool, vs_lod_cache *cache, const struct vs_volume *vol,
                      int level, const vs_classify *c, const struct vs_volume **out, double *ms)
{
    *ms = 0.0;
    *out = cache->level[level];
    if (cache->kept_alpha && (cache->kept_vmin != c->vmin || cache->kept_scale != c->scale ||
                              memcmp(cache->kept_alpha, c->alpha, sizeof c->alpha)))
        vs_lod_keep_clear(cache);
    if (!cache->kept_alpha) {
        if (!(cache->kept_alpha = malloc(sizeof c->alpha)))
            return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "levels of detail: out of memory");
        memcpy(cache->kept_alpha, c->alpha, sizeof c->alpha);
        cache->kept_vmin = c->vmin;
        cache->kept_scale = c->scale;
    }
    const double t0 = vs_now_ms();
    int worked = 0;
    for (int l = 1; l <= level; l++) {
        if (cache->kept_done[l] && cache->kept_serial[l] == cache->level[l]->serial) continue;
        worked = 1;
        /* this level anew, and so every coarser one */
        for (int m = l; m <= VS_LOD_MAX; m++) {
            vs_volume_release(cache->kept[m]);
            cache->kept[m] = NULL;
            cache->kept_done[m] = 0;
        }
        const struct vs_volume *fine = shown(cache, l - 1, vol);
        float *mm = NULL;
        if (l == 1) {
            if (!cache->base_minmax) cache->base_minmax = vs_relevant_minmax(pool, vol);
            mm = cache->base_minmax;
        } else {
            mm = vs_relevant_minmax(pool, fine);
        }
        if (!mm) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "levels of detail: out of memory");
        vs_status st = keep_level(ctx, pool, fine, mm, cache->level[l], vol, c, &cache->kept[l]);
        if (l > 1) free(mm);
        if (st != VS_OK) return st;
        cache->kept_done[l] = 1;
        cache->kept_serial[l] = cache->level[l]->serial;
    }
    if (worked) *ms = vs_now_ms() - t0;
    /* the copy lands where its level does (vs_volume_set_transform) */
    for (int l = 1; l <= level; l++) {
        struct vs_volume *k = cache->kept[l];
        if (!k) continue;
        memcpy(k->affine, cache->level[l]->affine, sizeof k->affine);
        k->has_orientation = cache->level[l]->has_orientation;
        k->vmin = cache->level[l]->vmin;
        k->vmax = cache->level[l]->vmax;
    }
    *out = shown(cache, level, vol);
    return VS_OK;
}
