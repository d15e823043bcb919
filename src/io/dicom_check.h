/* DICOM elements whose stated length runs past the end of the file,
 * refused before GDCM reads it (dicom_check.c). */
#ifndef VS_DICOM_CHECK_H
#define VS_DICOM_CHECK_H

#include "context.h"

/* VS_OK, or VS_ERR_FORMAT/VS_ERR_IO with a message naming the path. */
vs_status vs_dicom_check(vs_context *ctx, const char *path);

#endif
