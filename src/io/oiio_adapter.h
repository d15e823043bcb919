/* C interface to the OpenImageIO adapter (src/io/oiio_adapter.cpp), the only C++
 * in the project.  The adapter is a loadable module (vsplat-oiio.so), not
 * part of libvsplat: OpenImageIO pulls in some 260 shared libraries (OpenCV,
 * FFmpeg, GStreamer, ...) that cost 130 MB of resident memory and 0.15 s at
 * every start, which a program that only renders volumes should not pay.
 * The library reaches the entry points below through the table vs_oiio(ctx)
 * loads on a context's first image I/O (src/io/oiio_module.c); calling them
 * directly from the library would not link.  Every entry catches exceptions and reports a status plus a
 * message (which names the file) in the caller's buffer, so the C side never
 * sees C++ and the adapter never touches a vs_context. */
#ifndef VS_OIIO_ADAPTER_H
#define VS_OIIO_ADAPTER_H

#include "vsplat.h"
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Sample types the adapter reads into. */
typedef enum vs_pixel_type {
    VS_PIX_U8 = 0,
    VS_PIX_I16 = 1,
    VS_PIX_U16 = 2,
    VS_PIX_F32 = 3,
    VS_PIX_OTHER = 4 /* native type not one of the above (int8, uint32, ...) */
} vs_pixel_type;

/* What a page (subimage) holds, and the metadata the stack loader needs. */
typedef struct vs_oiio_info {
    int width, height, channels;
    vs_pixel_type native;    /* file's sample type; half and double -> F32 */
    int has_resolution;      /* XResolution/YResolution present and > 0 */
    double xres, yres;       /* pixels per unit */
    char description[2048];  /* ImageDescription (truncated), "" if none */
} vs_oiio_info;

typedef struct vs_oiio_reader vs_oiio_reader;

/* Open an image file (mem == NULL) or an in-memory encoded image (mem/size;
 * `name` then only picks the decoder by extension and names it in errors). */
vs_status vs_oiio_open(const char *name, const void *mem, size_t size,
                       vs_oiio_reader **out, char *err, size_t errcap);
void vs_oiio_close(vs_oiio_reader *r);
/* Number of subimages (pages), counted up to `cap` (so it never runs long). */
vs_status vs_oiio_count_pages(vs_oiio_reader *r, int cap, int *count, char *err, size_t errcap);
vs_status vs_oiio_page_info(vs_oiio_reader *r, int page, vs_oiio_info *info,
                            char *err, size_t errcap);
/* Read all channels of one page, interleaved, as `type` (U8/I16/U16 need the
 * file's native type to match; F32 from any type keeps float values as they
 * are).  dst must hold width*height*channels samples (checked). */
vs_status vs_oiio_read_page(vs_oiio_reader *r, int page, vs_pixel_type type, void *dst,
                            size_t dst_bytes, char *err, size_t errcap);

/* Read a whole image as straight (unassociated) RGBA float: gray is spread
 * to RGB, a missing alpha becomes 1.  *rgba is malloc'ed (free()). */
vs_status vs_oiio_read_rgba(const char *path, int *width, int *height, float **rgba,
                            char *err, size_t errcap);
/* Write straight RGBA float.  Format from the extension: .png (8-bit, 16 when
 * bits == 16), .exr (float, half when bits == 16; stored premultiplied as the
 * format expects), .tif/.tiff (8/16-bit when bits is 8/16, else float).
 * Written to a temporary name in the same folder and renamed; on failure no
 * file is left behind. */
vs_status vs_oiio_write_rgba(const char *path, int width, int height, const float *rgba,
                             int bits, char *err, size_t errcap);

/* Write `pages` single- or multi-channel pages of one size and sample type
 * (U8/U16/F32) as one file: a multi-page TIFF, or one page of any format.
 * xres/yres > 0 are stored as resolution; description (may be NULL) as
 * ImageDescription.  Same temporary-file-and-rename rule as above. */
vs_status vs_oiio_write_pages(const char *path, int width, int height, int channels,
                              int pages, vs_pixel_type type, const void *data,
                              double xres, double yres, const char *description,
                              char *err, size_t errcap);

/* Write `count` frames of straight RGBA float (width*height*4 each) as one
 * multi-image file: an animated GIF (.gif: 8-bit RGB composited over black,
 * as GIF has no partial transparency; FramesPerSecond = fps, looping
 * forever) or a multi-page TIFF (.tif/.tiff: 8-bit straight RGBA).  One
 * frame at a time is converted.  Same temporary-file-and-rename rule. */
vs_status vs_oiio_write_frames(const char *path, int width, int height, int count,
                               const float *const *frames, double fps, char *err, size_t errcap);

/* The module's entry points as one table: what vs_oiio_module_api(), the
 * module's only looked-up symbol, returns. */
typedef struct vs_oiio_api {
    vs_status (*open)(const char *name, const void *mem, size_t size, vs_oiio_reader **out, char *err,
                      size_t errcap);
    void (*close)(vs_oiio_reader *r);
    vs_status (*count_pages)(vs_oiio_reader *r, int cap, int *count, char *err, size_t errcap);
    vs_status (*page_info)(vs_oiio_reader *r, int page, vs_oiio_info *info, char *err, size_t errcap);
    vs_status (*read_page)(vs_oiio_reader *r, int page, vs_pixel_type type, void *dst, size_t dst_bytes, char *err,
                           size_t errcap);
    vs_status (*read_rgba)(const char *path, int *width, int *height, float **rgba, char *err, size_t errcap);
    vs_status (*write_rgba)(const char *path, int width, int height, const float *rgba, int bits, char *err,
                            size_t errcap);
    vs_status (*write_pages)(const char *path, int width, int height, int channels, int pages, vs_pixel_type type,
                             const void *data, double xres, double yres, const char *description, char *err,
                             size_t errcap);
    vs_status (*write_frames)(const char *path, int width, int height, int count, const float *const *frames,
                              double fps, char *err, size_t errcap);
} vs_oiio_api;

#define VS_OIIO_MODULE_NAME "vsplat-oiio.so"
#define VS_OIIO_MODULE_ENTRY "vs_oiio_module_api"
#define VS_OIIO_MODULE_ENV "VSPLAT_OIIO_MODULE"
const vs_oiio_api *vs_oiio_module_api(void);

/* The table for this context, loading the module on first use; NULL (and
 * the context's error says why and where it looked) if it cannot be loaded.
 * Search: $VSPLAT_OIIO_MODULE if set (that file only), else vsplat-modules/
 * next to the binary holding libvsplat's code, one or two folders up
 * (build tree: tests/, bench/, tests/fuzz/), under ../LIBDIR (installed
 * bin/), then the installed library folder. */
struct vs_context;
const vs_oiio_api *vs_oiio(struct vs_context *ctx);

#ifdef __cplusplus
}
#endif
#endif
