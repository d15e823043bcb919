/* The relevant-voxel list built brick by brick (a min-max per brick, then a
 * block around each brick the classification can reach) is the list the
 * whole-grid passes build, voxel for voxel: u8, i16 (negative, CT-like)
 * and f32 volumes with NaN and infinite voxels, sizes that are not
 * multiples of the brick, iso-ranges with ramps and hard thresholds,
 * transfer functions with gaps, nothing visible, seams 0 to 9; lone
 * voxels and steps at brick borders, where the brick rule is tight (seams
 * to 16); and a rebuild for a new classification reuses the min-max. */
#include "classify.h"
#include "context.h"
#include "pool.h"
#include "relevant.h"
#include "testutil.h"

#include <stdint.h>

static vs_context *ctx;

/* Two overlapping balls, a one-voxel shell and a speckle of noise. */
static vs_volume *make_volume(vs_type t, const int d[3], double scale, double offset)
{
    vs_volume *v = NULL;
    if (vs_volume_create(ctx, t, d, NULL, &v) != VS_OK) return NULL;
    unsigned r = 7;
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++) {
                const double r1 = sqrt(pow(i - 0.4 * d[0], 2) + pow(j - 0.5 * d[1], 2) + pow(k - 0.5 * d[2], 2));
                const double r2 = sqrt(pow(i - 0.7 * d[0], 2) + pow(j - 0.3 * d[1], 2) + pow(k - 0.4 * d[2], 2));
                double x = fmax(0.0, 200.0 - 9.0 * r1) + (r2 < 9.0 ? 60.0 : 0.0);
                if (fabs(r2 - 14.0) < 0.5) x = 120.0; /* a thin shell */
                r = r * 1103515245u + 12345u;
                if ((r >> 16) % 97 == 0) x += (double)((r >> 8) % 40);
                const double y = scale * x + offset;
                const size_t at = ((size_t)k * d[1] + j) * d[0] + i;
                switch (t) {
                case VS_U8: ((uint8_t *)vs_volume_data(v))[at] = (uint8_t)(y > 255 ? 255 : y); break;
                case VS_I16: ((int16_t *)vs_volume_data(v))[at] = (int16_t)y; break;
                default: ((float *)vs_volume_data(v))[at] = (float)y; break;
                }
            }
    if (t == VS_F32) {
        float *f = vs_volume_data(v);
        f[0] = NAN;
        f[(size_t)d[0] * d[1] * d[2] / 2 + 3] = NAN;
        f[(size_t)d[0] * d[1] * 3 + 17] = INFINITY;
        f[(size_t)d[0] * 40 + 5] = -INFINITY;
        f[((size_t)22 * d[1] + 26) * d[0] + 26] = NAN; /* in a brick all inside the iso-range otherwise */
    }
    vs_volume_update_range(v);
    return v;
}

static int same_list(const vs_relevant_cache *a, const vs_relevant_cache *b)
{
    if (a->count != b->count || a->stored != b->stored || a->nbricks != b->nbricks) return 0;
    if (memcmp(a->voxels, b->voxels, a->stored * sizeof *a->voxels)) return 0;
    return !memcmp(a->bricks, b->bricks, a->nbricks * sizeof *a->bricks);
}

static int cases, sparse_cases, shared_bricks;

/* The list's shape: each brick's voxels in k, j, i order inside its box;
 * a brick with all 512 voxels relevant points at the block of all
 * positions at slot 0 (stored once), every other brick at its own slots
 * after it; the bricks' counts add up to the count. */
static int well_formed(const vs_relevant_cache *r)
{
    size_t sum = 0;
    int whole = 0;
    for (size_t b = 0; b < r->nbricks; b++) whole |= r->bricks[b].count == 512;
    if (whole)
        for (int i = 0; i < 512; i++)
            if (r->voxels[i] != i) return 0;
    for (size_t b = 0; b < r->nbricks; b++) {
        const vs_brick *br = &r->bricks[b];
        sum += br->count;
        if (br->count == 0 || br->count > 512) return 0;
        if (br->count == 512) {
            if (br->start != 0) return 0;
            shared_bricks++;
            continue;
        }
        if ((whole && br->start < 512) || (size_t)br->start + br->count > r->stored) return 0;
        for (uint32_t q = 0; q < br->count; q++) {
            const vs_voxel v = r->voxels[br->start + q];
            if (q && v <= r->voxels[br->start + q - 1]) return 0;
            if (br->i0 + VS_VOXEL_DI(v) > br->i1 || br->j0 + VS_VOXEL_DJ(v) > br->j1 || br->k0 + VS_VOXEL_DK(v) > br->k1)
                return 0;
        }
    }
    return sum == r->count && r->stored <= r->count + (whole ? 512 : 0);
}

static void compare(struct vs_pool *pool, const vs_volume *v, const vs_settings *s, int seam, const char *what)
{
    vs_classify *c = malloc(sizeof *c);
    if (!c || vs_classify_setup(ctx, v, s, c) != VS_OK) {
        CHECK(0, "%s: classification: %s", what, vs_last_error(ctx));
        free(c);
        return;
    }
    vs_relevant_cache *dense = NULL, *sparse = NULL;
    const vs_relevant_cache *a = NULL, *b = NULL;
    int rebuilt;
    CHECK(vs_relevant_get_mode(ctx, &dense, pool, v, c, seam, VS_RELEVANT_DENSE, &a, &rebuilt) == VS_OK && a,
          "%s: dense", what);
    CHECK(vs_relevant_get_mode(ctx, &sparse, pool, v, c, seam, VS_RELEVANT_SPARSE, &b, &rebuilt) == VS_OK && b,
          "%s: sparse", what);
    if (a && b) {
        CHECK(!a->sparse, "%s: the dense list was built sparsely", what);
        CHECK(well_formed(a) && well_formed(b), "%s, seam %d: a list is malformed", what, seam);
        CHECK(same_list(a, b), "%s, seam %d: dense %zu voxels in %zu bricks, brick by brick %zu in %zu", what, seam,
              a->count, a->nbricks, b->count, b->nbricks);
        cases++;
        sparse_cases += b->sparse;
    }
    vs_relevant_cache_free(dense);
    vs_relevant_cache_free(sparse);
    free(c);
}

static void classifications(struct vs_pool *pool, const vs_volume *v, double scale, double offset, const char *name)
{
    static const int seams[] = {0, 1, 2, 3, 9};
    const vs_tf_point gaps[] = {{(float)(offset + 30 * scale), 1, 1, 1, 0.0f},
                                {(float)(offset + 40 * scale), 1, 1, 1, 0.3f},
                                {(float)(offset + 45 * scale), 1, 1, 1, 0.0f},
                                {(float)(offset + 150 * scale), 1, 1, 1, 0.0f},
                                {(float)(offset + 160 * scale), 1, 1, 1, 1.0f}};
    for (int si = 0; si < 5; si++) {
        char what[160];
        vs_settings s;
        vs_settings_init(&s);
        s.has_iso = 1;
        s.iso_lo = offset + 100 * scale; /* ramp */
        s.iso_hi = INFINITY;
        s.ramp = 10 * scale;
        snprintf(what, sizeof what, "%s iso ramp", name);
        compare(pool, v, &s, seams[si], what);
        s.iso_lo = offset + 118 * scale; /* hard threshold band: the thin shell */
        s.iso_hi = offset + 122 * scale;
        s.ramp = 0;
        snprintf(what, sizeof what, "%s hard band", name);
        compare(pool, v, &s, seams[si], what);
        s.iso_lo = offset + 1000 * scale; /* nothing reaches it */
        s.iso_hi = INFINITY;
        s.ramp = scale;
        snprintf(what, sizeof what, "%s nothing", name);
        compare(pool, v, &s, seams[si], what);
        vs_settings_init(&s);
        s.tf = gaps;
        s.tf_count = 5;
        snprintf(what, sizeof what, "%s transfer function", name);
        compare(pool, v, &s, seams[si], what);
    }
}

/* Where the brick rule is tight: a lone opaque voxel at the first voxel
 * of a brick (what a seam reaches from it spans two more bricks at seam 8),
 * and steps from 0 to 255 on a brick border and inside a brick, under a
 * band that no voxel value meets (only the neighbourhood rule's "values on
 * both sides" makes them relevant, across the border). */
static void test_borders(struct vs_pool *pool)
{
    const int d[3] = {48, 40, 36};
    static const int seams[] = {1, 2, 7, 8, 9, 15, 16};
    for (int shape = 0; shape < 4; shape++) {
        vs_volume *v = NULL;
        if (vs_volume_create(ctx, VS_U8, d, NULL, &v) != VS_OK) continue;
        uint8_t *p = vs_volume_data(v);
        for (int k = 0; k < d[2]; k++)
            for (int j = 0; j < d[1]; j++)
                for (int i = 0; i < d[0]; i++) {
                    const size_t at = ((size_t)k * d[1] + j) * d[0] + i;
                    p[at] = shape == 0   ? 0
                            : shape == 1 ? (i >= 16 ? 255 : 0)
                            : shape == 2 ? (i >= 23 && j >= 9 ? 255 : 0)
                                         : (i < 20 ? 90 : 200); /* 90: the open ramp's end, not inside */
                }
        if (shape == 0) {
            p[((size_t)16 * d[1] + 16) * d[0] + 16] = 255;
            p[((size_t)8 * d[1] + 23) * d[0] + 31] = 255;
        }
        vs_volume_update_range(v);
        vs_settings s;
        vs_settings_init(&s);
        s.has_iso = 1;
        s.iso_lo = shape == 0 ? 200 : 100;
        s.iso_hi = shape == 0 || shape == 3 ? INFINITY : 120;
        s.ramp = shape == 3 ? 10 : 0;
        for (int si = 0; si < 7; si++) {
            const char *names[] = {"lone voxels", "step on a brick border", "steps inside bricks",
                                   "a plateau at the ramp's end"};
            if (shape == 3 && si == 0) compare(pool, v, &s, 0, names[shape]);
            compare(pool, v, &s, seams[si], names[shape]);
        }
        vs_volume_release(v);
    }
}

/* A rebuild for another iso-range on the same data reuses the min-max;
 * new data (vs_volume_update_range) makes a new one. */
static void test_reuse(struct vs_pool *pool)
{
    const int d[3] = {40, 33, 27};
    vs_volume *v = make_volume(VS_U8, d, 1.0, 0.0);
    if (!v) return;
    vs_classify *c = malloc(sizeof *c);
    vs_settings s;
    vs_settings_init(&s);
    s.has_iso = 1;
    s.iso_lo = 100;
    s.iso_hi = INFINITY;
    s.ramp = 10;
    vs_relevant_cache *slot = NULL;
    const vs_relevant_cache *r = NULL;
    int rebuilt;
    if (c && vs_classify_setup(ctx, v, &s, c) == VS_OK &&
        vs_relevant_get_mode(ctx, &slot, pool, v, c, 2, VS_RELEVANT_SPARSE, &r, &rebuilt) == VS_OK) {
        const float *mm = r->minmax;
        CHECK(mm && r->sparse, "min-max built");
        s.iso_lo = 60;
        vs_classify_setup(ctx, v, &s, c);
        vs_relevant_get_mode(ctx, &slot, pool, v, c, 2, VS_RELEVANT_SPARSE, &r, &rebuilt);
        CHECK(rebuilt && r->minmax == mm, "an iso change rebuilt the min-max");
        vs_volume_update_range(v);
        vs_relevant_get_mode(ctx, &slot, pool, v, c, 2, VS_RELEVANT_SPARSE, &r, &rebuilt);
        CHECK(rebuilt && r->minmax_serial != 0, "new data: rebuilt");
    } else {
        CHECK(0, "reuse set-up: %s", vs_last_error(ctx));
    }
    vs_relevant_cache_free(slot);
    free(c);
    vs_volume_release(v);
}

int main(void)
{
    if (vs_context_create(&ctx) != VS_OK) return 1;
    struct vs_pool *pool = vs_pool_create(2, 0);
    const int d[3] = {61, 50, 43}; /* no side a multiple of 8 */
    struct {
        vs_type t;
        double scale, offset;
        const char *name;
    } vols[] = {{VS_U8, 1.0, 0.0, "u8"}, {VS_I16, 10.0, -1024.0, "i16 CT-like"}, {VS_F32, 0.01, -0.5, "f32"}};
    for (int k = 0; k < 3; k++) {
        vs_volume *v = make_volume(vols[k].t, d, vols[k].scale, vols[k].offset);
        CHECK(v != NULL, "volume");
        if (v) classifications(pool, v, vols[k].scale, vols[k].offset, vols[k].name);
        vs_volume_release(v);
    }
    /* rows shorter than twice the seam (the dilation's row ends) and
     * single voxels across */
    static const int narrow[][3] = {{3, 7, 5}, {1, 9, 4}, {2, 2, 2}, {5, 1, 6}, {17, 3, 1}};
    for (int k = 0; k < 5; k++) {
        vs_volume *v = make_volume(VS_U8, narrow[k], 1.0, 0.0);
        CHECK(v != NULL, "volume");
        char name[64];
        snprintf(name, sizeof name, "u8 %dx%dx%d", narrow[k][0], narrow[k][1], narrow[k][2]);
        if (v) classifications(pool, v, 1.0, 0.0, name);
        vs_volume_release(v);
    }
    printf("%d classifications: brick by brick equals the whole grid (%d built sparsely)\n", cases, sparse_cases);
    CHECK(sparse_cases > cases / 2, "only %d of %d built brick by brick", sparse_cases, cases);
    printf("%d bricks with every voxel relevant share one block\n", shared_bricks);
    CHECK(shared_bricks > 0, "no list had a brick with every voxel relevant");
    test_borders(pool);
    test_reuse(pool);
    vs_pool_destroy(pool);
    vs_context_release(ctx);
    TEST_DONE();
}
