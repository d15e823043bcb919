/* Private interface between the volume loader front end (load.c) and the
 * per-format readers (load_*.c).  Every reader sets the context error with a
 * message that starts with the path, and returns the status. */
#ifndef VS_LOAD_H
#define VS_LOAD_H

#include "internal.h"
#include <stdint.h>

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

/* vs_volume_alloc whose error message is prefixed with the path. */
vs_status vs_load_alloc(vs_context *ctx, const char *path, vs_type type, const int dims[3],
                        const double spacing[3], vs_volume **out);

vs_status vs_load_nifti(vs_context *ctx, const char *path, vs_volume **out);
vs_status vs_load_nrrd(vs_context *ctx, const char *path, vs_volume **out);
vs_status vs_load_den(vs_context *ctx, const char *path, vs_volume **out);
vs_status vs_load_raw(vs_context *ctx, const char *path, const int dims[3], vs_type type,
                      vs_endian endian, vs_volume **out);
/* Any single image file read by OpenImageIO; its pages are the z slices. */
vs_status vs_load_image_pages(vs_context *ctx, const char *path, vs_volume **out);
/* A folder of PNG/TIFF slices, in natural numeric order of the names. */
vs_status vs_load_folder(vs_context *ctx, const char *path, vs_volume **out);
/* An uncompressed ustar archive of PNG/TIFF slices, in member order. */
vs_status vs_load_tar(vs_context *ctx, const char *path, vs_volume **out);

#endif
