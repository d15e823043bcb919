/* C interface to the DICOM adapter (src/io/dicom_adapter.cpp), GDCM in a
 * loadable module (vsplat-dicom.so) of its own, beside the image module:
 * GDCM is C++, and a user without it keeps every other format.  The module
 * reads one file at a time (its header, or its decoded pixels); the series
 * logic (grouping, sorting by position, spacing, rescale, orientation) is C,
 * in src/io/load_dicom.c.  Every entry catches exceptions and reports a status
 * plus a message in the caller's buffer; GDCM's own messages are silenced, as
 * the library never prints. */
#ifndef VS_DICOM_ADAPTER_H
#define VS_DICOM_ADAPTER_H

#include "vsplat.h"
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Stored sample types the adapter decodes to (native byte order). */
typedef enum vs_dicom_sample {
    VS_DCM_U8 = 0,
    VS_DCM_I8 = 1,
    VS_DCM_U16 = 2,
    VS_DCM_I16 = 3,
    VS_DCM_U32 = 4,
    VS_DCM_I32 = 5,
    VS_DCM_OTHER = 6
} vs_dicom_sample;

/* The attributes of one file that the series reader needs.  A missing
 * attribute leaves its has_ flag 0 (strings empty). */
typedef struct vs_dicom_header {
    int rows, cols;             /* (0028,0010), (0028,0011)                      */
    int frames;                 /* (0028,0008), 1 when absent                   */
    int samples;                /* (0028,0002), 1 when absent                   */
    int bits_allocated;         /* (0028,0100)                                  */
    int pixel_representation;   /* (0028,0103): 0 unsigned, 1 signed            */
    int has_pixel_data;         /* (7FE0,0010) present                          */
    int has_position, has_orientation, has_pixel_spacing, has_thickness;
    double position[3];         /* ImagePositionPatient (LPS, mm)               */
    double orientation[6];      /* ImageOrientationPatient: row then column dir */
    double pixel_spacing[2];    /* PixelSpacing: between rows, between columns  */
    double thickness;           /* SliceThickness                               */
    double slope, intercept;    /* RescaleSlope/Intercept (1 and 0 if absent)   */
    int instance;               /* InstanceNumber, 0 if absent                  */
    char series_uid[72];        /* SeriesInstanceUID                            */
    char description[72];       /* SeriesDescription (truncated)                */
    char modality[20];
    char photometric[20];       /* PhotometricInterpretation                    */
    char transfer_syntax[72];   /* "" for files without a meta header           */
} vs_dicom_header;

/* The module's entry points as one table: what vs_dicom_module_api(), the
 * module's only exported symbol, returns. */
typedef struct vs_dicom_api {
    /* Parse a file up to its pixel data.  VS_ERR_FORMAT if it is not DICOM
     * or cannot be parsed (err says why). */
    vs_status (*read_header)(const char *path, vs_dicom_header *h, char *err, size_t errcap);
    /* Decode the pixel data of a single-frame, one-sample file (compressed
     * transfer syntaxes as far as GDCM decodes them) into dst, rows*cols
     * samples of *type, columns fastest.  dst_bytes is checked. */
    vs_status (*read_pixels)(const char *path, int rows, int cols, void *dst, size_t dst_bytes,
                             vs_dicom_sample *type, char *err, size_t errcap);
} vs_dicom_api;

#define VS_DICOM_MODULE_NAME "vsplat-dicom.so"
#define VS_DICOM_MODULE_ENTRY "vs_dicom_module_api"
#define VS_DICOM_MODULE_ENV "VSPLAT_DICOM_MODULE"
const vs_dicom_api *vs_dicom_module_api(void);

/* The table for this context, loading the module on first use (searched as
 * the image module is, src/io/module.c); NULL with the context's error set
 * when it cannot be loaded. */
struct vs_context;
const vs_dicom_api *vs_dicom(struct vs_context *ctx);

#ifdef __cplusplus
}
#endif
#endif
