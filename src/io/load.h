/* The per-format readers (load_*.c) as the loader front end (load.c)
 * calls them.  Every reader sets the context error with a message that
 * starts with the path, and returns the status; what they share is
 * load_common.h's, so no reader depends on the front end. */
#ifndef VS_LOAD_H
#define VS_LOAD_H

#include "load_common.h"
#include "volume.h"
#include <stdint.h>

/* box (NULL: the whole volume): read only its part, or only the dims
 * (load_common.h); the two formats that can be read in part. */
vs_status vs_load_nifti(vs_context *ctx, const char *path, vs_load_box *box, vs_volume **out);
vs_status vs_load_nrrd(vs_context *ctx, const char *path, vs_volume **out);
vs_status vs_load_den(vs_context *ctx, const char *path, vs_volume **out);
vs_status vs_load_raw(vs_context *ctx, const char *path, const int dims[3], vs_type type,
                      vs_endian endian, vs_load_box *box, vs_volume **out);
/* Any single image file read by OpenImageIO; its pages are the z slices. */
vs_status vs_load_image_pages(vs_context *ctx, const char *path, vs_volume **out);
/* A folder of PNG/TIFF slices, in natural numeric order of the names. */
vs_status vs_load_folder(vs_context *ctx, const char *path, vs_volume **out);
/* A DICOM series: a folder, or one file of it (its series is read from its
 * folder); `series` picks one of several by UID or 1-based number (NULL:
 * the folder must hold one).  Needs the GDCM module. */
vs_status vs_load_dicom(vs_context *ctx, const char *path, const char *series, vs_volume **out);
/* The file starts like DICOM (with or without the 128-byte preamble). */
int vs_dicom_sniff(const char *path);
/* The folder holds at least one file that starts like DICOM. */
int vs_dicom_folder(const char *dir);
/* ITK MetaImage: .mha (header and data) or .mhd (data in ElementDataFile). */
vs_status vs_load_metaimage(vs_context *ctx, const char *path, vs_volume **out);
/* An uncompressed ustar archive of PNG/TIFF slices, in member order. */
vs_status vs_load_tar(vs_context *ctx, const char *path, vs_volume **out);

#endif
