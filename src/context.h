/* The context: the caches a renderer keeps between calls, and the
 * last-error message every call reports into (error.c). */
#ifndef VS_CONTEXT_H
#define VS_CONTEXT_H

#include "vsplat.h"
#include <stdatomic.h>
#include <stdint.h>

/* pre-integration tables kept, one per slab thickness */
#define VS_PREINT_KEEP 3

struct vs_pool;
struct vs_relevant_cache;
struct vs_lod_cache;
struct vs_resample_cache;
struct vs_shade_lut;
struct vs_normal_table;
struct vs_normal_codes;
struct vs_context {
    char error[1024]; /* room for a list of the series in a DICOM folder */
    struct vs_pool *pool;       /* created lazily, reused across frames        */
    int pool_threads;
    int pool_pin;
    struct vs_relevant_cache *relevant; /* relevant-voxel list, reused          */
    struct vs_lod_cache *lod;           /* levels of detail of the last volume  */
    struct vs_resample_cache *resample; /* its copy on cubic voxels, if anisotropic */
    uint64_t otsu_serial;               /* default iso (Otsu) of the volume with
                                           this serial (0: none): a full pass
                                           over the volume, once, not per frame */
    double otsu_iso;
    struct vs_shade_lut *shade_lut;     /* normal and shading tables, rebuilt
                                           only when their size or the light
                                           changes (a headlight never does) */
    struct vs_normal_table *normal_table; /* pre-shaded voxels' Phong terms per
                                           normal code, rebuilt when the view
                                           or the light changes */
    struct vs_normal_codes *normal_codes; /* VS_NORMAL_CODES_KEEP volumes' voxel
                                           normal codes */
    uint64_t normal_codes_clock;
    struct vs_preint *preint[VS_PREINT_KEEP]; /* pre-integration tables, one
                                           per slab in use (the depth bands of a
                                           perspective view splat up to three
                                           levels a frame), rebuilt only when the
                                           classification changes */
    int preint_next;                    /* the table a new slab replaces */
    struct vs_tile_scratch *scratch;    /* per worker, reused across frames       */
    int nscratch;
    const struct vs_oiio_api *oiio;     /* image I/O module, loaded on first use */
    void *oiio_handle;                  /* its dlopen handle                     */
    const struct vs_dicom_api *dicom;   /* DICOM module (GDCM), on first use     */
    void *dicom_handle;
    atomic_int busy;                    /* 1 while vs_render runs: a second
                                           thread's vs_render gets VS_ERR_BUSY
                                           instead of racing on the caches */
};

/* Free the workers' tile scratch (src/tile.c). */
void vs_tile_scratch_release(struct vs_tile_scratch *s, int n);

/* Set the last-error message (printf-style); returns status for chaining. */
vs_status vs_set_error(vs_context *ctx, vs_status st, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

#endif
