/* Volumes over memory the caller owns (vs_volume_wrap): checked like an
 * allocated volume, never copied, handed back through the release callback.
 * Only the dense x-fastest layout is taken: every reader of the voxels
 * (relevant.c, activate.c, raycast.c, volume.h) indexes them as one array. */
#include "volume.h"
#include "context.h"

#include <stdint.h>

vs_status vs_volume_wrap(vs_context *ctx, vs_type type, const int dims[3], const size_t strides_bytes[3],
                         const double spacing[3], void *data, vs_release_fn release, void *release_user,
                         vs_volume **out)
{
    if (!out) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "vs_volume_wrap: NULL output");
    *out = NULL;
    if (!dims || !data) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "vs_volume_wrap: NULL dims or data");
    struct vs_volume *v;
    vs_status st = vs_volume_alloc_shell(ctx, type, dims, spacing, &v);
    if (st != VS_OK) return st;
    const size_t size = vs_type_size(type);
    if ((uintptr_t)data % size != 0) {
        vs_volume_release(v);
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                            "vs_volume_wrap: data at %p is not aligned to its %zu-byte voxels", data, size);
    }
    if (strides_bytes) {
        const size_t want[3] = {size, size * (size_t)dims[0], size * (size_t)dims[0] * (size_t)dims[1]};
        for (int a = 0; a < 3; a++)
            if (dims[a] > 1 && strides_bytes[a] != want[a]) {
                vs_volume_release(v);
                return vs_set_error(ctx, VS_ERR_UNSUPPORTED,
                                    "vs_volume_wrap: strides %zu,%zu,%zu bytes are not the dense x-fastest "
                                    "layout %zu,%zu,%zu; copy the voxels into that layout first",
                                    strides_bytes[0], strides_bytes[1], strides_bytes[2], want[0], want[1],
                                    want[2]);
            }
    }
    v->data = data;
    v->wrapped = 1;
    v->release = release;
    v->release_user = release_user;
    vs_volume_update_range(v); /* the range, and a fresh serial for the caches */
    *out = v;
    return VS_OK;
}
