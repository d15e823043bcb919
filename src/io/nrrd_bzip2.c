/* bzip2-encoded NRRD data.  Teem 1.12's bzip2 reader returns without
 * closing the stream when the data is corrupt, cut short or shorter than
 * the header says, or a byte skip runs past it, so libbz2's decoder leaks,
 * 3.6 MB a file (found by fuzz_nrrd).  Teem still parses the header, opens
 * the data and skips its lines; this decodes each data file's stream with
 * libbz2 as Teem would, and always closes it.  As in Teem: "byte skip"
 * counts decoded bytes, each data file holds an equal share of the samples,
 * and the data may end before the stream does.  Unlike Teem, a stream may
 * be followed by another, as pbzip2 writes them; a byte skip, decoded
 * rather than sought, is bounded (SKIP_MAX). */
#include "nrrd_bzip2.h"

#include "nrrd_data_files.h"

#include <bzlib.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *bz_problem(int err)
{
    switch (err) {
    case BZ_DATA_ERROR: return "corrupt bzip2 data";
    case BZ_DATA_ERROR_MAGIC: return "not bzip2 data";
    case BZ_UNEXPECTED_EOF: return "bzip2 data cut short";
    case BZ_MEM_ERROR: return "out of memory decoding bzip2 data";
    case BZ_IO_ERROR: return "read error";
    default: return "bzip2 decoding failed";
    }
}

#define SKIP_MAX (1L << 30)
#define SHORT "fewer bzip2-encoded bytes than the header's sizes"

/* Decodes n bytes into dst (NULL: discards them), opening the next stream
 * where one ends.  NULL, or what went wrong. */
static const char *decode(FILE *f, BZFILE **bz, unsigned char *dst, size_t n)
{
    unsigned char scratch[4096];
    int next = 0; /* reading a stream that followed another */
    while (n > 0) {
        int err = BZ_OK;
        if (!*bz) {
            *bz = BZ2_bzReadOpen(&err, f, 0, 0, NULL, 0);
            if (err != BZ_OK) {
                *bz = NULL;
                return bz_problem(err);
            }
        }
        const size_t cap = dst ? (n > INT_MAX ? INT_MAX : n) : (n > sizeof scratch ? sizeof scratch : n);
        const int got = BZ2_bzRead(&err, *bz, dst ? dst : scratch, (int)cap);
        if (next && err == BZ_DATA_ERROR_MAGIC) return SHORT; /* what follows is not a stream */
        if (err != BZ_OK && err != BZ_STREAM_END) return bz_problem(err);
        next = 0;
        if (dst) dst += got;
        n -= (size_t)got;
        if (err == BZ_STREAM_END && n > 0) {
            /* the bytes read past this stream's end start the next one */
            void *rest;
            int nrest, e2;
            BZ2_bzReadGetUnused(&e2, *bz, &rest, &nrest);
            unsigned char keep[BZ_MAX_UNUSED];
            memcpy(keep, rest, (size_t)nrest);
            BZ2_bzReadClose(&e2, *bz);
            *bz = NULL;
            if (nrest == 0) {
                int c = getc(f);
                if (c == EOF) return SHORT;
                ungetc(c, f);
            }
            next = 1;
            err = BZ_OK;
            *bz = BZ2_bzReadOpen(&err, f, 0, 0, keep, nrest);
            if (err != BZ_OK) {
                *bz = NULL;
                return bz_problem(err);
            }
        }
    }
    return NULL;
}

vs_status vs_nrrd_read_bzip2(vs_context *ctx, const char *path, Nrrd *nrrd, NrrdIoState *nio)
{
    const size_t elem = nrrdElementSize(nrrd), total = nrrdElementNumber(nrrd);
    const unsigned files = vs_nrrd_data_count(nio);
    if (files == 0) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: no NRRD data files", path);
    /* A skip is decoded, not sought: bound the time a small file can take. */
    if (nio->byteSkip < 0 || nio->byteSkip > SKIP_MAX)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: byte skip %ld with bzip2 data (0 to %ld)", path,
                            nio->byteSkip, (long)SKIP_MAX);
    unsigned char *data = calloc(total ? total : 1, elem);
    if (!data) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    const size_t piece = total / files * elem;
    for (unsigned i = 0; i < files; i++) {
        char name[4096] = "";
        FILE *f = NULL;
        const char *why = NULL;
        if (files == 1) { /* left open by Teem after the header and line skip */
            f = nio->dataFile;
            nio->dataFile = NULL;
            if (!f) why = "data file not open";
        } else if (!vs_nrrd_data_path(nio, i, name, sizeof name) || !(f = fopen(name, "rb"))) {
            why = "cannot open";
        } else if (nrrdLineSkip(f, nio)) {
            free(biffGetDone(NRRD));
            why = "line skip past the end of a data file";
        }
        BZFILE *bz = NULL;
        if (!why) why = decode(f, &bz, NULL, (size_t)nio->byteSkip);
        if (!why) why = decode(f, &bz, data + i * piece, piece);
        int err;
        if (bz) BZ2_bzReadClose(&err, bz);
        if (f) fclose(f);
        if (why) {
            free(data);
            if (files == 1) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: %s", path, why);
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: data file %u of %u (%s): %s", path, i + 1, files, name, why);
        }
    }
    nrrd->data = data;
    if (elem > 1 && nio->endian != airEndianUnknown && nio->endian != airMyEndian()) nrrdSwapEndian(nrrd);
    return VS_OK;
}
