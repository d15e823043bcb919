/* The pool of emptied bucket arrays (src/tile.h vs_keep_spare): whatever
 * comes, it holds at most VS_SPARES arrays and VS_SPARE_BYTES together,
 * its byte count is the sum of what it holds, and an array is given up
 * only for a larger one that is then kept -- never evicted to no end.
 * Every array is either in the pool or freed exactly once (the sanitizer
 * builds of the suite see a leak or a double free). */
#include "tile.h"
#include "testutil.h"

#include <stdint.h>
#include <string.h>

static unsigned rng = 12345u;
static unsigned next(void)
{
    rng = rng * 1664525u + 1013904223u;
    return rng >> 8;
}

/* The pool's arrays as addresses and sizes: an array the pool frees may
 * not be compared as a pointer afterwards, its address as a number may. */
typedef struct snapshot {
    int n;
    uintptr_t p[VS_SPARES];
    int cap[VS_SPARES];
} snapshot;

static snapshot take(const vs_spares *s)
{
    snapshot z;
    z.n = s->n;
    for (int i = 0; i < s->n; i++) {
        z.p[i] = (uintptr_t)s->p[i];
        z.cap[i] = s->cap[i];
    }
    return z;
}

/* index of the array at address a with cap entries in z, or -1 */
static int find(const snapshot *z, uintptr_t a, int cap)
{
    for (int j = 0; j < z->n; j++)
        if (z->p[j] == a && z->cap[j] == cap) return j;
    return -1;
}

static void check_one(vs_spares *s, int cap, int *kept, int *refused)
{
    pend *p = malloc((size_t)cap * sizeof(pend));
    if (!p) {
        CHECK(0, "out of memory for a test array of %d voxels", cap);
        return;
    }
    const uintptr_t pa = (uintptr_t)p;
    const snapshot before = take(s);
    vs_keep_spare(s, p, cap);
    const snapshot after = take(s);
    size_t bytes = 0;
    for (int i = 0; i < s->n; i++) bytes += (size_t)s->cap[i] * sizeof(pend);
    const int in = find(&after, pa, cap) >= 0;
    CHECK(s->n <= VS_SPARES, "%d arrays kept, at most %d allowed", s->n, VS_SPARES);
    CHECK(bytes == s->bytes, "pool counts %zu bytes, holds %zu", s->bytes, bytes);
    CHECK(s->bytes <= VS_SPARE_BYTES, "pool holds %zu bytes, at most %d allowed", s->bytes, VS_SPARE_BYTES);
    if (in) {
        ++*kept;
        /* whatever went was smaller than what came */
        for (int i = 0; i < before.n; i++)
            CHECK(find(&after, before.p[i], before.cap[i]) >= 0 || before.cap[i] < cap,
                  "an array of %d gave way to one of %d", before.cap[i], cap);
    } else {
        ++*refused;
        int same = after.n == before.n;
        for (int i = 0; same && i < before.n; i++) same = find(&after, before.p[i], before.cap[i]) >= 0;
        CHECK(same, "an array of %d refused, yet the pool changed", cap);
    }
}

int main(void)
{
    vs_spares s;
    memset(&s, 0, sizeof s);
    const int big = VS_SPARE_BYTES / (int)sizeof(pend); /* voxels that fill the pool alone */
    int kept = 0, refused = 0;
    /* the count limit: 32 small ones, then a larger one takes a place */
    for (int i = 0; i < VS_SPARES; i++) check_one(&s, 256, &kept, &refused);
    CHECK(s.n == VS_SPARES && kept == VS_SPARES, "%d of %d small arrays kept", s.n, VS_SPARES);
    check_one(&s, 512, &kept, &refused);
    CHECK(kept == VS_SPARES + 1 && s.n == VS_SPARES, "a larger array not kept in a full pool");
    check_one(&s, 128, &kept, &refused);
    CHECK(refused == 1, "a smaller array pushed into a full pool");
    /* larger than the whole pool: refused with nothing evicted */
    check_one(&s, big + 1, &kept, &refused);
    CHECK(refused == 2 && s.n == VS_SPARES, "an array over the pool's bytes handled wrongly");
    /* the byte limit: one array of most of the pool, then one that only
     * fits if the large one went, which is not smaller: refused */
    vs_spares_free(&s);
    check_one(&s, big - 4096, &kept, &refused);
    check_one(&s, 256, &kept, &refused);
    check_one(&s, 8192, &kept, &refused);
    CHECK(refused == 3 && s.n == 2, "an array that fits only by evicting a larger one: %d kept", s.n);
    /* and anything at all, with arrays taken back out as new buckets do
     * (src/activate.c grow_bucket: the last one kept) */
    vs_spares_free(&s);
    for (int i = 0; i < 4000; i++) {
        const unsigned r = next();
        if (r % 3 == 0 && s.n > 0) {
            s.n--;
            s.bytes -= (size_t)s.cap[s.n] * sizeof(pend);
            free(s.p[s.n]);
            continue;
        }
        const int cap = r % 16 == 1 ? (int)(next() % (unsigned)(2 * big)) + 1 : 256 << (next() % 8);
        check_one(&s, cap, &kept, &refused);
    }
    printf("bucket spares: %d arrays kept, %d refused; the pool ends with %d arrays, %zu bytes\n", kept, refused,
           s.n, s.bytes);
    CHECK(refused > 100 && kept > 1000, "the random sequence tried too little: %d kept, %d refused", kept, refused);
    vs_spares_free(&s);
    TEST_DONE();
}
