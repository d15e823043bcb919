/* What every volume reader shares: file sizes, name checks, size limits
 * and allocation with the path in the error message (load_common.h). */
#include "context.h"
#include "load_common.h"

#include <ctype.h>
#include <errno.h>
#include <string.h>
#include <sys/stat.h>

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

