/* Shared libFuzzer plumbing: write the input to a temporary file with the
 * suffix the loader dispatches on, call vs_volume_load (and, for formats
 * read in part, vs_volume_load_box on the middle box, which must agree),
 * release.  Any
 * status is fine; a crash, a sanitizer report, a leak, a hang (-timeout) or
 * an allocation over -rss_limit_mb/-malloc_limit_mb is a finding. */
#ifndef VS_FUZZ_COMMON_H
#define VS_FUZZ_COMMON_H

#include "vsplat.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static vs_context *fz_ctx;

/* A file name per process (libFuzzer -jobs/-workers run processes). */
static inline const char *fz_path(const char *suffix)
{
    static char path[512];
    const char *t = getenv("TMPDIR");
    snprintf(path, sizeof path, "%s/vsplat_fuzz_%ld%s", (t && *t) ? t : "/tmp", (long)getpid(), suffix);
    return path;
}

static inline int fz_write(const char *path, const uint8_t *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    if (!f) return 0;
    int ok = fwrite(data, 1, size, f) == size;
    ok = (fclose(f) == 0) && ok;
    return ok;
}

/* A file that loads and can be read in part (raw, NIfTI) gives, for its
 * middle box, the loaded volume's voxels there, type and directions. */
static inline void fz_check_box(const char *path, const vs_load_options *opt, vs_volume *v)
{
    int fd[3], d[3];
    vs_volume_dims(v, d);
    vs_status st = vs_volume_file_dims(fz_ctx, path, opt, fd);
    if (st == VS_ERR_UNSUPPORTED) return;
    if (st != VS_OK || fd[0] != d[0] || fd[1] != d[1] || fd[2] != d[2]) abort();
    int lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = d[a] / 4;
        hi[a] = d[a] - d[a] / 4;
    }
    vs_volume *b = NULL;
    if (vs_volume_load_box(fz_ctx, path, opt, lo, hi, &b) != VS_OK || !b) abort();
    int bd[3];
    vs_volume_dims(b, bd);
    if (vs_volume_type(b) != vs_volume_type(v)) abort();
    const size_t e = vs_volume_type(v) == VS_U8 ? 1 : vs_volume_type(v) == VS_F32 ? 4 : 2;
    const char *pv = vs_volume_data(v), *pb = vs_volume_data(b);
    for (int k = 0; k < bd[2]; k++)
        for (int j = 0; j < bd[1]; j++)
            if (memcmp(pv + ((((size_t)(k + lo[2]) * d[1] + (j + lo[1])) * d[0]) + lo[0]) * e,
                       pb + (((size_t)k * bd[1] + j) * bd[0]) * e, (size_t)bd[0] * e))
                abort();
    double mv[12], mb[12];
    if (vs_volume_affine(v, mv) != vs_volume_affine(b, mb)) abort();
    for (int r = 0; r < 3; r++)
        for (int a = 0; a < 3; a++)
            if (memcmp(&mv[4 * r + a], &mb[4 * r + a], sizeof(double))) abort();
    vs_volume_release(b);
}

/* Load `data` as a file ending in `suffix` (opt may be NULL). */
static inline void fz_load(const uint8_t *data, size_t size, const char *suffix, const vs_load_options *opt)
{
    if (!fz_ctx && vs_context_create(&fz_ctx) != VS_OK) abort();
    const char *path = fz_path(suffix);
    if (!fz_write(path, data, size)) abort();
    vs_volume *v = NULL;
    vs_status st = vs_volume_load(fz_ctx, path, opt, &v);
    if (st == VS_OK) {
        /* what a loaded volume promises: sane dims and a finite range */
        int d[3];
        double lo, hi;
        vs_volume_dims(v, d);
        vs_volume_range(v, &lo, &hi);
        if (d[0] < 1 || d[1] < 1 || d[2] < 1 || !(lo <= hi)) abort();
        fz_check_box(path, opt, v);
        vs_volume_release(v);
    } else {
        if (v) abort();                         /* out must be cleared */
        if (!*vs_last_error(fz_ctx)) abort();   /* and a message given */
        /* a harness that cannot reach the image loaders fuzzes nothing.
         * Matched as the message's start: loader messages start with the
         * file's path, and libFuzzer copies the harness's own strings into
         * inputs, which a loader may echo back in its message. */
        static const char no_module[] = "image I/O: cannot load the OpenImageIO module";
        if (!strncmp(vs_last_error(fz_ctx), no_module, sizeof no_module - 1)) {
            fprintf(stderr, "fuzz: %s\n", vs_last_error(fz_ctx));
            abort();
        }
    }
    unlink(path);
}

#endif
