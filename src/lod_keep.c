/* Levels of detail that keep what the classification shows (lod_keep.h).
 *
 * For level l (coarse) and the level it was made from (fine: the volume
 * itself, or level l-1 as patched), brick by brick of the coarse grid
 * (skipping bricks whose fine values all lie on one side of the relevant
 * range, or, for an iso-range, whose coarse values around are all at
 * least half opaque), a first pass finds the lost voxels:
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
 *  - each lost voxel's target T, the least value from its reconstruction
 *    upwards whose opacity is A, and its ceiling, the largest fine value
 *    under it; where none is higher, or no value above has that opacity
 *    (a dark sheet in bright tissue, under an iso-range with an upper
 *    end), the greatest value downwards and its floor, the least fine
 *    value under it.
 * A second pass moves each brick's lost voxels (from the level's value
 * towards the ceiling or floor, never past it) so that the reconstruction
 * there reaches T, counting
 * the lost voxels of the bricks next to it within one voxel: a first step
 * divides what is missing by the kernel's weight over the lost voxels
 * (exact for a uniform sheet, line or point), three Jacobi steps of the
 * same kind settle uneven ones.
 *
 * Each brick reads the plain level, the fine grid and the first pass's
 * lists, and writes only its own voxels of the copy, so the copy is the
 * same for any thread count. */
#include "lod_keep.h"
#include "context.h"
#include "pool.h"
#include "relevant_bricks.h"
#include "relevant_class.h"
#include "timing.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define KEEP_JACOBI 3
/* block edges: the fine taps of a brick and the kernel around them; the
 * level's brick and a ring of 3 */
#define FB (2 * VS_BRICK + 4)
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

/* A lost voxel: its place in its brick (as vs_voxel), the reconstruction
 * it must reach, and how far it may move: raised, the greatest fine value
 * under it; lowered, the least. */
typedef struct lost_voxel {
    uint16_t at;
    float t, bound;
} lost_voxel;

typedef struct keep_job {
    const struct vs_volume *fine, *coarse;
    struct vs_volume *out;
    const vs_classify *c;
    const float *fine_mm; /* min-max per brick of the fine grid */
    const float *coarse_mm; /* and of the level */
    int fnb[3], nb[3];    /* brick grids: fine, coarse */
    int dec[3];           /* axes the level halved */
    float base;           /* what non-finite voxels and the outside read */
    float eps;            /* least opacity worth keeping */
    uint16_t *first, *last; /* reach's tables: up (lift) and down (sink) */
    float peak;           /* the table's greatest opacity */
    int iso;              /* an iso-range and ramp: opacity in closed form */
    float a0, a1, inv2r;  /* its ramp's feet (lo - ramp, hi + ramp), 1 / (2 ramp) */
    float *scratch;       /* per worker */
    size_t per_worker;
    size_t *patched;      /* per slab of bricks */
    struct lost_voxel **lost; /* per brick of the level: its lost voxels */
    uint16_t *nlost;
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

/* The greatest of each voxel and its neighbours (3x3x3) of block b into
 * out (tmp: a block of the same size); the faces repeat their voxel. */
static void max3(const float *b, float *tmp, float *out, const int n[3])
{
    const size_t sy = (size_t)n[0], sz = (size_t)n[0] * n[1];
    for (size_t r = 0; r < sz * n[2]; r += sy)
        for (int x = 0; x < n[0]; x++) {
            const float l = b[r + (x > 0 ? x - 1 : x)], m = b[r + x], h = b[r + (x < n[0] - 1 ? x + 1 : x)];
            const float lm = l > m ? l : m;
            tmp[r + x] = lm > h ? lm : h;
        }
    for (int z = 0; z < n[2]; z++)
        for (int y = 0; y < n[1]; y++) {
            const float *m = tmp + z * sz + y * sy, *l = y > 0 ? m - sy : m, *h = y < n[1] - 1 ? m + sy : m;
            float *o = out + z * sz + y * sy;
            for (int x = 0; x < n[0]; x++) {
                const float lm = l[x] > m[x] ? l[x] : m[x];
                o[x] = lm > h[x] ? lm : h[x];
            }
        }
    memcpy(tmp, out, sz * n[2] * sizeof *out);
    for (int z = 0; z < n[2]; z++) {
        const float *m = tmp + z * sz, *l = z > 0 ? m - sz : m, *h = z < n[2] - 1 ? m + sz : m;
        float *o = out + z * sz;
        for (size_t x = 0; x < sz; x++) {
            const float lm = l[x] > m[x] ? l[x] : m[x];
            o[x] = lm > h[x] ? lm : h[x];
        }
    }
}

/* lift's and sink's tables: for LIFT_Q + 1 steps q of the peak opacity and
 * each entry i of the opacity table, the nearest entry from i on (up:
 * lift's) or up to i (sink's) whose opacity reaches peak q / LIFT_Q
 * (VS_TF_TABLE: none). */
#define LIFT_Q 64
static uint16_t *reach_table(const vs_classify *c, float peak, int up)
{
    uint16_t *f = malloc((size_t)(LIFT_Q + 1) * VS_TF_TABLE * sizeof *f);
    if (!f) return NULL;
    for (int q = 0; q <= LIFT_Q; q++) {
        const float thr = peak * (float)q / LIFT_Q;
        uint16_t *row = f + (size_t)q * VS_TF_TABLE, near = VS_TF_TABLE;
        for (int n = 0; n < VS_TF_TABLE; n++) {
            const int i = up ? VS_TF_TABLE - 1 - n : n;
            row[i] = near = c->alpha[i] >= thr ? (uint16_t)i : near;
        }
    }
    return f;
}

/* The nearest value from r upwards (up: lift) or downwards (sink: a dark
 * structure thinner than a level voxel, under an iso-range with an upper
 * end, is averaged above it) whose opacity reaches a (0 < a <= peak), from
 * the tables; NAN when none.  Entries between r and the table's entry lie
 * under peak q / LIFT_Q <= a: the search starts there. */
static float reach(const keep_job *J, float r, float a, int up)
{
    const vs_classify *c = J->c;
    const double x = (r - c->vmin) * c->scale;
    if (up ? !(x < VS_TF_TABLE - 1) : !(x >= 0.0)) return NAN;
    int q = (int)(a / J->peak * LIFT_Q);
    q = q < 0 ? 0 : q > LIFT_Q ? LIFT_Q : q;
    const int from = up ? (x <= 0.0 ? 0 : (int)ceil(x)) : (x >= VS_TF_TABLE - 1 ? VS_TF_TABLE - 1 : (int)floor(x));
    for (int i = (up ? J->first : J->last)[(size_t)q * VS_TF_TABLE + from]; i >= 0 && i < VS_TF_TABLE; i += up ? 1 : -1)
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

/* The n values x replaced by their opacity: the iso-range's in closed
 * form (what the table samples; this vectorises), else the table's. */
static void classify_n(const keep_job *J, float *x, size_t n)
{
    const vs_classify *c = J->c;
    if (J->iso) {
        const float a0 = J->a0, a1 = J->a1, k = J->inv2r, peak = J->peak;
        /* min and max as |.| (branch-free: the loop vectorises); the
         * values are finite (read_block) */
        const int band = isfinite(a1);
        for (size_t i = 0; i < n; i++) {
            const float a = (x[i] - a0) * k, b = band ? (a1 - x[i]) * k : a;
            float m = 0.5f * (a + b - fabsf(a - b));
            m = 0.5f * (m + fabsf(m));
            x[i] = 0.5f * (m + 1.0f - fabsf(m - 1.0f)) * peak;
        }
        return;
    }
    const float alo = (float)c->alpha_lo, ahi = (float)c->alpha_hi;
    for (size_t i = 0; i < n; i++) x[i] = x[i] > alo && x[i] < ahi ? vs_classify_alpha(c, x[i]) : 0.0f;
}

/* Is every level voxel of brick (bi, bj, bk) and its ring at least half
 * opaque?  Then none is lost.  Known for an iso-range from the min-max of
 * the bricks around (its opacity has no dip between two values); a
 * transfer function's table is not asked. */
static int level_opaque(const keep_job *J, int bi, int bj, int bk)
{
    if (!J->iso) return 0;
    float mn = INFINITY, mx = -INFINITY;
    for (int k = bk - 1; k <= bk + 1; k++)
        for (int j = bj - 1; j <= bj + 1; j++)
            for (int i = bi - 1; i <= bi + 1; i++) {
                if (i < 0 || j < 0 || k < 0 || i >= J->nb[0] || j >= J->nb[1] || k >= J->nb[2]) continue;
                const float *m = J->coarse_mm + 2 * (((size_t)k * J->nb[1] + j) * J->nb[0] + i);
                if (m[0] < mn) mn = m[0];
                if (m[1] > mx) mx = m[1];
            }
    if (!(mn >= -FLT_MAX)) return 0; /* a NaN reads as base */
    float v[2] = {mn, mx};
    classify_n(J, v, 2);
    return v[0] >= 0.5f * J->peak && v[1] >= 0.5f * J->peak;
}

/* Phase 1, brick (bi, bj, bk) of the level: its lost voxels, each with
 * the reconstruction it must reach and the greatest fine value under it,
 * into J->lost; their count. */
static size_t find_lost(const keep_job *J, float *s, int bi, int bj, int bk)
{
    const int *cd = J->coarse->dims;
    int o[3], n[3], fo[3], fn[3], co[3], cn[3], flo[3], fhi[3];
    const int bo[3] = {bi, bj, bk};
    for (int a = 0; a < 3; a++) {
        o[a] = bo[a] * VS_BRICK;
        n[a] = o[a] + VS_BRICK <= cd[a] ? VS_BRICK : cd[a] - o[a];
        fo[a] = J->dec[a] ? 2 * o[a] - 2 : o[a] - 1;
        fn[a] = J->dec[a] ? 2 * n[a] + 4 : n[a] + 2;
        co[a] = o[a] - 2;
        cn[a] = n[a] + 4;
        flo[a] = fo[a];
        fhi[a] = fo[a] + fn[a] - 1;
    }
    if (!fine_can_show(J, flo, fhi) || level_opaque(J, bi, bj, bk)) return 0;
    const size_t fsz = (size_t)fn[0] * fn[1] * fn[2], csz = (size_t)cn[0] * cn[1] * cn[2];
    float *fv = s, *fa = fv + FB * FB * FB, *tmp = fa + FB * FB * FB, *cv = tmp + FB * FB * FB,
          *cr = cv + CB * CB * CB, *ca = cr + CB * CB * CB, *around = ca + CB * CB * CB;

    /* the coarse reconstruction and its opacity first, and the most opaque
     * coarse voxel around each: where that passes half the peak none is
     * lost, and most bricks have no others */
    read_block(J->coarse, co, cn, J->base, cv);
    memcpy(cr, cv, csz * sizeof *cr);
    kernel3(cr, tmp, cn);
    memcpy(ca, cr, csz * sizeof *ca);
    classify_n(J, ca, csz);
    max3(ca, tmp, around, cn);
    size_t open = 0;
    for (int z = 0; z < n[2]; z++)
        for (int y = 0; y < n[1]; y++)
            for (int x = 0; x < n[0]; x++)
                open += around[((size_t)(z + 2) * cn[1] + y + 2) * cn[0] + x + 2] < 0.5f * J->peak;
    if (!open) return 0;

    /* the fine grid's opacity, filtered down as the level is: A (in tmp) */
    read_block(J->fine, fo, fn, J->base, fv);
    memcpy(fa, fv, fsz * sizeof *fa);
    kernel3(fa, tmp, fn);
    classify_n(J, fa, fsz);
    int na[3] = {fn[0], fn[1], fn[2]};
    for (int a = 0; a < 3; a++) down_axis(a == 1 ? tmp : fa, na, a, J->dec[a], n[a], a == 1 ? fa : tmp);
    const float *A = tmp;
    lost_voxel *list = NULL;
    size_t lost = 0;
    for (int z = 0; z < n[2]; z++)
        for (int y = 0; y < n[1]; y++)
            for (int x = 0; x < n[0]; x++) {
                const size_t ci = ((size_t)(z + 2) * cn[1] + y + 2) * cn[0] + x + 2;
                const float a = A[((size_t)z * n[1] + y) * n[0] + x];
                if (!(a > J->eps) || !(around[ci] < 0.5f * a)) continue;
                /* the greatest and least fine values under it: no further */
                const int p[3] = {J->dec[0] ? 2 * x + 1 : x + 1, J->dec[1] ? 2 * y + 1 : y + 1,
                                  J->dec[2] ? 2 * z + 1 : z + 1};
                float vmax = -INFINITY, vmin = INFINITY;
                for (int tz = 0; tz < (J->dec[2] ? 4 : 1); tz++)
                    for (int ty = 0; ty < (J->dec[1] ? 4 : 1); ty++)
                        for (int tx = 0; tx < (J->dec[0] ? 4 : 1); tx++) {
                            const float v = fv[((size_t)(p[2] + tz) * fn[1] + p[1] + ty) * fn[0] + p[0] + tx];
                            if (v > vmax) vmax = v;
                            if (v < vmin) vmin = v;
                        }
                /* raised, as a bright sheet averaged into dark space; else
                 * lowered, as a dark one into bright */
                float t = reach(J, cr[ci], a, 1), bound = vmax;
                if (!(t > cr[ci]) || !(vmax > cv[ci])) {
                    t = reach(J, cr[ci], a, 0);
                    bound = vmin;
                    if (!(t < cr[ci]) || !(vmin < cv[ci])) continue;
                }
                if (!list && !(list = malloc((size_t)VS_BRICK * VS_BRICK * VS_BRICK * sizeof *list))) return SIZE_MAX;
                list[lost].at = (uint16_t)(x | y << VS_BRICK_BITS | z << (2 * VS_BRICK_BITS));
                list[lost].t = t;
                list[lost].bound = bound;
                lost++;
            }
    const size_t b = ((size_t)bk * J->nb[1] + bj) * J->nb[0] + bi;
    J->lost[b] = list;
    J->nlost[b] = (uint16_t)lost;
    return lost;
}

/* Phase 2, brick (bi, bj, bk): its lost voxels moved, those of the
 * bricks around it within one voxel taken into account. */
static void move_lost(const keep_job *J, float *s, int bi, int bj, int bk)
{
    const int *cd = J->coarse->dims;
    const int bo[3] = {bi, bj, bk};
    int o[3], n[3], co[3], cn[3];
    for (int a = 0; a < 3; a++) {
        o[a] = bo[a] * VS_BRICK;
        n[a] = o[a] + VS_BRICK <= cd[a] ? VS_BRICK : cd[a] - o[a];
        co[a] = o[a] - 3;
        cn[a] = n[a] + 6;
    }
    const size_t csz = (size_t)cn[0] * cn[1] * cn[2];
    float *cv = s, *cr = cv + CB * CB * CB, *tgt = cr + CB * CB * CB, *gain = tgt + CB * CB * CB,
          *nv = gain + CB * CB * CB, *bnd = nv + CB * CB * CB, *tmp = bnd + CB * CB * CB;
    for (size_t i = 0; i < csz; i++) tgt[i] = NAN;
    for (int dk = -1; dk <= 1; dk++)
        for (int dj = -1; dj <= 1; dj++)
            for (int di = -1; di <= 1; di++) {
                const int q[3] = {bi + di, bj + dj, bk + dk};
                if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= J->nb[0] || q[1] >= J->nb[1] || q[2] >= J->nb[2])
                    continue;
                const size_t b = ((size_t)q[2] * J->nb[1] + q[1]) * J->nb[0] + q[0];
                for (int e = 0; e < J->nlost[b]; e++) {
                    const lost_voxel *lv = &J->lost[b][e];
                    const int l[3] = {q[0] * VS_BRICK + VS_VOXEL_DI(lv->at) - o[0],
                                      q[1] * VS_BRICK + VS_VOXEL_DJ(lv->at) - o[1],
                                      q[2] * VS_BRICK + VS_VOXEL_DK(lv->at) - o[2]};
                    if (l[0] < -1 || l[1] < -1 || l[2] < -1 || l[0] > n[0] || l[1] > n[1] || l[2] > n[2]) continue;
                    const size_t ci = ((size_t)(l[2] + 3) * cn[1] + l[1] + 3) * cn[0] + l[0] + 3;
                    tgt[ci] = lv->t;
                    bnd[ci] = lv->bound;
                }
            }
    read_block(J->coarse, co, cn, J->base, cv);
    memcpy(cr, cv, csz * sizeof *cr);
    kernel3(cr, tmp, cn);
    /* the kernel's weight over the lost voxels; a first step, then Jacobi */
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
            /* between the level's value and the bound */
            const float lo = cv[i] < bnd[i] ? cv[i] : bnd[i], hi = cv[i] < bnd[i] ? bnd[i] : cv[i];
            float v = nv[i] + (tgt[i] - cr[i]) / gain[i];
            v = v < lo ? lo : v > hi ? hi : v;
            nv[i] = v;
        }
    }
    const int *od = J->out->dims;
    const size_t b = ((size_t)bk * J->nb[1] + bj) * J->nb[0] + bi;
    for (int e = 0; e < J->nlost[b]; e++) {
        const uint16_t at = J->lost[b][e].at;
        const int x = VS_VOXEL_DI(at), y = VS_VOXEL_DJ(at), z = VS_VOXEL_DK(at);
        const size_t ci = ((size_t)(z + 3) * cn[1] + y + 3) * cn[0] + x + 3;
        vs_volume_store_floats(J->out, ((size_t)(o[2] + z) * od[1] + o[1] + y) * od[0] + o[0] + x, &nv[ci], 1);
    }
}

static void find_slab(void *arg, int worker, int bk)
{
    const keep_job *J = arg;
    float *s = J->scratch + (size_t)worker * J->per_worker;
    size_t lost = 0;
    for (int bj = 0; bj < J->nb[1]; bj++)
        for (int bi = 0; bi < J->nb[0]; bi++) {
            const size_t n = find_lost(J, s, bi, bj, bk);
            if (n == SIZE_MAX) { /* out of memory: keep_level reports it */
                J->patched[bk] = SIZE_MAX;
                return;
            }
            lost += n;
        }
    J->patched[bk] = lost;
}

static void move_slab(void *arg, int worker, int bk)
{
    const keep_job *J = arg;
    float *s = J->scratch + (size_t)worker * J->per_worker;
    for (int bj = 0; bj < J->nb[1]; bj++)
        for (int bi = 0; bi < J->nb[0]; bi++)
            if (J->nlost[((size_t)bk * J->nb[1] + bj) * J->nb[0] + bi]) move_lost(J, s, bi, bj, bk);
}

/* What every level's job takes from the classification c (the rest of
 * *J zero): its opacity's peak, the closed form of an iso-range, reach's
 * tables (J->first, J->last: free them; NULL when out of memory, or when
 * nothing is visible: peak 0). */
static void class_job(keep_job *J, const vs_classify *c, const struct vs_volume *vol)
{
    memset(J, 0, sizeof *J);
    J->c = c;
    J->base = (float)vs_volume_base(vol);
    for (int i = 0; i < VS_TF_TABLE; i++)
        if (c->alpha[i] > J->peak) J->peak = c->alpha[i];
    if (!(J->peak > 0.0f)) return;
    J->eps = J->peak / 256.0f;
    /* an iso-range with a ramp (vs_classify_setup's iso_alpha): the
     * opacity rises over [lo - ramp, lo + ramp] and falls over [hi - ramp,
     * hi + ramp]; a band narrower than 2 ramp never reaches the plateau,
     * and its opacity comes from the table */
    J->iso = !c->use_points && c->ramp > 0.0 && isfinite(c->lo) && !(c->hi - c->lo < 2.0 * c->ramp);
    if (J->iso) {
        J->a0 = (float)(c->lo - c->ramp);
        J->a1 = isfinite(c->hi) ? (float)(c->hi + c->ramp) : INFINITY;
        J->inv2r = (float)(0.5 / c->ramp);
    }
    J->first = reach_table(c, J->peak, 1);
    J->last = reach_table(c, J->peak, 0);
}

/* The copy of lv patched against fine for the classification in *cj
 * (class_job): *out NULL when nothing is lost. */
static vs_status keep_level(vs_context *ctx, struct vs_pool *pool, const keep_job *cj, const struct vs_volume *fine,
                            const float *fine_mm, const struct vs_volume *lv, const float *coarse_mm,
                            struct vs_volume **out)
{
    *out = NULL;
    if (!(cj->peak > 0.0f)) return VS_OK; /* nothing visible: nothing lost */
    keep_job J = *cj;
    J.fine = fine;
    J.coarse = lv;
    J.fine_mm = fine_mm;
    J.coarse_mm = coarse_mm;
    for (int a = 0; a < 3; a++) J.dec[a] = lv->dims[a] != fine->dims[a] || lv->spacing[a] != fine->spacing[a];
    vs_relevant_grid(fine->dims, J.fnb);
    vs_relevant_grid(lv->dims, J.nb);
    const size_t nbt = (size_t)J.nb[0] * J.nb[1] * J.nb[2];
    const int nw = vs_pool_threads(pool);
    J.per_worker = 3 * (size_t)FB * FB * FB + 7 * (size_t)CB * CB * CB;
    J.scratch = malloc(J.per_worker * nw * sizeof *J.scratch);
    J.patched = calloc((size_t)J.nb[2], sizeof *J.patched);
    J.lost = calloc(nbt, sizeof *J.lost);
    J.nlost = calloc(nbt, sizeof *J.nlost);
    vs_status st = VS_OK;
    struct vs_volume *v = NULL;
    size_t lost = 0;
    if (!J.scratch || !J.patched || !J.lost || !J.nlost) {
        st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "levels of detail: out of memory");
        goto done;
    }
    vs_pool_run(pool, J.nb[2], find_slab, &J);
    for (int k = 0; k < J.nb[2]; k++) {
        if (J.patched[k] == SIZE_MAX) {
            st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "levels of detail: out of memory");
            goto done;
        }
        lost += J.patched[k];
    }
    if (!lost) goto done;
    /* the copy, then its lost voxels moved */
    if ((st = vs_volume_alloc(ctx, lv->type, lv->dims, lv->spacing, &v)) != VS_OK) goto done;
    memcpy(v->data, lv->data, (size_t)lv->dims[0] * lv->dims[1] * lv->dims[2] * vs_type_size(lv->type));
    J.out = v;
    vs_pool_run(pool, J.nb[2], move_slab, &J);
done:
    if (J.lost)
        for (size_t b = 0; b < nbt; b++) free(J.lost[b]);
    free(J.lost);
    free(J.nlost);
    free(J.scratch);
    free(J.patched);
    if (st != VS_OK || !v) return st;
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
    keep_job cj; /* made for the first level that needs patching */
    int worked = 0;
    vs_status st = VS_OK;
    for (int l = 1; l <= level; l++) {
        if (cache->kept_done[l] && cache->kept_serial[l] == cache->level[l]->serial) continue;
        if (!worked) {
            worked = 1;
            class_job(&cj, c, vol);
            if (cj.peak > 0.0f && (!cj.first || !cj.last)) {
                st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "levels of detail: out of memory");
                break;
            }
        }
        /* this level anew, and so every coarser one */
        for (int m = l; m <= VS_LOD_MAX; m++) {
            vs_volume_release(cache->kept[m]);
            cache->kept[m] = NULL;
            cache->kept_done[m] = 0;
        }
        const struct vs_volume *fine = shown(cache, l - 1, vol);
        /* min-max per brick: of the plain grids once, of a patched one anew */
        float *mm = NULL; /* a patched fine level's own */
        for (int m = l - 1; m <= l; m++)
            if (!cache->minmax[m] && !(cache->minmax[m] = vs_relevant_minmax(pool, m == 0 ? vol : cache->level[m])))
                st = VS_ERR_OUT_OF_MEMORY;
        if (st == VS_OK && l > 1 && cache->kept[l - 1] && !(mm = vs_relevant_minmax(pool, fine)))
            st = VS_ERR_OUT_OF_MEMORY;
        if (st != VS_OK) {
            st = vs_set_error(ctx, st, "levels of detail: out of memory");
            break;
        }
        st = keep_level(ctx, pool, &cj, fine, mm ? mm : cache->minmax[l - 1], cache->level[l], cache->minmax[l],
                        &cache->kept[l]);
        free(mm);
        if (st != VS_OK) break;
        cache->kept_done[l] = 1;
        cache->kept_serial[l] = cache->level[l]->serial;
    }
    if (worked) {
        free(cj.first);
        free(cj.last);
        *ms = vs_now_ms() - t0;
    }
    if (st != VS_OK) return st;
    /* the copy lands where its level does (vs_volume_set_transform
     * re-places the levels; a new range gives them new serials, and so
     * new copies, made with their range) */
    for (int l = 1; l <= level; l++) {
        struct vs_volume *k = cache->kept[l];
        if (!k) continue;
        memcpy(k->affine, cache->level[l]->affine, sizeof k->affine);
        k->has_orientation = cache->level[l]->has_orientation;
    }
    *out = shown(cache, level, vol);
    return VS_OK;
}
