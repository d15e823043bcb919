/* The render fuzzer's decoder (tests/fuzz/render_case.h) driven by a fixed
 * seed in the normal suite, so that the gcc, ASan and TSan builds run it
 * too: a few hundred random cases (small hostile volumes of every voxel
 * type, settings from every corner), each rendered with 1 and with 2-3
 * threads.  Fails on a broken promise (a non-finite colour, alpha outside
 * [0,1], images that differ between thread counts, an error without a
 * message), a crash, or a case slower than 5 s.  Also renders every file
 * of tests/fuzz/seeds/render and tests/fuzz/regressions/render.
 * VSPLAT_RENDER_FUZZ_CASES and VSPLAT_RENDER_FUZZ_SEED change the run. */
#include "testutil.h"
#include "fuzz/render_case.h"

#include <dirent.h>

static vs_context *ctxs[4]; /* by thread count */
static int cases, rendered;

static void one(const uint8_t *d, size_t n, const char *what)
{
    char why[512];
    vs_status st;
    double t0 = tu_now_s();
    const char *fail = rc_check(ctxs, d, n, &st, why, sizeof why);
    double dt = tu_now_s() - t0;
    CHECK(!fail, "%s: %s", what, fail);
    CHECK(dt < 5.0, "%s: took %.1f s", what, dt);
    cases++;
    rendered += st == VS_OK;
}

static void run_dir(const char *kind)
{
    char dir[1200];
    const char *src = getenv("VSPLAT_SOURCE_DIR");
    snprintf(dir, sizeof dir, "%s/tests/fuzz/%s/render", src ? src : ".", kind);
    DIR *dd = opendir(dir);
    if (!dd) return;
    struct dirent *e;
    while ((e = readdir(dd))) {
        if (e->d_name[0] == '.') continue;
        char p[2400];
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        size_t n;
        unsigned char *b = tu_read_file(p, &n);
        if (!b) continue;
        one(b, n, p);
        free(b);
    }
    closedir(dd);
}

int main(void)
{
    for (int t = 1; t < 4; t++)
        if (vs_context_create(&ctxs[t]) != VS_OK) return 2;
    run_dir("seeds");
    run_dir("regressions");
    const char *ec = getenv("VSPLAT_RENDER_FUZZ_CASES"), *es = getenv("VSPLAT_RENDER_FUZZ_SEED");
    int ncases = ec ? atoi(ec) : getenv("VSPLAT_TEST_QUICK") ? 200 : 600; /* sanitizer builds: quick */
    uint64_t x = es ? strtoull(es, NULL, 10) : 24;
    double t0 = tu_now_s();
    for (int k = 0; k < ncases; k++) {
        uint8_t buf[160];
        size_t n = 40 + k % 120; /* short inputs leave the tail of the settings at 0 */
        for (size_t i = 0; i < n; i++) {
            x ^= x << 13; /* xorshift64: the same cases everywhere */
            x ^= x >> 7;
            x ^= x << 17;
            buf[i] = (uint8_t)(x >> 32);
        }
        char what[64];
        snprintf(what, sizeof what, "case %d", k);
        one(buf, n, what);
    }
    printf("%d cases (%d rendered, the rest refused with a status) in %.1f s\n", cases, rendered,
           tu_now_s() - t0);
    CHECK(rendered > cases / 4, "only %d of %d cases rendered: the decoder makes mostly invalid settings", rendered,
          cases);
    for (int t = 1; t < 4; t++) vs_context_release(ctxs[t]);
    TEST_DONE();
}
