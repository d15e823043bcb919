/* Headerless raw volumes, plain or gzip-compressed (detected by the 1f 8b
 * magic, whatever the name).  Dimensions, type and byte order come from the
 * caller.  The data must be exactly the expected size: short files are
 * "truncated", longer ones report their extra bytes; both are errors, since
 * a size mismatch almost always means wrong dimensions or type. */
#include "context.h"
#include "load.h"
#include "load_common.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

static vs_status read_plain(vs_context *ctx, const char *path, uint64_t fsize, uint64_t need,
                            void *dst)
{
    if (fsize < need)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: truncated: expected %llu bytes, file has %llu",
                            path, (unsigned long long)need, (unsigned long long)fsize);
    if (fsize > need)
        return vs_set_error(ctx, VS_ERR_FORMAT,
                            "%s: has %llu extra bytes (expected %llu bytes, file has %llu): "
                            "check dimensions and type",
                            path, (unsigned long long)(fsize - need), (unsigned long long)need,
                            (unsigned long long)fsize);
    FILE *f = fopen(path, "rb");
    if (!f) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    size_t got = fread(dst, 1, (size_t)need, f);
    fclose(f);
    if (got != need)
        return vs_set_error(ctx, VS_ERR_IO, "%s: read %llu of %llu bytes", path,
                            (unsigned long long)got, (unsigned long long)need);
    return VS_OK;
}

static vs_status read_gz(vs_context *ctx, const char *path, uint64_t need, void *dst)
{
    gzFile gz = gzopen(path, "rb");
    if (!gz) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    gzbuffer(gz, 1 << 18);
    const uint64_t got = vs_load_gzread(gz, dst, need);
    if (got < need) {
        int zerr = Z_OK;
        const char *msg = gzerror(gz, &zerr);
        vs_status st = vs_set_error(
            ctx, VS_ERR_FORMAT, "%s: truncated: expected %llu bytes, decompressed %llu%s%s%s", path,
            (unsigned long long)need, (unsigned long long)got, zerr != Z_OK ? " (gzip: " : "",
            zerr != Z_OK ? msg : "", zerr != Z_OK ? ")" : "");
        gzclose(gz);
        return st;
    }
    /* Count what follows, bounded, so the message says how much is extra. */
    unsigned char buf[65536];
    uint64_t extra = 0;
    const uint64_t extra_cap = (uint64_t)1 << 30;
    int r;
    while (extra < extra_cap && (r = gzread(gz, buf, sizeof buf)) > 0) extra += (uint64_t)r;
    int zerr = Z_OK;
    const char *msg = gzerror(gz, &zerr);
    vs_status st = VS_OK;
    if (extra > 0)
        st = vs_set_error(ctx, VS_ERR_FORMAT,
                          "%s: has %s%llu extra bytes after the expected %llu: check dimensions "
                          "and type",
                          path, extra >= extra_cap ? "at least " : "", (unsigned long long)extra,
                          (unsigned long long)need);
    else if (zerr != Z_OK && zerr != Z_BUF_ERROR)
        st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: corrupt gzip data: %s", path, msg);
    gzclose(gz);
    return st;
}

vs_status vs_load_raw(vs_context *ctx, const char *path, const int dims[3], vs_type type,
                      vs_endian endian, vs_load_box *box, vs_volume **out)
{
    size_t elem = vs_type_size(type);
    if (elem == 0)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "%s: unknown raw voxel type %d", path,
                            (int)type);
    if (endian != VS_ENDIAN_LITTLE && endian != VS_ENDIAN_BIG)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "%s: unknown byte order %d", path,
                            (int)endian);
    int64_t d[3] = {dims[0], dims[1], dims[2]};
    uint64_t need;
    vs_status st = vs_load_check_dims(ctx, path, d, elem, &need);
    if (st != VS_OK) return st;
    uint64_t fsize;
    st = vs_load_file_size(ctx, path, &fsize);
    if (st != VS_OK) return st;
    if (fsize == 0) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: empty file", path);

    unsigned char magic[2] = {0, 0};
    FILE *f = fopen(path, "rb");
    if (!f) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    size_t m = fread(magic, 1, 2, f);
    fclose(f);
    int gz = m == 2 && magic[0] == 0x1f && magic[1] == 0x8b;

    /* Refuse before allocating when the file cannot possibly hold the data. */
    if (gz && need > vs_load_inflate_bound(fsize))
        return vs_set_error(ctx, VS_ERR_FORMAT,
                            "%s: truncated: expected %llu bytes, more than a gzip file of %llu "
                            "bytes can hold",
                            path, (unsigned long long)need, (unsigned long long)fsize);
    if (!gz && fsize < need)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: truncated: expected %llu bytes, file has %llu",
                            path, (unsigned long long)need, (unsigned long long)fsize);
    if (!gz && fsize > need) return read_plain(ctx, path, fsize, need, NULL);

    int idims[3] = {dims[0], dims[1], dims[2]};
    if (box) {
        memcpy(box->dims, idims, sizeof box->dims);
        if (box->dims_only) return VS_OK;
        if ((st = vs_load_check_box(ctx, path, box, idims)) != VS_OK) return st;
        for (int a = 0; a < 3; a++) idims[a] = box->hi[a] - box->lo[a];
        need = (uint64_t)idims[0] * (uint64_t)idims[1] * (uint64_t)idims[2] * elem;
    }
    vs_volume *v;
    st = vs_load_alloc(ctx, path, type, idims, NULL, &v);
    if (st != VS_OK) return st;
    st = box  ? vs_load_read_box(ctx, path, path, 0, dims, elem, box, v->data)
         : gz ? read_gz(ctx, path, need, v->data)
              : read_plain(ctx, path, fsize, need, v->data);
    if (st != VS_OK) {
        vs_volume_release(v);
        return st;
    }
    const uint16_t one = 1;
    vs_endian host = *(const unsigned char *)&one ? VS_ENDIAN_LITTLE : VS_ENDIAN_BIG;
    if (endian != host && elem > 1) vs_load_swap_bytes(v->data, (size_t)(need / elem), elem);
    *out = v;
    return VS_OK;
}
