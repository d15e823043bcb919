/* VolPack / Levoy ".den" density files: a 62-byte header of int16 fields
 * (map_version, orig/extr/map min/max/len triples, map_warps) and an int32
 * map_length, then map_len[0]*map_len[1]*map_len[2] u8 voxels, x fastest.
 * Files are little-endian; a header whose version only reads as 1 when
 * byte-swapped (old big-endian machines) is accepted too.  No spacing is
 * stored, so it is 1,1,1 unless the caller overrides it. */
#include "context.h"
#include "load.h"
#include "load_common.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

enum { DEN_HEADER = 62, DEN_MAP_LEN = 50, DEN_MAP_LENGTH = 58 };

static unsigned rd16(const unsigned char *p, int big)
{
    return big ? (unsigned)p[0] << 8 | p[1] : (unsigned)p[1] << 8 | p[0];
}

static uint32_t rd32(const unsigned char *p, int big)
{
    return big ? (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]
               : (uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0];
}

vs_status vs_load_den(vs_context *ctx, const char *path, vs_volume **out)
{
    uint64_t fsize;
    vs_status st = vs_load_file_size(ctx, path, &fsize);
    if (st != VS_OK) return st;
    if (fsize == 0) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: empty file", path);
    if (fsize < DEN_HEADER)
        return vs_set_error(ctx, VS_ERR_FORMAT,
                            "%s: truncated: the .den header needs %d bytes, file has %llu", path,
                            DEN_HEADER, (unsigned long long)fsize);
    FILE *f = fopen(path, "rb");
    if (!f) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    unsigned char h[DEN_HEADER];
    if (fread(h, 1, DEN_HEADER, f) != DEN_HEADER) {
        fclose(f);
        return vs_set_error(ctx, VS_ERR_IO, "%s: cannot read the header", path);
    }
    int big = 0;
    if (rd16(h, 0) != 1) {
        if (rd16(h, 1) == 1) big = 1;
        else {
            fclose(f);
            return vs_set_error(ctx, VS_ERR_FORMAT,
                                "%s: not a VolPack .den file: map_version is %u, expected 1", path,
                                rd16(h, 0));
        }
    }
    /* int16 in VolPack, but negative sizes mean nothing: read as unsigned so
     * a corrupt header reports the size it claims. */
    int64_t d[3];
    for (int a = 0; a < 3; a++) d[a] = rd16(h + DEN_MAP_LEN + 2 * a, big);
    uint64_t need;
    st = vs_load_check_dims(ctx, path, d, 1, &need);
    if (st != VS_OK) {
        fclose(f);
        return st;
    }
    uint32_t map_length = rd32(h + DEN_MAP_LENGTH, big);
    if (map_length != need) {
        fclose(f);
        return vs_set_error(ctx, VS_ERR_FORMAT,
                            "%s: header map_length %lu does not match dimensions %lldx%lldx%lld",
                            path, (unsigned long)map_length, (long long)d[0], (long long)d[1],
                            (long long)d[2]);
    }
    uint64_t have = fsize - DEN_HEADER;
    if (have < need) {
        fclose(f);
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: truncated: expected %llu bytes, file has %llu",
                            path, (unsigned long long)(need + DEN_HEADER),
                            (unsigned long long)fsize);
    }
    if (have > need) {
        fclose(f);
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: has %llu extra bytes after %llu voxels", path,
                            (unsigned long long)(have - need), (unsigned long long)need);
    }
    int dims[3] = {(int)d[0], (int)d[1], (int)d[2]};
    vs_volume *v;
    st = vs_load_alloc(ctx, path, VS_U8, dims, NULL, &v);
    if (st != VS_OK) {
        fclose(f);
        return st;
    }
    size_t got = fread(v->data, 1, (size_t)need, f);
    fclose(f);
    if (got != need) {
        vs_volume_release(v);
        return vs_set_error(ctx, VS_ERR_IO, "%s: read %llu of %llu voxel bytes", path,
                            (unsigned long long)got, (unsigned long long)need);
    }
    *out = v;
    return VS_OK;
}
