/* NRRD (.nrrd, .nhdr + detached data) through Teem.  The header is read
 * first without data, so absurd sizes are refused before anything is
 * allocated; then the volume is allocated and the data read into it: by
 * Teem, or for gzip and bzip2 by nrrd_compressed.c.  uchar/short/ushort/float keep their type,
 * other scalar types become f32.  Spacing per axis from nrrdSpacingCalculate
 * (axis spacing, or the length of the space direction), else 1.
 * Orientation from an anatomical `space` (RAS, LAS, LPS, or one of them
 * with time) with a `space direction` for each of three axes and the
 * `space origin` (0 if absent): converted to RAS by negating the left and
 * posterior components.  Other spaces ("scanner-xyz", "3D-right-handed",
 * ...) say nothing about the anatomy: spacing only. */
#include "context.h"
#include "load.h"
#include "load_common.h"
#include "nrrd_compressed.h"
#include "nrrd_data_files.h"
#include "nrrd_header_check.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <teem/biff.h>
#include <teem/nrrd.h>

/* Takes Teem's accumulated error text (freeing it) into our message. */
static vs_status teem_error(vs_context *ctx, vs_status st, const char *path, const char *what)
{
    char *e = biffGetDone(NRRD);
    char msg[384] = "";
    if (e) {
        size_t j = 0;
        for (size_t i = 0; e[i] && j + 3 < sizeof msg; i++) {
            if (e[i] == '\n') {
                if (e[i + 1]) {
                    msg[j++] = ';';
                    msg[j++] = ' ';
                }
            } else {
                msg[j++] = e[i];
            }
        }
        msg[j] = '\0';
        free(e);
    }
    return vs_set_error(ctx, st, "%s: %s%s%s", path, what, *msg ? ": " : "", msg);
}

/* Bytes in the files that hold the data, or 0 if unknown. */
static uint64_t data_bytes(const NrrdIoState *nio, uint64_t header_size)
{
    if (!nio->dataFNFormat && nio->dataFNArr->len == 0) return header_size;
    const unsigned files = vs_nrrd_data_count(nio);
    uint64_t sum = 0;
    for (unsigned i = 0; i < files; i++) {
        char buf[4096];
        struct stat st;
        if (!vs_nrrd_data_path(nio, i, buf, sizeof buf) || stat(buf, &st) != 0) return 0;
        sum += (uint64_t)st.st_size;
    }
    return sum;
}

/* The data file Teem leaves open (nrrdIoStateKeepNrrdDataFileOpen). */
static void close_kept(NrrdIoState *nio)
{
    if (!nio || !nio->dataFile) return;
    fclose(nio->dataFile);
    nio->dataFile = NULL;
}

static double nrrd_value(const void *p, int type, size_t i)
{
    switch (type) {
    case nrrdTypeChar: return ((const signed char *)p)[i];
    case nrrdTypeUChar: return ((const unsigned char *)p)[i];
    case nrrdTypeShort: return ((const short *)p)[i];
    case nrrdTypeUShort: return ((const unsigned short *)p)[i];
    case nrrdTypeInt: return ((const int *)p)[i];
    case nrrdTypeUInt: return ((const unsigned int *)p)[i];
    case nrrdTypeLLong: return (double)((const long long *)p)[i];
    case nrrdTypeULLong: return (double)((const unsigned long long *)p)[i];
    case nrrdTypeFloat: return ((const float *)p)[i];
    default: return ((const double *)p)[i];
    }
}

/* The volume's type for a NRRD type: other types become f32. */
static vs_type type_of(int nrrd_type)
{
    switch (nrrd_type) {
    case nrrdTypeUChar: return VS_U8;
    case nrrdTypeShort: return VS_I16;
    case nrrdTypeUShort: return VS_U16;
    default: return VS_F32;
    }
}

/* Spacing per axis: axis spacing or the length of the space direction, else 1. */
static void spacing_of(const Nrrd *nrrd, double spacing[3])
{
    spacing[0] = spacing[1] = spacing[2] = 1.0;
    for (unsigned a = 0; a < nrrd->dim && a < 3; a++) {
        double sp = NAN, vec[NRRD_SPACE_DIM_MAX];
        int ss = nrrdSpacingCalculate(nrrd, a, &sp, vec);
        if (ss == nrrdSpacingStatusScalarNoSpace || ss == nrrdSpacingStatusScalarWithSpace ||
            ss == nrrdSpacingStatusDirection) {
            sp = fabs(sp);
            if (sp > 0.0 && isfinite(sp)) spacing[a] = sp;
        }
    }
}

static void set_orientation(vs_volume *v, const Nrrd *nrrd)
{
    double flip[3] = {1, 1, 1};
    switch (nrrd->space) {
    case nrrdSpaceRightAnteriorSuperior: case nrrdSpaceRightAnteriorSuperiorTime: break;
    case nrrdSpaceLeftAnteriorSuperior: case nrrdSpaceLeftAnteriorSuperiorTime: flip[0] = -1; break;
    case nrrdSpaceLeftPosteriorSuperior: case nrrdSpaceLeftPosteriorSuperiorTime: flip[0] = flip[1] = -1; break;
    default: return;
    }
    if (nrrd->dim != 3 || nrrd->spaceDim < 3) return;
    double m[3][4];
    for (int r = 0; r < 3; r++) {
        double o = nrrd->spaceOrigin[r];
        m[r][3] = flip[r] * (isfinite(o) ? o : 0.0);
        for (int c = 0; c < 3; c++) m[r][c] = flip[r] * nrrd->axis[c].spaceDirection[r];
    }
    vs_volume_set_affine(NULL, v, m); /* NaN (no direction) or singular: spacing only */
}

vs_status vs_load_nrrd(vs_context *ctx, const char *path, vs_volume **out)
{
    uint64_t fsize;
    vs_status st = vs_load_file_size(ctx, path, &fsize);
    if (st != VS_OK) return st;
    if (fsize == 0) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: empty file", path);
    /* .nrrd and .nhdr files start with the line "NRRD000N".  Without it
     * Teem tries its other formats (a plain-text table, PNM, ...), slowly,
     * and leaks on the text table's error paths (fuzz_nrrd): refuse first. */
    {
        char magic[9] = {0};
        FILE *f = fopen(path, "rb");
        if (!f) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open", path);
        size_t got = fread(magic, 1, sizeof magic, f);
        fclose(f);
        if (got != sizeof magic || memcmp(magic, "NRRD000", 7) != 0 || magic[7] < '1' || magic[7] > '9' ||
            (magic[8] != '\n' && magic[8] != '\r'))
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: not a NRRD file (no NRRD magic at the start)", path);
    }
    st = vs_nrrd_header_check(ctx, path); /* headers Teem leaks on */
    if (st != VS_OK) return st;

    /* Teem's only switch for its stderr warnings (e.g. data after the end)
     * is this process-wide flag; vsplat never prints, so turn it off. */
    nrrdStateVerboseIO = 0;
    Nrrd *nrrd = nrrdNew();
    NrrdIoState *nio = nrrdIoStateNew();
    vs_volume *v = NULL;
    if (!nrrd || !nio) {
        st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
        goto done;
    }
    nrrdIoStateSet(nio, nrrdIoStateSkipData, AIR_TRUE);
    nrrdIoStateSet(nio, nrrdIoStateKeepNrrdDataFileOpen, AIR_TRUE); /* for compressed data */
    if (nrrdLoad(nrrd, path, nio)) {
        /* data after the header: the file kept open was the header's,
         * which nrrdLoad has closed on its way out */
        if (!nio->dataFNFormat && nio->dataFNArr->len == 0) nio->dataFile = NULL;
        st = teem_error(ctx, VS_ERR_FORMAT, path, "cannot read NRRD header");
        goto done;
    }
    if (nrrd->dim != 2 && nrrd->dim != 3) {
        st = vs_set_error(ctx, VS_ERR_UNSUPPORTED, "%s: %u-D NRRD, expected a 3-D scalar volume",
                          path, nrrd->dim);
        goto done;
    }
    if (nrrd->type <= nrrdTypeUnknown || nrrd->type >= nrrdTypeBlock) {
        st = vs_set_error(ctx, VS_ERR_UNSUPPORTED, "%s: unsupported NRRD type %d", path, nrrd->type);
        goto done;
    }
    int64_t d[3];
    for (unsigned a = 0; a < 3; a++) {
        size_t n = a < nrrd->dim ? nrrd->axis[a].size : 1;
        if (n > (size_t)VS_MAX_DIM) {
            st = vs_set_error(ctx, VS_ERR_TOO_LARGE, "%s: axis %u has %zu samples (limit %d)", path,
                              a, n, VS_MAX_DIM);
            goto done;
        }
        d[a] = (int64_t)n;
    }
    size_t elem = nrrdTypeSize[nrrd->type];
    uint64_t need;
    st = vs_load_check_dims(ctx, path, d, elem, &need);
    if (st != VS_OK) goto done;
    /* Refuse sizes the data file(s) cannot hold before Teem allocates. */
    uint64_t have = data_bytes(nio, fsize);
    const NrrdEncoding *enc = nio->encoding;
    if (have > 0 && enc) {
        uint64_t limit = UINT64_MAX;
        if (enc == nrrdEncodingRaw) limit = have;
        else if (enc == nrrdEncodingGzip) limit = vs_load_inflate_bound(have);
        else if (enc == nrrdEncodingAscii || enc == nrrdEncodingHex) limit = have * elem;
        if (need > limit) {
            st = vs_set_error(ctx, VS_ERR_FORMAT,
                              "%s: truncated: expected %llu bytes of %s data, file has %llu", path,
                              (unsigned long long)need, enc->name, (unsigned long long)have);
            goto done;
        }
    }

    /* The volume first, so that the data go straight into it where the
     * file's type is the volume's: Teem reuses a buffer of the right size
     * (nrrdWrap before nrrdLoad), the gzip and bzip2 reader writes into
     * nrrd->data.  Other types are read by Teem and converted. */
    int dims[3];
    for (int a = 0; a < 3; a++) dims[a] = (int)d[a];
    double spacing[3];
    spacing_of(nrrd, spacing);
    const int file_type = nrrd->type;
    const vs_type type = type_of(file_type);
    const int in_place = type != VS_F32 || file_type == nrrdTypeFloat;
    st = vs_load_alloc(ctx, path, type, dims, spacing, &v);
    if (st != VS_OK) goto done;
    if (enc == nrrdEncodingGzip || enc == nrrdEncodingBzip2) { /* nrrd_compressed.c says why */
        if (in_place) nrrd->data = v->data;
        st = vs_nrrd_read_compressed(ctx, path, nrrd, nio);
        if (st != VS_OK) goto done;
    } else { /* a second read, by Teem */
        close_kept(nio);
        nrrdIoStateNix(nio);
        nio = nrrdIoStateNew();
        nrrdNuke(nrrd);
        nrrd = nrrdNew();
        size_t sizes[3] = {(size_t)d[0], (size_t)d[1], (size_t)d[2]};
        if (!nrrd || !nio || (in_place && nrrdWrap_nva(nrrd, v->data, file_type, 3, sizes))) {
            st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
            goto done;
        }
        /* Teem frees a buffer it did not reuse (the sizes changed: the
         * check below says so) and clears nio->oldData, even if it fails
         * afterwards; set here in case it fails before looking. */
        nio->oldData = in_place ? v->data : NULL;
        const int failed = nrrdLoad(nrrd, path, nio);
        if (in_place && nrrd->data != v->data && !nio->oldData) v->data = NULL;
        if (failed) {
            st = teem_error(ctx, VS_ERR_FORMAT, path, "cannot read NRRD");
            goto done;
        }
    }
    /* The file could have changed between the reads; check again. */
    for (unsigned a = 0; a < 3; a++) {
        size_t n = a < nrrd->dim ? nrrd->axis[a].size : 1;
        if ((int64_t)n != d[a] || !nrrd->data || !v->data || nrrd->type != file_type) {
            st = vs_set_error(ctx, VS_ERR_IO, "%s: file changed while reading", path);
            goto done;
        }
    }
    set_orientation(v, nrrd);
    if (!in_place) {
        const size_t n = (size_t)dims[0] * dims[1] * dims[2];
        float *f = v->data;
        for (size_t i = 0; i < n; i++) f[i] = (float)nrrd_value(nrrd->data, file_type, i);
    }
    st = VS_OK;
done:
    close_kept(nio);
    if (nio) nrrdIoStateNix(nio);
    if (nrrd && v && nrrd->data == v->data) nrrd->data = NULL; /* the volume's */
    if (nrrd) nrrdNuke(nrrd);
    if (st != VS_OK) {
        vs_volume_release(v);
        return st;
    }
    *out = v;
    return VS_OK;
}
