/* gzip- and bzip2-encoded NRRD data, decoded by vsplat rather than by Teem
 * (nrrd_compressed.c). */
#ifndef VS_NRRD_COMPRESSED_H
#define VS_NRRD_COMPRESSED_H

#include "context.h"

#include <teem/nrrd.h>

/* Fills nrrd->data from the gzip or bzip2 data files of a header read with
 * nrrdIoStateSkipData and nrrdIoStateKeepNrrdDataFileOpen, in the host's
 * byte order: into the buffer it points to (of the header's size; still the
 * caller's), or into one allocated for it if NULL.  VS_OK, or an error
 * naming the path. */
vs_status vs_nrrd_read_compressed(vs_context *ctx, const char *path, Nrrd *nrrd, NrrdIoState *nio);

#endif
