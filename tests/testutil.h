/* Minimal test helpers: CHECK counts failures; TEST_DONE returns the exit
 * code.  A test that needs absent data prints "SKIP: why" and returns 0. */
#ifndef VS_TESTUTIL_H
#define VS_TESTUTIL_H
#include "vsplat.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static int tu_failures = 0;
#define CHECK(cond, ...)                                                         \
    do {                                                                         \
        if (!(cond)) {                                                           \
            tu_failures++;                                                       \
            fprintf(stderr, "FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);      \
            fprintf(stderr, __VA_ARGS__);                                        \
            fprintf(stderr, "\n");                                               \
        }                                                                        \
    } while (0)
#define TEST_DONE()                                                              \
    do {                                                                         \
        if (tu_failures) {                                                       \
            fprintf(stderr, "%d check(s) failed\n", tu_failures);                \
            return 1;                                                            \
        }                                                                        \
        printf("all checks passed\n");                                           \
        return 0;                                                                \
    } while (0)

/* Folder of the real volumes: $VSPLAT_DATA, else ../shared/data beside the
 * source tree.  Returns NULL (and the caller skips with a message) if absent. */
static inline const char *tu_data_dir(void)
{
    static char buf[4096];
    const char *env = getenv("VSPLAT_DATA");
    struct stat st;
    if (env && *env && stat(env, &st) == 0) return env;
    const char *src = getenv("VSPLAT_SOURCE_DIR");
    if (!src) src = ".";
    snprintf(buf, sizeof buf, "%s/../shared/data", src);
    if (stat(buf, &st) == 0) return buf;
    return NULL;
}

/* Largest absolute difference of two images of the same size, over every
 * channel; a NaN on either side counts as a difference. */
static inline double tu_max_diff(const vs_image *a, const vs_image *b)
{
    double m = 0;
    for (size_t i = 0; i < (size_t)a->width * a->height * 4; i++) {
        double d = fabs((double)a->rgba[i] - b->rgba[i]);
        if (!(d <= m)) m = d;
    }
    return m;
}

static inline const char *tu_tmpdir(void)
{
    const char *t = getenv("TMPDIR");
    return (t && *t) ? t : "/tmp";
}
#endif
