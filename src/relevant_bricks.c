/* The relevant-voxel list built brick by brick (relevant_bricks.h): a
 * min-max per brick, then only the bricks the classification can reach,
 * each worked out on a block of bit rows around it. */
#include "context.h"
#include "pool.h"
#include "relevant_bricks.h"
#include "relevant_class.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* The first voxel of brick b (linear in k, j, i order) of a grid of nb bricks. */
static void brick_origin(uint32_t b, const int nb[3], int o[3])
{
    o[0] = (int)(b % (uint32_t)nb[0]) * VS_BRICK;
    o[1] = (int)(b / (uint32_t)nb[0] % (uint32_t)nb[1]) * VS_BRICK;
    o[2] = (int)(b / ((uint32_t)nb[0] * (uint32_t)nb[1])) * VS_BRICK;
}

typedef struct minmax_job {
    const struct vs_volume *vol;
    int nb[3];
    float *mm; /* 2 per brick */
} minmax_job;

/* A slab of bricks' minima and maxima: each row of bricks (bj) folds its
 * 64 grid rows column by column (vertical min and max, which vectorise),
 * then each brick reduces its 8 columns.  NaN is kept apart: a brick
 * holding one is never "all inside" (its minimum becomes -inf). */
#define MINMAX_SLAB(T, INIT_LO, INIT_HI, ISNAN)                                                                   \
    do {                                                                                                           \
        T *cl = (T *)cols, *ch = cl + d[0];                                                                        \
        uint8_t *cn = (uint8_t *)(ch + d[0]);                                                                      \
        for (int bj = 0; bj < nb[1]; bj++) {                                                                       \
            for (int i = 0; i < d[0]; i++) cl[i] = INIT_LO, ch[i] = INIT_HI, cn[i] = 0;                            \
            const int j1 = (bj + 1) * VS_BRICK < d[1] ? (bj + 1) * VS_BRICK : d[1];                                \
            for (int k = bk * VS_BRICK; k < k1; k++)                                                               \
                for (int j = bj * VS_BRICK; j < j1; j++) {                                                         \
                    const T *p = (const T *)J->vol->data + ((size_t)k * d[1] + j) * d[0];                          \
                    for (int i = 0; i < d[0]; i++) {                                                               \
                        cl[i] = p[i] < cl[i] ? p[i] : cl[i];                                                       \
                        ch[i] = p[i] > ch[i] ? p[i] : ch[i];                                                       \
                        cn[i] |= ISNAN(p[i]);                                                                      \
                    }                                                                                              \
                }                                                                                                  \
            float *m = mm + 2 * (size_t)bj * nb[0];                                                                \
            for (int bi = 0; bi < nb[0]; bi++) {                                                                   \
                const int i0 = bi * VS_BRICK, i1 = i0 + VS_BRICK < d[0] ? i0 + VS_BRICK : d[0];                    \
                float lo = INFINITY, hi = -INFINITY;                                                               \
                int nan = 0;                                                                                       \
                for (int i = i0; i < i1; i++) {                                                                    \
                    lo = (float)cl[i] < lo ? (float)cl[i] : lo;                                                    \
                    hi = (float)ch[i] > hi ? (float)ch[i] : hi;                                                    \
                    nan |= cn[i];                                                                                  \
                }                                                                                                  \
                m[2 * bi] = nan ? -INFINITY : lo;                                                                  \
                m[2 * bi + 1] = hi;                                                                                \
            }                                                                                                      \
        }                                                                                                          \
    } while (0)
#define NEVER_NAN(x) 0
#define IS_NAN(x) ((x) != (x))

static void minmax_slab(void *arg, int worker, int bk)
{
    (void)worker;
    const minmax_job *J = arg;
    const int *d = J->vol->dims, *nb = J->nb;
    float *mm = J->mm + 2 * (size_t)bk * nb[1] * nb[0];
    const int k1 = (bk + 1) * VS_BRICK < d[2] ? (bk + 1) * VS_BRICK : d[2];
    void *cols = malloc((size_t)d[0] * (2 * sizeof(float) + 1));
    if (!cols) { /* no room for the columns: the slab's bricks reach everything */
        for (size_t b = 0; b < (size_t)nb[1] * nb[0]; b++) {
            mm[2 * b] = -INFINITY;
            mm[2 * b + 1] = INFINITY;
        }
        return;
    }
    switch (J->vol->type) {
    case VS_U8: MINMAX_SLAB(uint8_t, UINT8_MAX, 0, NEVER_NAN); break;
    case VS_I16: MINMAX_SLAB(int16_t, INT16_MAX, INT16_MIN, NEVER_NAN); break;
    case VS_U16: MINMAX_SLAB(uint16_t, UINT16_MAX, 0, NEVER_NAN); break;
    default: MINMAX_SLAB(float, INFINITY, -INFINITY, IS_NAN); break;
    }
    free(cols);
}

float *vs_relevant_minmax(struct vs_pool *pool, const struct vs_volume *vol)
{
    minmax_job J = {vol, {0, 0, 0}, NULL};
    float *mm = malloc(2 * vs_relevant_grid(vol->dims, J.nb) * sizeof *mm);
    if (!mm) return NULL;
    J.mm = mm;
    vs_pool_run(pool, J.nb[2], minmax_slab, &J);
    return mm;
}

/* Bricks whose voxels can be relevant.  Without a seam: those whose own
 * values reach the closed range [alpha_lo, alpha_hi].  With one: a voxel w
 * meets the rule when its 3x3x3 neighbourhood holds a value inside or values
 * on both sides, so the bricks whose 3x3x3 bricks' range reaches the range
 * (seeds) hold every such w; a relevant voxel lies within `seam` of one.
 * Any brick holding a w that a voxel of brick b needs, from more than one
 * brick away, has its neighbour towards b seeded too (w's own brick's range
 * is in its neighbours'), and from there seam voxels reach at most
 * floor(seam / VS_BRICK) bricks further: the seeds dilated by that many
 * bricks.  A superset of the exact bricks, in k, j, i order. */
static size_t region_bricks(const float *mm, const int nb[3], const vs_classify *c, int seam, uint8_t *seed,
                            uint8_t *reg, uint32_t *list, uint8_t *full, size_t *nfull)
{
    const size_t nbt = (size_t)nb[0] * nb[1] * nb[2];
    const int nr = seam > 0 ? 1 : 0, rb = seam > 0 ? seam / VS_BRICK : 0;
    const double lo = c->alpha_lo, hi = c->alpha_hi;
    /* the 3x3x3 bricks' range, separably: running min and max over +-nr
     * bricks along x, then y, then z (two float planes per pass) */
    float *a = malloc(2 * nbt * sizeof *a), *nx = a ? malloc(2 * nbt * sizeof *nx) : NULL;
    if (!a || !nx) { /* no room: every brick a seed */
        free(a);
        memset(seed, 1, nbt);
    } else {
        memcpy(a, mm, 2 * nbt * sizeof *a);
        const size_t st[3] = {1, (size_t)nb[0], (size_t)nb[0] * nb[1]};
        for (int ax = 0; ax < 3 && nr; ax++) {
            for (int bk = 0; bk < nb[2]; bk++)
                for (int bj = 0; bj < nb[1]; bj++)
                    for (int bi = 0; bi < nb[0]; bi++) {
                        const int c3[3] = {bi, bj, bk};
                        const size_t at = ((size_t)bk * nb[1] + bj) * nb[0] + bi;
                        float m = a[2 * at], M = a[2 * at + 1];
                        if (c3[ax] > 0) {
                            m = a[2 * (at - st[ax])] < m ? a[2 * (at - st[ax])] : m;
                            M = a[2 * (at - st[ax]) + 1] > M ? a[2 * (at - st[ax]) + 1] : M;
                        }
                        if (c3[ax] + 1 < nb[ax]) {
                            m = a[2 * (at + st[ax])] < m ? a[2 * (at + st[ax])] : m;
                            M = a[2 * (at + st[ax]) + 1] > M ? a[2 * (at + st[ax]) + 1] : M;
                        }
                        nx[2 * at] = m;
                        nx[2 * at + 1] = M;
                    }
            float *t = a;
            a = nx;
            nx = t;
        }
        for (size_t i = 0; i < nbt; i++) seed[i] = a[2 * i] <= a[2 * i + 1] && a[2 * i + 1] >= lo && a[2 * i] <= hi;
        free(a);
        free(nx);
    }
    memset(reg, 0, nbt);
    for (int bk = 0; bk < nb[2]; bk++)
        for (int bj = 0; bj < nb[1]; bj++)
            for (int bi = 0; bi < nb[0]; bi++) {
                if (!seed[((size_t)bk * nb[1] + bj) * nb[0] + bi]) continue;
                for (int k = bk - rb; k <= bk + rb; k++)
                    for (int j = bj - rb; j <= bj + rb; j++)
                        for (int i = bi - rb; i <= bi + rb; i++)
                            if (i >= 0 && j >= 0 && k >= 0 && i < nb[0] && j < nb[1] && k < nb[2])
                                reg[((size_t)k * nb[1] + j) * nb[0] + i] = 1;
            }
    /* a brick whose every value is inside the range is all relevant (each
     * voxel meets the rule by itself): no block to work out */
    const int open = c->ramp > 0 || c->use_points;
    size_t n = 0;
    *nfull = 0;
    for (size_t b = 0; b < nbt; b++)
        if (reg[b]) {
            const float m = mm[2 * b], M = mm[2 * b + 1];
            full[n] = m <= M && (open ? m > lo && M < hi : m >= lo && M <= hi);
            *nfull += full[n];
            list[n++] = (uint32_t)b;
        }
    return n;
}

/* Bricks' masks by the dense rule on a block around them: the bricks and
 * seam + 1 voxels more on each side (clamped to the volume), enough for
 * every voxel of a brick to see what the whole-grid passes would show it. */
typedef struct sparse_job {
    const struct vs_volume *vol;
    const vs_classify *c;
    const uint8_t *lut8;
    int seam, nb[3];
    const uint32_t *list;
    const uint8_t *full; /* per listed brick: all its voxels are relevant     */
    const struct brick_run *runs;
    uint8_t *masks;     /* per listed brick, 64 rows of 8 bits: row dj | dk << 3 */
    uint32_t *counts;   /* per listed brick                                   */
    uint8_t *scratch;   /* per worker: five blocks of bit rows                */
    size_t per_worker;
} sparse_job;

/* OR each of the n bit rows with the rows within r of it along one axis
 * of the block: `count` rows `step` apart on that axis. */
static void dilate_rows(uint64_t *m, uint64_t *tmp, int n, int count, int step, int r)
{
    memcpy(tmp, m, (size_t)n * sizeof *m);
    for (int i = 0; i < n; i++) {
        const int c = i / step % count;
        uint64_t x = 0;
        for (int t = c - r < 0 ? -c : -r; t <= r && c + t < count; t++) x |= tmp[i + t * step];
        m[i] = x;
    }
}

/* OR-dilate a block of bit rows (w bits, bh rows a plane, bd planes) by r
 * voxels in a box, separably: shifts within the rows, then across rows in
 * y and in z; tmp holds a copy. */
static void dilate_bits(uint64_t *m, uint64_t *tmp, int w, int bh, int bd, int r, uint64_t all)
{
    const int n = bh * bd;
    for (int i = 0; i < n; i++) {
        uint64_t x = m[i];
        for (int s = 0; s < r && s < w; s++) x |= (x << 1 | x >> 1) & all;
        m[i] = x;
    }
    dilate_rows(m, tmp, n, bh, 1, r);
    dilate_rows(m, tmp, n, bd, bh, r);
}

/* A block row's classes as three words of bits (ri, rb, ra). */
#define CLASS_ROW(T, CLASS)                                                                                        \
    do {                                                                                                           \
        const T *p = (const T *)J->vol->data + row;                                                                \
        for (int i = 0; i < w; i++) {                                                                              \
            const uint8_t c = (CLASS);                                                                             \
            ri |= (uint64_t)((c & VS_REL_INSIDE) != 0) << i;                                                              \
            rb |= (uint64_t)((c & VS_REL_BELOW) != 0) << i;                                                               \
            ra |= (uint64_t)((c & VS_REL_ABOVE) != 0) << i;                                                               \
        }                                                                                                          \
    } while (0)

/* A run of listed bricks: consecutive along x, all mixed (a run of one
 * for an all-relevant brick), as wide as a 64-bit row of the block holds. */
typedef struct brick_run {
    uint32_t t0, n; /* first listed brick, how many */
} brick_run;

static void sparse_run(void *arg, int worker, int task)
{
    const sparse_job *J = arg;
    const int *d = J->vol->dims, *nb = J->nb;
    const brick_run run = J->runs[task];
    const int h = J->seam > 0 ? J->seam + 1 : 0;
    int o[3];
    brick_origin(J->list[run.t0], nb, o);
    const int len[3] = {VS_BRICK * (int)run.n, VS_BRICK, VS_BRICK};
    int lo[3], hi[3], e[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = o[a] - h > 0 ? o[a] - h : 0;
        hi[a] = o[a] + len[a] + h < d[a] ? o[a] + len[a] + h : d[a];
        e[a] = hi[a] - lo[a];
    }
    if (J->full[run.t0]) { /* every voxel of the brick inside the volume */
        uint32_t e3 = 1;
        for (int a = 0; a < 3; a++) e3 *= (uint32_t)(o[a] + VS_BRICK < d[a] ? VS_BRICK : d[a] - o[a]);
        J->counts[run.t0] = e3;
        return;
    }
    /* the block as rows of bits (a row is at most 64 voxels): one word per
     * row and class, dilated with shifts and ORs of rows */
    const int w = e[0], nr = e[1] * e[2];
    const uint64_t all = w == 64 ? ~(uint64_t)0 : ((uint64_t)1 << w) - 1;
    uint64_t *in = (uint64_t *)(void *)(J->scratch + (size_t)worker * J->per_worker), *be = in + nr, *ab = be + nr,
             *q = ab + nr, *tmp = q + nr;
    for (int k = lo[2], r = 0; k < hi[2]; k++)
        for (int j = lo[1]; j < hi[1]; j++, r++) {
            const size_t row = ((size_t)k * d[1] + j) * d[0] + lo[0];
            uint64_t ri = 0, rb = 0, ra = 0;
            switch (J->vol->type) {
            case VS_U8: CLASS_ROW(uint8_t, J->lut8[p[i]]); break;
            case VS_U16: CLASS_ROW(uint16_t, J->lut8[p[i]]); break;
            case VS_I16: CLASS_ROW(int16_t, J->lut8[p[i] + 32768]); break;
            default: CLASS_ROW(float, vs_relevant_class(J->c, p[i])); break;
            }
            in[r] = ri;
            be[r] = rb;
            ab[r] = ra;
        }
    if (J->seam > 0) {
        dilate_bits(in, tmp, w, e[1], e[2], 1, all);
        dilate_bits(be, tmp, w, e[1], e[2], 1, all);
        dilate_bits(ab, tmp, w, e[1], e[2], 1, all);
        for (int r = 0; r < nr; r++) q[r] = in[r] | (be[r] & ab[r]);
        dilate_bits(q, tmp, w, e[1], e[2], J->seam, all);
    } else {
        memcpy(q, in, (size_t)nr * sizeof *q);
    }
    /* each brick's rows: 8 bits each, row dj | dk << 3 */
    for (uint32_t l = 0; l < run.n; l++) {
        const int ox = o[0] + VS_BRICK * (int)l;
        uint8_t *out = J->masks + (size_t)(run.t0 + l) * VS_BRICK * VS_BRICK;
        uint32_t count = 0;
        memset(out, 0, VS_BRICK * VS_BRICK);
        const int ew = ox + VS_BRICK < d[0] ? VS_BRICK : d[0] - ox;
        const uint64_t keep = ((uint64_t)1 << ew) - 1;
        for (int k = o[2]; k < o[2] + VS_BRICK && k < d[2]; k++)
            for (int j = o[1]; j < o[1] + VS_BRICK && j < d[1]; j++) {
                const uint64_t bits = q[(k - lo[2]) * e[1] + (j - lo[1])] >> (ox - lo[0]) & keep;
                out[(k - o[2]) << VS_BRICK_BITS | (j - o[1])] = (uint8_t)bits;
                count += (uint32_t)__builtin_popcountll(bits);
            }
        J->counts[run.t0 + l] = count;
    }
}

/* The list from the listed bricks' masks (sparse_run), in their order:
 * slots from the counts, then the voxels filled in parallel, a chunk of
 * bricks a task. */
typedef struct compact_job {
    const sparse_job *S;
    const uint32_t *start; /* per listed brick: its first slot */
    vs_voxel *vox;
    size_t nreg;
} compact_job;

enum { COMPACT_CHUNK = 256 };

static void compact_chunk(void *arg, int worker, int task)
{
    (void)worker;
    const compact_job *C = arg;
    const sparse_job *S = C->S;
    const int *d = S->vol->dims, *nb = S->nb;
    const size_t t1 = (size_t)(task + 1) * COMPACT_CHUNK < C->nreg ? (size_t)(task + 1) * COMPACT_CHUNK : C->nreg;
    for (size_t t = (size_t)task * COMPACT_CHUNK; t < t1; t++) {
        if (!S->counts[t] || S->counts[t] == VS_BRICK_VOXELS) continue; /* none, or the shared block */
        vs_voxel *out = C->vox + C->start[t];
        if (S->full[t]) {
            int o[3], e[3];
            brick_origin(S->list[t], nb, o);
            for (int a = 0; a < 3; a++) e[a] = o[a] + VS_BRICK < d[a] ? VS_BRICK : d[a] - o[a];
            for (int k = 0; k < e[2]; k++)
                for (int j = 0; j < e[1]; j++)
                    for (int i = 0; i < e[0]; i++)
                        *out++ = (vs_voxel)(k << (2 * VS_BRICK_BITS) | j << VS_BRICK_BITS | i);
        } else {
            const uint8_t *m = S->masks + t * VS_BRICK * VS_BRICK;
            for (int r = 0; r < VS_BRICK * VS_BRICK; r++)
                for (int i = 0; i < VS_BRICK; i++)
                    if (m[r] >> i & 1) *out++ = (vs_voxel)(r << VS_BRICK_BITS | i);
        }
    }
}

static vs_status compact_sparse(vs_context *ctx, struct vs_pool *pool, const sparse_job *S, size_t nreg,
                                vs_relevant_cache *rc, vs_relevant_cache *old)
{
    const int *d = S->vol->dims, *nb = S->nb;
    size_t count = 0, stored = 0, nonempty = 0;
    int whole = 0;
    for (size_t t = 0; t < nreg; t++) {
        count += S->counts[t];
        nonempty += S->counts[t] != 0;
        if (S->counts[t] == VS_BRICK_VOXELS)
            whole = 1;
        else
            stored += S->counts[t];
    }
    stored += whole ? VS_BRICK_VOXELS : 0;
    vs_voxel *vox;
    vs_brick *bricks;
    const vs_status st = vs_relevant_lists(ctx, old, stored, nonempty, &vox, &bricks);
    if (st != VS_OK) return st;
    uint32_t *start = malloc((nreg ? nreg : 1) * sizeof *start);
    if (!start) {
        free(vox);
        free(bricks);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "relevant voxels: cannot hold %zu voxels", count);
    }
    uint32_t run = whole ? VS_BRICK_VOXELS : 0;
    size_t nbk = 0;
    for (size_t t = 0; t < nreg; t++) {
        const int shared = S->counts[t] == VS_BRICK_VOXELS;
        start[t] = shared ? 0 : run;
        if (!S->counts[t]) continue;
        int o[3];
        brick_origin(S->list[t], nb, o);
        bricks[nbk++] = vs_relevant_brick(d, o[0] / VS_BRICK, o[1] / VS_BRICK, o[2] / VS_BRICK, start[t], S->counts[t]);
        if (!shared) run += S->counts[t];
    }
    if (whole) vs_relevant_whole_block(vox);
    compact_job C = {S, start, vox, nreg};
    vs_pool_run(pool, (int)((nreg + COMPACT_CHUNK - 1) / COMPACT_CHUNK), compact_chunk, &C);
    free(start);
    rc->nbricks = nbk;
    rc->bricks = bricks;
    rc->count = count;
    rc->stored = stored;
    rc->voxels = vox;
    rc->sparse = 1;
    return VS_OK;
}

vs_status vs_relevant_build_bricks(vs_context *ctx, struct vs_pool *pool, const struct vs_volume *vol,
                                   const vs_classify *c, const uint8_t *lut, int seam, int force, vs_relevant_cache *rc,
                                   vs_relevant_cache *old)
{
    const int *d = vol->dims;
    const size_t n = (size_t)d[0] * d[1] * d[2];
    int nb[3];
    const size_t nbt = vs_relevant_grid(d, nb);
    uint8_t *flags = malloc(3 * nbt);
    uint32_t *list = malloc(nbt * sizeof *list);
    if (!flags || !list) {
        free(flags);
        free(list);
        return VS_ERR_UNSUPPORTED;
    }
    size_t nfull;
    const size_t nreg = region_bricks(rc->minmax, nb, c, seam, flags, flags + nbt, list, flags + 2 * nbt, &nfull);
    const int h = seam > 0 ? seam + 1 : 0;
    const uint8_t *full = flags + 2 * nbt;
    /* runs of mixed bricks along x, each worked out on one block */
    const uint32_t most = (uint32_t)((64 - 2 * h) / VS_BRICK);
    brick_run *runs = malloc((nreg ? nreg : 1) * sizeof *runs);
    size_t nruns = 0, cost = 0;
    for (size_t t = 0; runs && t < nreg;) {
        uint32_t len = 1;
        if (!full[t])
            while (t + len < nreg && len < most && !full[t + len] && list[t + len] == list[t] + len &&
                   list[t] / (uint32_t)nb[0] == list[t + len] / (uint32_t)nb[0])
                len++;
        runs[nruns++] = (brick_run){(uint32_t)t, len};
        if (!full[t]) cost += (size_t)(VS_BRICK * len + 2 * h) * (VS_BRICK + 2 * h) * (VS_BRICK + 2 * h);
        t += len;
    }
    /* the blocks against about two passes over the grid */
    if (!runs || (!force && cost > n / 2)) {
        free(runs);
        free(flags);
        free(list);
        return VS_ERR_UNSUPPORTED;
    }
    const int nw = pool ? vs_pool_threads(pool) : 1;
    const size_t rows = (size_t)(VS_BRICK + 2 * h) * (VS_BRICK + 2 * h);
    sparse_job J = {vol, c, lut, seam, {nb[0], nb[1], nb[2]}, list, full, runs, NULL, NULL, NULL,
                    5 * rows * sizeof(uint64_t)};
    J.masks = malloc((nreg ? nreg : 1) * VS_BRICK * VS_BRICK);
    J.counts = malloc((nreg ? nreg : 1) * sizeof *J.counts);
    J.scratch = malloc(J.per_worker * (size_t)nw);
    vs_status st = VS_ERR_UNSUPPORTED;
    if (J.masks && J.counts && J.scratch) {
        if (nreg > (size_t)INT32_MAX) abort(); /* nbt < 2^32 / 512 bricks */
        vs_pool_run(pool, (int)nruns, sparse_run, &J);
        st = compact_sparse(ctx, pool, &J, nreg, rc, old);
    }
    free(J.masks);
    free(J.counts);
    free(J.scratch);
    free(runs);
    free(list);
    free(flags);
    return st;
}
