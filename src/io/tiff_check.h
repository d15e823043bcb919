/* TIFF strips and tiles against the size of the file (tiff_check.c). */
#ifndef VS_TIFF_CHECK_H
#define VS_TIFF_CHECK_H

#include "context.h"

#include <stddef.h>

/* If the file `path` (or, when mem is not NULL, the `size` bytes at mem,
 * named `path` in messages) is a TIFF: VS_OK when every strip or tile of
 * every page lies inside it, else VS_ERR_FORMAT with a message ("...:
 * truncated: page P strip S ...").  Anything else (not a TIFF, an
 * unreadable directory) is left to the image reader: VS_OK. */
vs_status vs_tiff_check(vs_context *ctx, const char *path, const void *mem, size_t size);

#endif
