/* bzip2-encoded NRRD data, decoded by vsplat rather than by Teem
 * (nrrd_bzip2.c). */
#ifndef VS_NRRD_BZIP2_H
#define VS_NRRD_BZIP2_H

#include "context.h"

#include <teem/nrrd.h>

/* Fills nrrd->data (NULL on entry) from the data files of a header read
 * with nrrdIoStateSkipData and nrrdIoStateKeepNrrdDataFileOpen, in the
 * host's byte order.  VS_OK, or an error naming the path. */
vs_status vs_nrrd_read_bzip2(vs_context *ctx, const char *path, Nrrd *nrrd, NrrdIoState *nio);

#endif
