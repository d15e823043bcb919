/* Compressed NRRD data.  Teem 1.12's gzip and bzip2 readers return without
 * closing the stream when the data is corrupt, cut short or shorter than
 * the header says, or a byte skip runs past it, so the decoder leaks: 56 KB
 * (gzip) or 3.6 MB (bzip2) a file (found by fuzz_nrrd and valgrind).  Teem
 * still parses the header, opens the data and skips its lines; this decodes
 * each data file's stream with zlib's gz* reader or libbz2, and always
 * closes it.  As in Teem: "byte skip" counts decoded bytes, -N-1 puts the
 * data N bytes before the decoded end, each data file holds an equal share
 * of the samples, the data may end before the stream does, and gzip data
 * may be concatenated members or (zlib's transparent mode) not compressed
 * at all.  Beyond Teem: bzip2 data may be several concatenated streams, as
 * pbzip2 writes them.  A skip, decoded rather than sought, is at most 1 GiB
 * (a small file must not decode for hours), a trailer 64 MiB (it is held
 * in memory). */
#include "nrrd_compressed.h"

#include "load_common.h"
#include "nrrd_data_files.h"

#include <bzlib.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#define SKIP_MAX (1L << 30) /* bytes decoded before the data */
#define TAIL_MAX (1L << 26) /* bytes kept after it (byte skip -N-1) */
#define SHORT "fewer decoded bytes than the header's sizes"

typedef struct {
    int gzip;
    FILE *f;
    gzFile gz;
    BZFILE *bz;
    int streams, fresh, done; /* bzip2: streams begun; in a later one's first read; at the end */
    int nkeep;                /* bytes libbz2 read past a stream's end: the next one's start */
    unsigned char keep[BZ_MAX_UNUSED];
} stream;

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

/* Starts decoding at f's position. */
static const char *stream_open(stream *s, FILE *f, int gzip)
{
    s->gzip = gzip;
    s->gz = NULL;
    s->bz = NULL;
    s->streams = s->fresh = s->done = s->nkeep = 0;
    s->f = f;
    if (!gzip) return NULL; /* libbz2 opens a stream where one starts */
    /* zlib reads a descriptor: a copy, at the FILE's logical position */
    const off_t at = ftello(f);
    const int fd = at < 0 ? -1 : dup(fileno(f));
    if (fd < 0 || lseek(fd, at, SEEK_SET) != at || !(s->gz = gzdopen(fd, "rb"))) {
        if (fd >= 0) close(fd);
        return "cannot start decoding gzip data";
    }
    return NULL;
}

static void stream_close(stream *s)
{
    int err;
    if (s->gz) gzclose(s->gz);
    if (s->bz) BZ2_bzReadClose(&err, s->bz);
    s->gz = NULL;
    s->bz = NULL;
}

/* Reads up to n bytes into dst; *got is less than n only at the end of the
 * data.  NULL, or what went wrong. */
static const char *stream_read(stream *s, unsigned char *dst, size_t n, size_t *got)
{
    if (s->gzip) {
        *got = vs_load_gzread(s->gz, dst, n);
        int err = Z_OK;
        if (*got < n) gzerror(s->gz, &err);
        return err == Z_OK ? NULL : err == Z_BUF_ERROR ? "gzip data cut short" : "corrupt gzip data";
    }
    *got = 0;
    while (*got < n) {
        const size_t want = n - *got > (size_t)INT_MAX / 2 ? (size_t)INT_MAX / 2 : n - *got;
        int k, err = BZ_OK;
        if (s->done) return NULL;
        if (!s->bz) {
            if (s->nkeep == 0) { /* nothing after a stream: the end */
                const int c = getc(s->f);
                if (c == EOF) return NULL;
                ungetc(c, s->f);
            }
            s->bz = BZ2_bzReadOpen(&err, s->f, 0, 0, s->nkeep ? s->keep : NULL, s->nkeep);
            if (err != BZ_OK) {
                s->bz = NULL;
                return bz_problem(err);
            }
            s->fresh = s->streams++ > 0;
        }
        k = BZ2_bzRead(&err, s->bz, dst + *got, (int)want);
        if (s->fresh && err == BZ_DATA_ERROR_MAGIC) { /* bytes after a stream that are not one */
            s->done = 1;  /* the end, as the bzip2 tool ignores "trailing garbage" */
            return NULL;
        }
        if (err != BZ_OK && err != BZ_STREAM_END) return bz_problem(err);
        s->fresh = 0;
        *got += (size_t)k;
        if (err == BZ_STREAM_END) { /* another stream may follow */
            void *rest;
            BZ2_bzReadGetUnused(&err, s->bz, &rest, &s->nkeep);
            memcpy(s->keep, rest, (size_t)s->nkeep);
            BZ2_bzReadClose(&err, s->bz);
            s->bz = NULL;
        }
    }
    return NULL;
}

/* The piece of n bytes after `skip` decoded bytes, or (skip -N-1) ending N
 * bytes before the decoded end. */
static const char *read_piece(stream *s, long skip, unsigned char *dst, size_t n)
{
    size_t got;
    const char *why;
    if (skip >= 0) {
        unsigned char scratch[4096];
        for (size_t left = (size_t)skip; left > 0; left -= got) {
            why = stream_read(s, scratch, left < sizeof scratch ? left : sizeof scratch, &got);
            if (why) return why;
            if (got == 0) return SHORT;
        }
        why = stream_read(s, dst, n, &got);
        return why ? why : got < n ? SHORT : NULL;
    }
    /* keep the last n + N decoded bytes in a ring */
    const size_t ring_n = n + (size_t)(-(skip + 1));
    if (ring_n == 0) return NULL;
    unsigned char *ring = malloc(ring_n);
    if (!ring) return "out of memory";
    size_t total = 0;
    for (;;) {
        const size_t at = total % ring_n;
        why = stream_read(s, ring + at, ring_n - at, &got);
        total += got;
        if (why || got < ring_n - at) break;
        if (total > ring_n + (size_t)SKIP_MAX) { /* bounded as a skip is */
            why = "more than 1 GiB decoded before the data";
            break;
        }
    }
    if (!why && total < ring_n) why = SHORT;
    if (!why) { /* the oldest kept byte is at total % ring_n */
        const size_t at = total % ring_n, first = ring_n - at < n ? ring_n - at : n;
        memcpy(dst, ring + at, first);
        memcpy(dst + first, ring, n - first);
    }
    free(ring);
    return why;
}

vs_status vs_nrrd_read_compressed(vs_context *ctx, const char *path, Nrrd *nrrd, NrrdIoState *nio)
{
    const int gzip = nio->encoding == nrrdEncodingGzip;
    const size_t elem = nrrdElementSize(nrrd), total = nrrdElementNumber(nrrd);
    const unsigned files = vs_nrrd_data_count(nio);
    if (files == 0) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: no NRRD data files", path);
    if (nio->byteSkip > SKIP_MAX || nio->byteSkip < -TAIL_MAX - 1)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: byte skip %ld with %s data (%ld to %ld)", path, nio->byteSkip,
                            nio->encoding->name, -TAIL_MAX - 1, SKIP_MAX);
    unsigned char *data = nrrd->data ? nrrd->data : calloc(total ? total : 1, elem);
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
        stream s;
        if (!why) why = stream_open(&s, f, gzip);
        if (!why) {
            why = read_piece(&s, nio->byteSkip, data + i * piece, piece);
            stream_close(&s);
        }
        if (f) fclose(f);
        if (why) {
            if (data != nrrd->data) free(data);
            if (files == 1) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: %s", path, why);
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: data file %u of %u (%s): %s", path, i + 1, files, name, why);
        }
    }
    nrrd->data = data;
    if (elem > 1 && nio->endian != airEndianUnknown && nio->endian != airMyEndian()) nrrdSwapEndian(nrrd);
    return VS_OK;
}
