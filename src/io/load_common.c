/* What every volume reader shares: file sizes, name checks, size limits
 * and allocation with the path in the error message (load_common.h). */
#include "context.h"
#include "load_common.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

vs_status vs_load_file_size(vs_context *ctx, const char *path, uint64_t *size)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    if (S_ISDIR(st.st_mode))
        return vs_set_error(ctx, VS_ERR_IO, "%s: is a folder, expected a file", path);
    if (!S_ISREG(st.st_mode))
        return vs_set_error(ctx, VS_ERR_IO, "%s: not a regular file", path);
    *size = (uint64_t)st.st_size;
    return VS_OK;
}

int vs_load_ends_with(const char *path, const char *suffix)
{
    size_t n = strlen(path), m = strlen(suffix);
    if (m > n) return 0;
    for (size_t i = 0; i < m; i++)
        if (tolower((unsigned char)path[n - m + i]) != tolower((unsigned char)suffix[i])) return 0;
    return 1;
}

vs_status vs_load_check_dims(vs_context *ctx, const char *path, const int64_t dims[3], size_t elem,
                             uint64_t *bytes)
{
    for (int a = 0; a < 3; a++)
        if (dims[a] < 1 || dims[a] > VS_MAX_DIM)
            return vs_set_error(ctx, dims[a] < 1 ? VS_ERR_FORMAT : VS_ERR_TOO_LARGE,
                                "%s: dimensions %lldx%lldx%lld: each must be 1..%d", path,
                                (long long)dims[0], (long long)dims[1], (long long)dims[2],
                                VS_MAX_DIM);
    uint64_t n = (uint64_t)dims[0] * (uint64_t)dims[1] * (uint64_t)dims[2];
    if (n > VS_MAX_VOXELS)
        return vs_set_error(ctx, VS_ERR_TOO_LARGE, "%s: %llu voxels exceed the limit of %llu", path,
                            (unsigned long long)n, (unsigned long long)VS_MAX_VOXELS);
    if (bytes) *bytes = n * (uint64_t)elem;
    return VS_OK;
}

uint64_t vs_load_inflate_bound(uint64_t compressed)
{
    return compressed * 1040u + 65536u;
}

vs_status vs_load_alloc(vs_context *ctx, const char *path, vs_type type, const int dims[3],
                        const double spacing[3], vs_volume **out)
{
    vs_status st = vs_volume_alloc(ctx, type, dims, spacing, out);
    if (st != VS_OK && ctx) {
        char msg[sizeof ctx->error];
        memcpy(msg, ctx->error, sizeof msg);
        msg[sizeof msg - 1] = '\0';
        vs_set_error(ctx, st, "%s: %s", path, msg);
    }
    return st;
}

uint64_t vs_load_gzread(gzFile gz, void *dst, uint64_t n)
{
    unsigned char *p = dst;
    uint64_t got = 0;
    while (got < n) {
        const uint64_t left = n - got;
        const int r = gzread(gz, p + got, left > (1u << 26) ? 1u << 26 : (unsigned)left);
        if (r <= 0) break;
        got += (uint64_t)r;
    }
    return got;
}

void vs_load_swap_bytes(void *data, size_t n, size_t elem)
{
    unsigned char *p = data;
    if (elem == 2) {
        for (size_t i = 0; i < n; i++, p += 2) {
            const unsigned char t = p[0];
            p[0] = p[1];
            p[1] = t;
        }
        return;
    }
    for (size_t i = 0; i < n; i++, p += elem)
        for (size_t a = 0, b = elem - 1; a < b; a++, b--) {
            const unsigned char t = p[a];
            p[a] = p[b];
            p[b] = t;
        }
}

vs_status vs_load_check_box(vs_context *ctx, const char *path, const vs_load_box *box, const int dims[3])
{
    for (int a = 0; a < 3; a++)
        if (box->lo[a] < 0 || box->hi[a] > dims[a] || box->lo[a] >= box->hi[a])
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                                "%s: box %d-%d,%d-%d,%d-%d is empty or outside the volume's %dx%dx%d voxels", path,
                                box->lo[0], box->hi[0], box->lo[1], box->hi[1], box->lo[2], box->hi[2], dims[0],
                                dims[1], dims[2]);
    return VS_OK;
}

vs_status vs_load_read_box(vs_context *ctx, const char *path, const char *file, uint64_t offset,
                           const int dims[3], size_t elem, const vs_load_box *box, void *dst)
{
    gzFile gz = gzopen(file, "rb");
    if (!gz) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", file, strerror(errno));
    gzbuffer(gz, 1 << 18);
    /* an uncompressed file is read with pread: zlib would refill its whole
     * buffer for every row */
    int fd = -1;
    if (gzdirect(gz)) {
        gzclose(gz);
        gz = NULL;
        if ((fd = open(file, O_RDONLY)) < 0)
            return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", file, strerror(errno));
    }
    const int *lo = box->lo, *hi = box->hi;
    /* the longest runs that are contiguous in the file: rows, or whole
     * slices when the box spans x, or everything when it spans x and y */
    uint64_t run = (uint64_t)(hi[0] - lo[0]) * elem;
    int rows = hi[1] - lo[1], per_slice = 1;
    if (lo[0] == 0 && hi[0] == dims[0]) {
        run *= (uint64_t)rows;
        per_slice = 0;
    }
    unsigned char *p = dst;
    vs_status st = VS_OK;
    for (int k = lo[2]; k < hi[2] && st == VS_OK; k++)
        for (int j = lo[1]; j < (per_slice ? hi[1] : lo[1] + 1) && st == VS_OK; j++) {
            const uint64_t at = offset + (((uint64_t)k * (uint64_t)dims[1] + (uint64_t)j) * (uint64_t)dims[0] +
                                          (uint64_t)lo[0]) * elem;
            uint64_t got = 0;
            if (fd >= 0)
                while (got < run) {
                    ssize_t r = pread(fd, p + got, (size_t)(run - got), (off_t)(at + got));
                    if (r <= 0) break;
                    got += (uint64_t)r;
                }
            else if (gzseek(gz, (z_off_t)at, SEEK_SET) == (z_off_t)at)
                got = vs_load_gzread(gz, p, run);
            if (got < run) {
                int zerr = Z_OK;
                const char *msg = gz ? gzerror(gz, &zerr) : "";
                const int bad = zerr != Z_OK && zerr != Z_BUF_ERROR;
                st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: truncated: no %llu bytes of voxel data at offset %llu%s%s%s",
                                  path, (unsigned long long)run, (unsigned long long)at, bad ? " (gzip: " : "",
                                  bad ? msg : "", bad ? ")" : "");
            }
            p += run;
        }
    if (gz) gzclose(gz);
    else close(fd);
    return st;
}
