/* The DICOM module's calls in a child process, so that a malformed file
 * which trips an assertion inside GDCM is an error, not the end of the
 * program (src/io/dicom_guard.c).  Files are handled in order; on failure
 * *failed is the index of the file err speaks of. */
#ifndef VS_DICOM_GUARD_H
#define VS_DICOM_GUARD_H

#include "dicom_adapter.h"

/* Receives slice i's decoded pixels (rows*cols samples of `type`). */
typedef void (*vs_dicom_sink)(void *user, int i, const void *pixels, vs_dicom_sample type);

/* The headers of paths[0..n-1] into out[0..n-1]. */
vs_status vs_dicom_headers_guarded(const vs_dicom_api *api, char *const *paths, int n, vs_dicom_header *out,
                                   int *failed, char *err, size_t errcap);
/* The pixels of paths[0..n-1], each rows x cols (at most `bytes`), handed
 * to take() one file at a time. */
vs_status vs_dicom_pixels_guarded(const vs_dicom_api *api, char *const *paths, int n, int rows, int cols,
                                  size_t bytes, vs_dicom_sink take, void *user, int *failed, char *err,
                                  size_t errcap);

#endif
