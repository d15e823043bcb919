/* What the volume readers (load_*.c) share (load_common.c). */
#ifndef VS_LOAD_COMMON_H
#define VS_LOAD_COMMON_H

#include "volume.h"

#include <stdint.h>
#include <zlib.h>

/* Size of a regular file; rejects missing files, folders, FIFOs and devices
 * (reading those could hang). */
vs_status vs_load_file_size(vs_context *ctx, const char *path, uint64_t *size);
/* Case-insensitive "path ends with suffix". */
int vs_load_ends_with(const char *path, const char *suffix);
/* Checks dims against VS_MAX_DIM/VS_MAX_VOXELS; *bytes = voxels * elem. */
vs_status vs_load_check_dims(vs_context *ctx, const char *path, const int64_t dims[3],
                             size_t elem, uint64_t *bytes);
/* Largest plausible inflated size of `compressed` bytes of gzip/deflate
 * (deflate cannot exceed about 1032:1), to refuse absurd headers early. */
uint64_t vs_load_inflate_bound(uint64_t compressed);

/* Reads up to n bytes from gz into dst, in pieces gzread can take (its
 * count is unsigned); returns the bytes read (fewer: end of data or error,
 * gzerror says which). */
uint64_t vs_load_gzread(gzFile gz, void *dst, uint64_t n);

/* Part of a volume file: voxels lo[a] <= i < hi[a] on each axis; a reader
 * given one reads only those voxels (vs_volume_load_box).  dims_only: read
 * the header, set dims, make no volume. */
typedef struct vs_load_box {
    int lo[3], hi[3];
    int dims_only;
    int dims[3]; /* out: the whole file's dimensions */
} vs_load_box;
/* Checks the box against the file's dims (empty or outside: an error). */
vs_status vs_load_check_box(vs_context *ctx, const char *path, const vs_load_box *box, const int dims[3]);
/* Reads box's voxels of a dims-sized array of elem-byte voxels (x fastest)
 * stored from byte `offset` of `file` (plain or gzip: zlib reads both,
 * seeking forward through a compressed one) into dst, box-sized, x fastest.
 * A short file is "truncated"; path names the volume in messages. */
vs_status vs_load_read_box(vs_context *ctx, const char *path, const char *file, uint64_t offset,
                           const int dims[3], size_t elem, const vs_load_box *box, void *dst);

/* Reverses the byte order of n elements of elem bytes, in place. */
void vs_load_swap_bytes(void *data, size_t n, size_t elem);

/* vs_volume_alloc whose error message is prefixed with the path. */
vs_status vs_load_alloc(vs_context *ctx, const char *path, vs_type type, const int dims[3],
                        const double spacing[3], vs_volume **out);

#endif
