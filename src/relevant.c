/* Building the relevant-voxel list: on the whole grid, an in-range mask
 * dilated by the seam width with separable shifted ORs, then compacted
 * in k, j, i order; for large volumes brick by brick when few bricks are
 * reached (relevant_bricks.c); the cache around both. */
#include "timing.h"
#include "context.h"
#include "relevant.h"
#include "relevant_bricks.h"
#include "relevant_class.h"
#include "pool.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void vs_relevant_cache_free(vs_relevant_cache *rc)
{
    if (!rc) return;
    free(rc->voxels);
    free(rc->bricks);
    free(rc->scratch);
    free(rc->minmax);
    free(rc);
}

/* OR-dilate a byte mask of flag bits by r voxels in a box, separably and
 * in three passes over memory between the mask and a second buffer as
 * large: each plane along x into the other buffer's plane and along y
 * back into its own (one task a plane), then each plane of the other
 * buffer as the OR of the mask's planes z - r .. z + r, which is where
 * the result ends.  Each pass ORs shifted copies of whole planes, which
 * the compiler vectorises; the x pass treats a plane as one long row and
 * then redoes the r voxels at each end of its rows, which a long row
 * would have mixed with the neighbouring row's. */
static void or_into(uint8_t *dst, const uint8_t *src, size_t n)
{
    for (size_t i = 0; i < n; i++) dst[i] |= src[i];
}

typedef struct dilate_job {
    uint8_t *m, *tmp;
    const int *d;
    int r;
} dilate_job;

static void dilate_xy(void *arg, int worker, int z)
{
    (void)worker;
    const dilate_job *J = arg;
    const int *d = J->d, r = J->r;
    const size_t row = (size_t)d[0], plane = row * d[1];
    uint8_t *p = J->m + (size_t)z * plane, *w = J->tmp + (size_t)z * plane;
    /* x: p into w */
    memcpy(w, p, plane);
    for (size_t sft = 1; sft <= (size_t)r && sft < plane; sft++) {
        or_into(w + sft, p, plane - sft);
        or_into(w, p + sft, plane - sft);
    }
    const int e = r < d[0] ? r : d[0];
    for (size_t o = 0; o < plane; o += row)
        for (int q = 0; q < 2 * e; q++) {
            const int i = q < e ? q : d[0] - 2 * e + q; /* the first and last e of the row */
            if (q >= e && i < e) continue;              /* a row shorter than 2 e: done above */
            uint8_t v = 0;
            for (int x = i - r < 0 ? 0 : i - r; x <= i + r && x < d[0]; x++) v |= p[o + (size_t)x];
            w[o + (size_t)i] = v;
        }
    /* y: w back into p */
    memcpy(p, w, plane);
    for (size_t sft = 1; sft <= (size_t)r && sft < (size_t)d[1]; sft++) {
        or_into(p + sft * row, w, plane - sft * row);
        or_into(p, w + sft * row, plane - sft * row);
    }
}

static void dilate_z(void *arg, int worker, int z)
{
    (void)worker;
    const dilate_job *J = arg;
    const size_t plane = (size_t)J->d[0] * J->d[1];
    uint8_t *t = J->tmp + (size_t)z * plane;
    memcpy(t, J->m + (size_t)z * plane, plane);
    for (int sft = 1; sft <= J->r; sft++) {
        if (z - sft >= 0) or_into(t, J->m + (size_t)(z - sft) * plane, plane);
        if (z + sft < J->d[2]) or_into(t, J->m + (size_t)(z + sft) * plane, plane);
    }
}

/* *m dilated; the result ends in the other buffer, so the two swap */
static void dilate(struct vs_pool *pool, uint8_t **m, uint8_t **tmp, const int d[3], int r)
{
    if (r <= 0) return;
    dilate_job J = {*m, *tmp, d, r};
    vs_pool_run(pool, d[2], dilate_xy, &J);
    vs_pool_run(pool, d[2], dilate_z, &J);
    uint8_t *t = *m;
    *m = *tmp;
    *tmp = t;
}

/* The per-voxel passes of a rebuild, on the pool: classification and the
 * in-range test in chunks of planes; counting and filling per slab of
 * bricks (VS_BRICK planes), whose bricks no other slab touches, so the list
 * is the same for any thread count. */
typedef struct build_job {
    const struct vs_volume *vol;
    const int *d;
    const uint8_t *lut8;   /* class of each u8 / u16 / i16 value (NULL: f32) */
    const vs_classify *c;
    uint8_t *mask;
    int nb[3];
    uint32_t *pos;         /* per brick: count, then next slot               */
    size_t *slab_count;    /* voxels per slab of bricks                      */
    vs_voxel *vox;
    int combine;           /* pass 2 of the seam rule, else in-range only    */
} build_job;

static void classify_planes(void *arg, int worker, int z)
{
    (void)worker;
    const build_job *J = arg;
    const size_t plane = (size_t)J->d[0] * J->d[1], i0 = (size_t)z * plane;
    uint8_t *mask = J->mask + i0;
    switch (J->vol->type) {
    case VS_U8: {
        const uint8_t *p = (const uint8_t *)J->vol->data + i0;
        for (size_t i = 0; i < plane; i++) mask[i] = J->lut8[p[i]];
    } break;
    case VS_U16: {
        const uint16_t *p = (const uint16_t *)J->vol->data + i0;
        for (size_t i = 0; i < plane; i++) mask[i] = J->lut8[p[i]];
    } break;
    case VS_I16: {
        const int16_t *p = (const int16_t *)J->vol->data + i0;
        for (size_t i = 0; i < plane; i++) mask[i] = J->lut8[p[i] + 32768];
    } break;
    default: {
        const float *p = (const float *)J->vol->data + i0;
        for (size_t i = 0; i < plane; i++) mask[i] = vs_relevant_class(J->c, p[i]);
    } break;
    }
}

static void finish_planes(void *arg, int worker, int z)
{
    (void)worker;
    const build_job *J = arg;
    const size_t plane = (size_t)J->d[0] * J->d[1];
    uint8_t *mask = J->mask + (size_t)z * plane;
    if (J->combine)
        for (size_t i = 0; i < plane; i++)
            mask[i] = (mask[i] & VS_REL_INSIDE) || (mask[i] & (VS_REL_BELOW | VS_REL_ABOVE)) == (VS_REL_BELOW | VS_REL_ABOVE);
    else
        for (size_t i = 0; i < plane; i++) mask[i] = (mask[i] & VS_REL_INSIDE) != 0;
}

/* Counting and filling take brick bi's part of a mask row of d0 bytes,
 * each 0 or 1 (finish_planes and the dilations keep them so), as one
 * word: byte l holds voxel 8 bi + l.  The last brick of a row may be
 * short; its bytes past the volume read as 0. */
static inline uint64_t brick_row(const uint8_t *row, int d0, int bi)
{
    const uint8_t *m = row + bi * VS_BRICK;
    const int n = d0 - bi * VS_BRICK < VS_BRICK ? d0 - bi * VS_BRICK : VS_BRICK;
    uint64_t x = 0;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    if (n == VS_BRICK) {
        memcpy(&x, m, sizeof x);
        return x;
    }
#endif
    for (int l = 0; l < n; l++) x |= (uint64_t)m[l] << (8 * l);
    return x;
}
_Static_assert(VS_BRICK == 8, "brick_row packs a brick's row into one 64-bit word");

/* bytes of 0 or 1: their sum, and bit l set where byte l is 1 (each
 * multiply gathers the bytes into the top one) */
static inline unsigned row_count(uint64_t x) { return (unsigned)((x * 0x0101010101010101ULL) >> 56); }
static inline unsigned row_bits(uint64_t x) { return (unsigned)((x * 0x0102040810204080ULL) >> 56); }

static void count_slab(void *arg, int worker, int bk)
{
    (void)worker;
    const build_job *J = arg;
    const int *d = J->d, *nb = J->nb;
    const int k1 = (bk + 1) * VS_BRICK < d[2] ? (bk + 1) * VS_BRICK : d[2];
    size_t count = 0;
    for (int k = bk * VS_BRICK; k < k1; k++)
        for (int j = 0; j < d[1]; j++) {
            const uint8_t *m = J->mask + ((size_t)k * d[1] + j) * d[0];
            uint32_t *pb = J->pos + ((size_t)bk * nb[1] + j / VS_BRICK) * nb[0];
            for (int bi = 0; bi < nb[0]; bi++) {
                const unsigned c = row_count(brick_row(m, d[0], bi));
                pb[bi] += c;
                count += c;
            }
        }
    J->slab_count[bk] = count;
}

/* pos[] of a brick with all its voxels relevant: fill_slab skips it */
#define WHOLE_BRICK UINT32_MAX

static void fill_slab(void *arg, int worker, int bk)
{
    (void)worker;
    const build_job *J = arg;
    const int *d = J->d, *nb = J->nb;
    const int k1 = (bk + 1) * VS_BRICK < d[2] ? (bk + 1) * VS_BRICK : d[2];
    for (int k = bk * VS_BRICK; k < k1; k++)
        for (int j = 0; j < d[1]; j++) {
            const uint8_t *m = J->mask + ((size_t)k * d[1] + j) * d[0];
            uint32_t *pb = J->pos + ((size_t)bk * nb[1] + j / VS_BRICK) * nb[0];
            const int jk = (j & (VS_BRICK - 1)) << VS_BRICK_BITS | (k & (VS_BRICK - 1)) << (2 * VS_BRICK_BITS);
            for (int bi = 0; bi < nb[0]; bi++) {
                if (pb[bi] == WHOLE_BRICK) continue; /* the shared block */
                uint32_t at = pb[bi];
                for (unsigned bits = row_bits(brick_row(m, d[0], bi)); bits; bits &= bits - 1)
                    J->vox[at++] = (vs_voxel)(jk | __builtin_ctz(bits));
                pb[bi] = at;
            }
        }
}

/* The whole grid at once: class mask, dilations, count and fill per slab
 * of bricks. */
static vs_status build_dense(vs_context *ctx, struct vs_pool *pool, const struct vs_volume *vol,
                             const vs_classify *c, const uint8_t *lut, int seam, int all_visible,
                             vs_relevant_cache *rc, vs_relevant_cache *old)
{
    const int *d = vol->dims;
    size_t n = (size_t)d[0] * d[1] * d[2];
    void *none = NULL;
    /* the mask and the dilations' second buffer (they take turns) */
    uint8_t *const scratch = vs_relevant_take(old ? (void **)&old->scratch : &none, 2 * n);
    if (!scratch) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "relevant voxels: out of memory");
    uint8_t *mask = scratch, *line = scratch + n;
    build_job J = {vol, d, lut, c, mask, {0, 0, 0}, NULL, NULL, NULL, 0};
    if (all_visible) {
        /* Empty space is visible (opacity at what the volume reads
         * outside, vs_volume_base, is > 0): a voxel left out would read as
         * that and become opaque, so nothing may be left out. */
        memset(mask, 1, n);
    } else if (seam > 0) {
        vs_pool_run(pool, d[2], classify_planes, &J);
        /* Post-classified pipelines: the iso-range is met between voxels
         * wherever a voxel's 3x3x3 neighbourhood holds a value inside the
         * range or values on both sides of it (a thin ramp can fall between
         * grid points).  Those voxels, dilated by the seam, are what the
         * kernel needs to reconstruct every point where opacity is > 0. */
        dilate(pool, &mask, &line, d, 1);
        J.mask = mask;
        J.combine = 1;
        vs_pool_run(pool, d[2], finish_planes, &J);
        dilate(pool, &mask, &line, d, seam);
        J.mask = mask;
    } else {
        vs_pool_run(pool, d[2], classify_planes, &J);
        vs_pool_run(pool, d[2], finish_planes, &J);
    }
    /* Compact brick by brick: count per brick, prefix sums, fill (the fill
     * walks the grid in k, j, i order, so each brick is in that order too). */
    int nb[3];
    const size_t nbt = vs_relevant_grid(d, nb);
    uint32_t *pos = calloc(nbt + 1, sizeof *pos);
    size_t *slab_count = calloc((size_t)nb[2], sizeof *slab_count);
    if (!pos || !slab_count) {
        free(scratch);
        free(pos);
        free(slab_count);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "relevant voxels: out of memory");
    }
    memcpy(J.nb, nb, sizeof J.nb);
    J.pos = pos;
    J.slab_count = slab_count;
    vs_pool_run(pool, nb[2], count_slab, &J);
    size_t count = 0, stored = 0, nonempty = 0;
    int whole = 0;
    for (int bk = 0; bk < nb[2]; bk++) count += slab_count[bk];
    free(slab_count);
    for (size_t b = 0; b < nbt; b++) {
        nonempty += pos[b] != 0;
        if (pos[b] == VS_BRICK_VOXELS)
            whole = 1;
        else
            stored += pos[b];
    }
    stored += whole ? VS_BRICK_VOXELS : 0;
    vs_voxel *vox;
    vs_brick *bricks;
    const vs_status st = vs_relevant_lists(ctx, old, stored, nonempty, &vox, &bricks);
    if (st != VS_OK) {
        free(scratch);
        free(pos);
        return st;
    }
    /* prefix sums: pos[b] becomes the first slot of brick b */
    uint32_t run = whole ? VS_BRICK_VOXELS : 0;
    size_t nbk = 0;
    for (int bk = 0; bk < nb[2]; bk++)
        for (int bj = 0; bj < nb[1]; bj++)
            for (int bi = 0; bi < nb[0]; bi++) {
                size_t b = ((size_t)bk * nb[1] + bj) * nb[0] + bi;
                uint32_t nvox = pos[b];
                if (nvox == VS_BRICK_VOXELS) {
                    pos[b] = WHOLE_BRICK;
                    bricks[nbk++] = vs_relevant_brick(d, bi, bj, bk, 0, nvox);
                    continue;
                }
                pos[b] = run;
                if (nvox) {
                    bricks[nbk++] = vs_relevant_brick(d, bi, bj, bk, run, nvox);
                }
                run += nvox;
            }
    if (whole) vs_relevant_whole_block(vox);
    J.vox = vox;
    vs_pool_run(pool, nb[2], fill_slab, &J);
    free(pos);
    rc->nbricks = nbk;
    rc->bricks = bricks;
    /* kept for the next rebuild (an iso change then pays no page faults),
     * unless large: a 2 G-voxel volume would hold 4 GB of it for good */
    if (2 * n <= VS_RELEVANT_KEEP_SCRATCH) {
        rc->scratch = scratch;
    } else {
        free(scratch);
        rc->scratch = NULL;
    }
    rc->count = count;
    rc->stored = stored;
    rc->voxels = vox;
    return VS_OK;
}

static vs_status build(vs_context *ctx, struct vs_pool *pool, const struct vs_volume *vol, const vs_classify *c,
                       int seam, int mode, vs_relevant_cache *rc, vs_relevant_cache *old)
{
    const int *d = vol->dims;
    size_t n = (size_t)d[0] * d[1] * d[2];
    /* integer volumes: classify each possible value once */
    uint8_t *lut = NULL;
    if (vol->type != VS_F32) {
        const int nv = vol->type == VS_U8 ? 256 : 65536, off = vol->type == VS_I16 ? 32768 : 0;
        lut = malloc((size_t)nv);
        if (!lut) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "relevant voxels: out of memory");
        for (int v = 0; v < nv; v++) lut[v] = vs_relevant_class(c, v - off);
    }
    /* the min-max per brick: the last list's if built from the same data,
     * else made now for a large volume (a failed allocation: dense) */
    const int all_visible = vs_relevant_in_range(c, vs_volume_base(vol)) && seam > 0;
    if (old && old->minmax && old->minmax_serial == vol->data_serial && !memcmp(old->dims, d, sizeof old->dims)) {
        rc->minmax = old->minmax;
        old->minmax = NULL;
    } else if (mode == VS_RELEVANT_SPARSE || (mode == VS_RELEVANT_AUTO && n >= VS_RELEVANT_SPARSE_VOXELS)) {
        rc->minmax = vs_relevant_minmax(pool, vol);
    }
    rc->minmax_serial = vol->data_serial;
    if (rc->minmax && !all_visible && mode != VS_RELEVANT_DENSE) {
        vs_status st = vs_relevant_build_bricks(ctx, pool, vol, c, lut, seam, mode == VS_RELEVANT_SPARSE, rc, old);
        if (st != VS_ERR_UNSUPPORTED) {
            free(lut);
            return st;
        }
    }
    vs_status st = build_dense(ctx, pool, vol, c, lut, seam, all_visible, rc, old);
    free(lut);
    return st;
}

vs_status vs_relevant_get(vs_context *ctx, vs_relevant_cache **slot, struct vs_pool *pool,
                          const struct vs_volume *vol, const vs_classify *c, int seam, const vs_relevant_cache **out,
                          int *rebuilt)
{
    return vs_relevant_get_mode(ctx, slot, pool, vol, c, seam, VS_RELEVANT_AUTO, out, rebuilt);
}

vs_status vs_relevant_get_mode(vs_context *ctx, vs_relevant_cache **slot, struct vs_pool *pool,
                               const struct vs_volume *vol, const vs_classify *c, int seam, int mode,
                               const vs_relevant_cache **out, int *rebuilt)
{
    /* A voxel left out reads as the value outside the volume, which lies
     * below every range it is not inside.  Left out above a range's upper
     * end, bright voxels would pull the reconstruction down through the
     * range and draw a false surface inside them (a soft-tissue band's
     * shell around every bone), so the post-classified pipelines keep
     * them as if the range were open upwards; the list then serves every
     * upper end. */
    vs_classify open = *c;
    if (seam > 0 && !(vs_volume_base(vol) > c->alpha_lo)) open.alpha_hi = INFINITY;
    c = &open;
    vs_relevant_cache *rc = *slot;
    *rebuilt = 0;
    if (rc && rc->vol == vol && rc->serial == vol->serial && !memcmp(rc->dims, vol->dims, sizeof rc->dims) && rc->vmin == vol->vmin &&
        rc->vmax == vol->vmax && rc->alpha_lo == c->alpha_lo && rc->alpha_hi == c->alpha_hi &&
        rc->seam == seam) {
        *out = rc;
        return VS_OK;
    }
    vs_relevant_cache *old = rc;
    *slot = NULL;
    rc = calloc(1, sizeof *rc);
    if (!rc) {
        vs_relevant_cache_free(old);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "relevant voxels: out of memory");
    }
    double t0 = vs_now_ms();
    vs_status st = build(ctx, pool, vol, c, seam, mode, rc, old);
    vs_relevant_cache_free(old); /* what build did not take over */
    if (st != VS_OK) {
        vs_relevant_cache_free(rc);
        return st;
    }
    rc->vol = vol;
    rc->serial = vol->serial;
    memcpy(rc->dims, vol->dims, sizeof rc->dims);
    rc->vmin = vol->vmin;
    rc->vmax = vol->vmax;
    rc->alpha_lo = c->alpha_lo;
    rc->alpha_hi = c->alpha_hi;
    rc->seam = seam;
    rc->build_ms = vs_now_ms() - t0;
    *slot = rc;
    *out = rc;
    *rebuilt = 1;
    return VS_OK;
}

int vs_classify_faces(const vs_classify *c, double base, double vmax)
{
    return vs_relevant_in_range(c, base) || (base < c->alpha_lo && vmax >= c->alpha_hi);
}
