/* NRRD header lines that Teem 1.12 leaks on or mishandles, refused before
 * Teem reads the file (nrrd_header_check.c). */
#ifndef VS_NRRD_HEADER_CHECK_H
#define VS_NRRD_HEADER_CHECK_H

#include "context.h"

/* VS_OK, or VS_ERR_FORMAT/VS_ERR_IO with a message naming the path. */
vs_status vs_nrrd_header_check(vs_context *ctx, const char *path);

#endif
