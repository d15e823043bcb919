/*
 * vsplat — image-aligned sheet-buffer splatting without the blur
 * (Mueller, Möller, Crawfis, IEEE Visualization 1999), public C API.
 *
 * Pattern: opaque handles with create/release, a settings struct filled with
 * defaults by vs_settings_init() (which records this header's struct sizes,
 * so settings can grow without breaking programs built against an older
 * header: docs/ABI.md), every call returns a vs_status, and the
 * context keeps a human-readable last-error message.  The library never prints.
 *
 * Threads.  The library has no global mutable state, so:
 *  - separate contexts may be used from separate threads at the same time;
 *  - one context serves one call at a time (it keeps the worker pool, the
 *    relevant-voxel list, the shading tables, the image module and the
 *    last-error message): use one context per thread, or serialise the
 *    calls.  vs_render on a context that is already rendering returns
 *    VS_ERR_BUSY at once (vs_last_error then still describes the other
 *    call); other misuse is not detected;
 *  - a volume may be rendered by several contexts at once: vs_render only
 *    reads it, and every cache keyed on it lives in the rendering context.
 *    Nothing may write into it (vs_volume_data, the buffer of
 *    vs_volume_wrap, vs_volume_update_range) or release it meanwhile;
 *  - a vs_trace serves one vs_render at a time; transfer-function arrays and
 *    images are plain memory, read-only while shared;
 *  - the progress callback runs on the thread that called vs_render, and a
 *    flag it returns may be set by any other thread: returning non-zero
 *    cancels the frame (VS_ERR_CANCELLED) and leaves the context usable.
 * tests/test_concurrency.c checks these promises (and runs under TSan).
 */
#ifndef VSPLAT_H
#define VSPLAT_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define VS_VERSION_MAJOR 0
#define VS_VERSION_MINOR 2
#define VS_VERSION_PATCH 0
#define VS_VERSION_STRING "0.2.0"

/* VS_API marks what libvsplat.so exports: the library is built with hidden
 * visibility, so a declaration without it stays internal (docs/ABI.md). */
#if defined(__GNUC__) && __GNUC__ >= 4
#define VS_API __attribute__((visibility("default")))
#else
#define VS_API
#endif

/* Stable status codes: values never change meaning. */
typedef enum vs_status {
    VS_OK = 0,
    VS_ERR_INVALID_ARGUMENT = 1, /* NULL or inconsistent argument, bad setting */
    VS_ERR_IO = 2,               /* file cannot be opened, read or written */
    VS_ERR_FORMAT = 3,           /* file is truncated, malformed or unsupported */
    VS_ERR_OUT_OF_MEMORY = 4,
    VS_ERR_TOO_LARGE = 5,        /* sizes overflow, exceed VS_MAX_* limits, or need
                                    more memory than the process may take */
    VS_ERR_UNSUPPORTED = 6,      /* valid request this build cannot serve */
    VS_ERR_CANCELLED = 7,        /* the progress callback asked to stop */
    VS_ERR_INTERNAL = 8,
    VS_ERR_BUSY = 9              /* the context is serving another thread's call */
} vs_status;

typedef enum vs_type { VS_U8 = 0, VS_I16 = 1, VS_U16 = 2, VS_F32 = 3 } vs_type;

typedef enum vs_pipeline {
    VS_PIPELINE_PRE = 0,        /* classify + shade voxels, splat RGBA          */
    VS_PIPELINE_POST_CD = 1,    /* splat density, (FH)D central differences     */
    VS_PIPELINE_POST_GS = 2,    /* splat density + gradient splats (FH')        */
    VS_PIPELINE_POST_ALPHA = 3, /* pre-shaded colour, alpha classified on sheet */
    VS_PIPELINE_RAYCAST = 4     /* reference ray caster                         */
} vs_pipeline;

/* Where the camera starts, in the world frame (RAS: +x right, +y anterior,
 * +z superior; docs/DESIGN.md §2).  Each is an (azimuth, elevation) pair
 * that the settings' azimuth and elevation are added to: posterior 0,0
 * (looks along +y, +z up), anterior 180,0, left -90,0 (face to the image's
 * left), right 90,0, superior 0,90 (anterior up), inferior 180,-90
 * (anterior up, the patient's right on the image's left).  VS_VIEW_AUTO,
 * the default, is VS_VIEW_ANTERIOR when the volume has an orientation and
 * azimuth and elevation are both 0 (the front by default), else the angles
 * alone: when turning the angles from the front, say VS_VIEW_ANTERIOR. */
typedef enum vs_view {
    VS_VIEW_AUTO = 0,      /* the front by default, else the angles (above)  */
    VS_VIEW_ANGLES = 1,    /* the angles alone: 0,0 (posterior)              */
    VS_VIEW_ANTERIOR = 2,
    VS_VIEW_POSTERIOR = 3,
    VS_VIEW_LEFT = 4,
    VS_VIEW_RIGHT = 5,
    VS_VIEW_SUPERIOR = 6,
    VS_VIEW_INFERIOR = 7
} vs_view;

typedef enum vs_isa {
    VS_ISA_AUTO = 0, VS_ISA_SCALAR = 1, VS_ISA_SSE4 = 2, VS_ISA_AVX2 = 3, VS_ISA_AVX512 = 4
} vs_isa;

/* Limits that guard against absurd input (allocation never exceeds them). */
#define VS_MAX_DIM 16384
#define VS_MAX_VOXELS ((uint64_t)1 << 32)
#define VS_MAX_IMAGE_DIM 16384

typedef struct vs_context vs_context;
typedef struct vs_volume vs_volume;
typedef struct vs_trace vs_trace;

/* One control point of a piecewise-linear 1-D transfer function: value in
 * data units -> colour (0..1) and opacity per unit length (one voxel). */
typedef struct vs_tf_point {
    double value;
    float r, g, b, a;
} vs_tf_point;

/* Progress callback: fraction in [0,1]; return non-zero to cancel.
 * Always called on the thread that called vs_render(): between the tiles
 * (ray caster: rows) it renders, and every 20 ms while it waits for the
 * other workers' tiles. */
typedef int (*vs_progress_fn)(void *user, double fraction);

/* Fields are only ever appended.  Fill it with vs_settings_init(), never by
 * hand or with = {0}: vs_render refuses a struct_size it does not know. */
typedef struct vs_settings {
    size_t struct_size;        /* sizeof(vs_settings) as this program was built */
    size_t stats_size;         /* sizeof(vs_stats) likewise: vs_render writes
                                  no more of *stats (both set by the init)     */
    vs_pipeline pipeline;
    int width, height;         /* image size in pixels (default 512x512)        */
    double azimuth, elevation; /* degrees, world frame, added to `view`'s angles:
                                  0,0 looks along +y (from behind), +z up; azimuth
                                  turns about +z, elevation looks down from above */
    double zoom;               /* largest physical extent spans zoom*width       */
    int has_center;            /* use center[] (voxel coordinates) if non-zero  */
    double center[3];
    double perspective_fov;    /* 0 = orthographic (default); else perspective with
                                  this vertical field of view in degrees (0..170],
                                  the z = 0 plane through `center` keeping the
                                  orthographic scale                            */

    /* kernel and sheets */
    double slab;               /* sheet thickness Δs in voxel units (default 1) */
    double kernel_radius;      /* radial extent of the Gaussian (default 2)     */
    int footprint_resolution;  /* table entries per kernel-radius unit          */
    int depth_resolution;      /* depth-integral table entries per voxel unit    */
    int seam;                  /* seam layer width in voxels, -1 = auto (ceil R) */

    /* classification: iso-range with ramp, or a piecewise-linear function */
    int has_iso;               /* 0: choose iso from the histogram (Otsu)       */
    double iso_lo, iso_hi;     /* iso_hi = +INFINITY for an open range          */
    double ramp;               /* opacity ramp half-width W, <0 = 2% of range   */
    float iso_opacity;         /* opacity inside the range (default 1)          */
    float material[3];         /* material colour (default white)               */
    const vs_tf_point *tf;     /* if tf_count > 0 it replaces the iso-range     */
    int tf_count;

    /* lighting: one directional light, Phong */
    int headlight;             /* 1: light comes from the eye (default)         */
    double light_dir[3];       /* direction *towards* the light, world space    */
    double ambient, diffuse, specular, shininess;
    float background[4];       /* RGBA, default transparent black               */

    /* leaving out what the scene does not need */
    int occlusion;             /* early splat elimination (default 1)           */
    double occlusion_threshold;/* opacity above which a pixel is occluded       */
    int tile_counters;         /* shade only touched regions (default 1)        */
    int tile_size;             /* parallel tile edge in pixels (default 64)     */
    int exact_normals;         /* 0: Clyne-Dennis LUT normals and shading table
                                  (post-shaded), 16-bit normal codes and their
                                  table (pre-shaded)                            */
    int normal_lut_size;       /* angle bins of the post-shaded shading table
                                  (default 256)                                 */

    /* execution */
    int threads;               /* 0 = one per physical core                      */
    vs_isa isa;                /* cap on the instruction set                     */
    int pin;                   /* bind workers to cores with hwloc (default 1)   */

    /* reference ray caster */
    double ray_step;           /* in voxel units (default 0.1)                   */
    int ray_trilinear;         /* 0: exact Gaussian reconstruction              */
    int ray_analytic;          /* 1: use the scene's analytic function if any    */

    vs_progress_fn progress;
    void *progress_user;

    /* profiling: record the frame's timeline into this trace (vs_trace_create;
     * NULL, the default: nothing is recorded and nothing costs) */
    vs_trace *trace;

    /* the view in the world frame (docs/DESIGN.md §2) */
    vs_view view;              /* starting direction (default VS_VIEW_AUTO)       */
    int has_up;                /* 1: up[] (world) is shown upwards               */
    double up[3];              /* projected onto the image plane; must not lie
                                  along the viewing direction                    */
    double roll;               /* degrees: turns the picture clockwise about its
                                  centre, after `up` (default 0)                 */

    /* sort-last rendering of one part of a volume (vsplat-mpi): with
     * has_crop, only sheet points inside the index box [crop_lo - 0.5,
     * crop_hi - 0.5) on each axis are composited; a face on the volume's
     * own face does not clip.  Voxels outside the box are still splatted,
     * so values near its faces are reconstructed as in the whole volume;
     * boxes that tile the volume partition its points.
     * 0 <= crop_lo < crop_hi <= dims.  Not for the ray caster. */
    int has_crop;
    int crop_lo[3], crop_hi[3];

    /* pre-integrated classification between sheets (post-cd, -gs, -alpha): each
     * pixel's segment from one sheet to the next classified from both
     * densities through a 2-D table.  -1 (default): on with a transfer
     * function or an iso opacity under 1 (translucent classification) or
     * when a coarser level of detail is splatted, off for an opaque
     * iso-range at full resolution; 0 off; 1 on */
    int preintegration;

    /* levels of detail: a volume seen small is splatted from a low-pass
     * filtered copy decimated by 2 per axis, the coarsest whose voxels lie
     * at most lod_pixels apart on the image (along the volume's finest
     * axis; half that for pre and post-alpha, which have no
     * pre-integration), so that a frame costs what its pixels cost.  Under
     * perspective the view is split into depth bands, each splatted from
     * the level its nearest depth allows (stats' lod_level is the nearest
     * band's).  Default 1; 0 renders full resolution.  The
     * levels are built on first use and kept in the context.  Not with a
     * crop box (full resolution there). */
    double lod_pixels;

    /* anisotropic grids (voxels thicker along an axis, by 1.25x or more)
     * splatted from a copy on cubic voxels of the finest spacing, filtered
     * so that it reconstructs the same Gaussian field (and the levels of
     * detail made from it): an ellipsoidal kernel seen obliquely places
     * every sheet's section on its own, a cubic one shares one footprint.
     * Built on first use, kept in the context.  -1 (default): when the
     * copy is at most the volume's size plus 64 MB; 1: whatever its size;
     * 0: never.  Not with a crop box, and not for sheared grids. */
    int resample;

    /* post-cd's differences: 2 the paper's central differences of
     * neighbouring pixels and sheets; 4 the four-point stencil, which reads
     * two pixels (within a sheet) or two sheets (across sheets: plain
     * sheets only, not in depth bands) each side; 0 (default):
     * within a sheet four-point up to 1.4 pixels a voxel, two-point from
     * 1.5, across sheets two-point while sheets lie up to 0.7 pixel's worth
     * of voxels apart (pixels a voxel times the slab), four-point from 1.0;
     * mixed linearly between. */
    int cd_stencil;

    /* the ray caster's Gaussian reconstruction: 0 (default) the kernel's
     * plain sum over the voxels, what splatting approximates; 1 that sum
     * over the kernel's own sum at the same point (weights that sum to 1),
     * which leaves out the lattice ripple the plain sum shows on smooth
     * surfaces and in translucent regions */
    int ray_normalize;

    /* post-gs: 1 (default) the splatted gradient less the value times the
     * kernel's own lattice ripple (the gradient of the normalised sum, as
     * ray_normalize's), which leaves out the grid the lattice draws on
     * smooth surfaces; 0 the plain gradient splats of the paper */
    int gs_normalize;
} vs_settings;

typedef struct vs_stage_times {
    double setup, rasterize, gradient, shade, composite;
} vs_stage_times;

/* Bytes a stage reads or writes by construction (what its loops touch,
 * counted from the work counts; caches not modelled). */
typedef struct vs_stage_bytes {
    uint64_t rasterize, gradient, shade, composite;
} vs_stage_bytes;

typedef struct vs_stats {
    size_t struct_size;        /* bytes vs_render wrote: the settings' stats_size */
    const char *pipeline;      /* static strings, valid forever                  */
    const char *isa;
    int threads;
    int width, height;
    uint64_t voxels_total;     /* voxels in the volume                           */
    uint64_t voxels_relevant;  /* in range plus seam                             */
    uint64_t voxels_splatted;  /* voxel-sheet rasterizations performed           */
    uint64_t voxels_culled;    /* voxel-sheet rasterizations skipped (occlusion) */
    uint64_t sheets;           /* sheets composited (summed over tiles)          */
    uint64_t tiles_total;      /* tile-sheets considered                         */
    uint64_t tiles_shaded;     /* tile-sheets gradient-estimated and shaded      */
    double ms_total;           /* wall clock of vs_render                        */
    vs_stage_times ms_stage;   /* summed over threads                            */
    double ms_relevant;        /* building the relevant-voxel list (if rebuilt)  */
    double iso_lo, iso_hi, ramp; /* classification actually used                 */
    int pin_warning;           /* 1 if binding workers to cores failed           */

    /* work counts, summed over tiles and threads: what each stage did, so
     * that its time compares across machines and versions */
    uint64_t bricks_culled;    /* bricks culled whole by the occlusion map       */
    uint64_t voxels_projected; /* voxel-tile transforms (a voxel once per tile)  */
    uint64_t voxels_tested;    /* occlusion tests of voxels                      */
    uint64_t footprint_floats; /* floats added into sheet buffers (rasterize)    */
    uint64_t pixels_classified;/* sheet pixels classified (gradient)             */
    uint64_t pixels_shaded;    /* of those, with opacity: shaded and composited  */
    vs_stage_bytes bytes_read, bytes_written;

    /* with lod_level > 0, voxels_relevant and the counts after it are the
     * level's; voxels_total is the volume's */
    double ms_lod;             /* building levels of detail, or patching them for
                                  a new classification (if either was done)      */
    int lod_level;             /* level splatted: 0 full resolution, L: voxels
                                  2^L times the volume's spacing apart        */
    double ms_resample;        /* resampling to cubic voxels (if it was done)   */
    int resampled;             /* 1: the cubic copy (or a level of detail made
                                  from it) was splatted (settings' resample);
                                  voxels_total is the volume's               */
} vs_stats;

/* A rendered image: straight RGBA float, row 0 at the top. */
typedef struct vs_image {
    int width, height;
    float *rgba; /* width*height*4, owned by the caller: free with vs_image_free */
} vs_image;

/* ---- context ---- */
VS_API vs_status vs_context_create(vs_context **out);
VS_API void vs_context_release(vs_context *ctx);
VS_API const char *vs_last_error(const vs_context *ctx); /* never NULL */
VS_API const char *vs_status_string(vs_status s);
VS_API const char *vs_version(void);

/* Defaults for every setting.  Call it as vs_settings_init(&s): the macro
 * passes this header's sizes, and the library writes at most struct_size
 * bytes, so a program built against an older (shorter) vs_settings gets
 * nothing written past its struct. */
VS_API void vs_settings_init_sized(vs_settings *s, size_t struct_size, size_t stats_size);
#define vs_settings_init(s) vs_settings_init_sized((s), sizeof(vs_settings), sizeof(vs_stats))
VS_API const char *vs_pipeline_name(vs_pipeline p);
VS_API vs_status vs_pipeline_parse(const char *name, vs_pipeline *out);
VS_API const char *vs_isa_name(vs_isa isa);
VS_API vs_status vs_isa_parse(const char *name, vs_isa *out);
/* "anterior", "posterior", "left", "right", "superior", "inferior" (any case) */
VS_API vs_status vs_view_parse(const char *name, vs_view *out);
/* best ISA this CPU and OS support */
VS_API vs_isa vs_isa_detect(void);

/* ---- volumes ---- */
typedef enum vs_endian { VS_ENDIAN_LITTLE = 0, VS_ENDIAN_BIG = 1 } vs_endian;

/* Options for headerless raw input (and spacing override for any format). */
typedef struct vs_load_options {
    size_t struct_size;       /* sizeof(vs_load_options): set by the init   */
    int raw;                  /* 1: treat the file as headerless raw            */
    int dims[3];
    vs_type type;
    vs_endian endian;
    int has_spacing;
    double spacing[3];
    /* DICOM: which series of a folder holding several, by SeriesInstanceUID
     * or 1-based number in the list the error gives; NULL: the only one */
    const char *series;
} vs_load_options;
/* Defaults; call it as vs_load_options_init(&o) (same scheme as the settings). */
VS_API void vs_load_options_init_sized(vs_load_options *o, size_t struct_size);
#define vs_load_options_init(o) vs_load_options_init_sized((o), sizeof(vs_load_options))

/* Formats: .nii/.nii.gz (nifticlib), .nrrd/.nhdr (Teem), .mha/.mhd (ITK
 * MetaImage), DICOM series (a folder or one of its files; GDCM module),
 * .tif/.tiff stacks, folders and .tar of PNG slices (OpenImageIO), .den
 * (VolPack), raw (+gzip). */
VS_API vs_status vs_volume_load(vs_context *ctx, const char *path, const vs_load_options *opt,
                                vs_volume **out);
/* Part of a volume file, for programs that split a volume too big for one
 * process (vsplat-mpi: each rank reads its brick).  vs_volume_file_dims:
 * the file's dimensions from its header.  vs_volume_load_box: only the
 * voxels lo[a] <= i < hi[a] of each axis, as vs_volume_load gives them
 * (type, spacing, options), the transform moved to the box's first voxel,
 * the value range the box's own.  Raw (+gzip) and NIfTI (.nii, .nii.gz,
 * .hdr/.img): a compressed file is decompressed up to the box's end, never
 * held whole.  Other formats: VS_ERR_UNSUPPORTED (load them whole); a box
 * empty or outside the volume: VS_ERR_INVALID_ARGUMENT. */
VS_API vs_status vs_volume_file_dims(vs_context *ctx, const char *path, const vs_load_options *opt, int dims[3]);
VS_API vs_status vs_volume_load_box(vs_context *ctx, const char *path, const vs_load_options *opt, const int lo[3],
                                    const int hi[3], vs_volume **out);
/* Synthetic scenes: cube, sphere, ml[:N], head, cell (optionally NAME:N). */
VS_API vs_status vs_volume_scene(vs_context *ctx, const char *spec, vs_volume **out);
VS_API vs_status vs_volume_create(vs_context *ctx, vs_type type, const int dims[3],
                                  const double spacing[3], vs_volume **out);
/* A volume over memory the caller owns, without a copy: `data` holds
 * dims[0]*dims[1]*dims[2] voxels of `type`, x fastest, then y, then z,
 * aligned to the voxel size.  strides_bytes (NULL: contiguous) must be the
 * contiguous ones, {size, size*dims[0], size*dims[0]*dims[1]} (an axis of
 * extent 1 may have any stride): other layouts are VS_ERR_UNSUPPORTED, as
 * the renderer reads the voxels as one dense array; copy them first.  The
 * value range is computed here: after writing into the buffer call
 * vs_volume_update_range.  The buffer must stay valid and unchanged while
 * a frame renders it.  vs_volume_release calls release(release_user, data)
 * exactly once (release may be NULL); on failure nothing is called and the
 * buffer stays the caller's. */
typedef void (*vs_release_fn)(void *user, void *data);
VS_API vs_status vs_volume_wrap(vs_context *ctx, vs_type type, const int dims[3], const size_t strides_bytes[3],
                                const double spacing[3], void *data, vs_release_fn release, void *release_user,
                                vs_volume **out);
VS_API void vs_volume_release(vs_volume *v);
VS_API void *vs_volume_data(vs_volume *v); /* x fastest, then y, then z */
VS_API void vs_volume_dims(const vs_volume *v, int dims[3]);
VS_API void vs_volume_spacing(const vs_volume *v, double spacing[3]);
VS_API vs_type vs_volume_type(const vs_volume *v);
/* Index-to-world transform, millimetres, world axes RAS (+x right,
 * +y anterior, +z superior): m is a row-major 3x4 matrix, world =
 * m[0..2] * (i,j,k) + m[3].  Returns 1 when the file gave an orientation, 0
 * when it is assumed (diag(spacing): raw data, image stacks, scenes). */
VS_API int vs_volume_affine(const vs_volume *v, double m[12]);
/* Give a volume its index-to-world transform (same layout as above; RAS
 * millimetres): a volume built in memory, or a brick cut from an oriented
 * one (its translation moved to the brick's first voxel).  The spacing
 * becomes the column lengths.  VS_ERR_INVALID_ARGUMENT for a zero, non-finite
 * or singular matrix (the volume is left as it was). */
VS_API vs_status vs_volume_set_transform(vs_context *ctx, vs_volume *v, const double m[12]);
VS_API const char *vs_type_name(vs_type t);
/* Recompute the value range after writing into vs_volume_data(). */
VS_API void vs_volume_update_range(vs_volume *v);
/* Declare the value range, lo <= hi, finite: a brick cut from a larger
 * volume classifies with the whole volume's range (the transfer-function
 * tables span it).  VS_ERR_INVALID_ARGUMENT otherwise. */
VS_API vs_status vs_volume_set_range(vs_volume *v, double lo, double hi);
VS_API void vs_volume_range(const vs_volume *v, double *lo, double *hi);
/* Otsu threshold of the value histogram: a default iso-value. */
VS_API double vs_volume_default_iso(const vs_volume *v);
/* The histogram behind it, for a volume split into bricks: each brick,
 * given the whole range (vs_volume_set_range), adds its finite values'
 * counts in VS_HISTOGRAM_BINS bins over that range into hist; on the sum,
 * vs_histogram_iso(hist, lo, hi) is the whole volume's default iso. */
#define VS_HISTOGRAM_BINS 256
VS_API void vs_volume_histogram(const vs_volume *v, double hist[VS_HISTOGRAM_BINS]);
VS_API double vs_histogram_iso(const double hist[VS_HISTOGRAM_BINS], double lo, double hi);
VS_API int vs_volume_has_analytic(const vs_volume *v);

/* Where the camera of these settings looks from, in the volume's index
 * coordinates: dir, the viewing direction (index units per view unit of
 * depth), and for a perspective view eye, the eye point (NAN otherwise).
 * For programs that order parts of a volume by visibility (vsplat-mpi).
 * Returns the settings' error as vs_render would. */
VS_API vs_status vs_view_in_index(vs_context *ctx, const vs_volume *vol, const vs_settings *s, double dir[3],
                                  double eye[3]);

/* ---- transfer-function files ---- */
/* Read a transfer function into a malloc'ed array of piecewise-linear
 * control points (free with vs_tf_free), ready for vs_settings.tf/tf_count.
 * Format from the extension (else sniffed from the content):
 *  .json  ParaView colour-map preset: an array of presets (the first is
 *         used) or one object.  "RGBPoints" [x,r,g,b,...] gives the colour
 *         (interpolated in RGB whatever "ColorSpace" says); "Points"
 *         [x,opacity,midpoint,sharpness,...] the opacity, shaped as
 *         vtkPiecewiseFunction does; without "Points" opacity rises linearly
 *         from 0 at the first RGB point to 1 at the last.  x is in data
 *         units, not rescaled.  ParaView's per-sample opacity is taken as
 *         vsplat's opacity per unit length (one voxel) directly.
 *  .1dt   ImageVis3D: entry count N, then N lines "r g b a" in [0,1].  It has
 *         no value axis: entry i is placed at vmin + i*(vmax-vmin)/(N-1) of
 *         the volume's value range, so it needs vs_tf_load_for_volume.
 *  .vtf   vsplat text: '#' comments; lines "iso LO HI R G B A RAMP" (an
 *         iso-range with the --iso/--ramp opacity rule, peak opacity A, HI
 *         may be inf; ranges must not overlap) or "point V R G B A".
 * Colours and opacities must lie in [0,1] and x must not decrease; anything
 * malformed is VS_ERR_FORMAT with a message naming the file and the line
 * (or JSON element).  At most 65536 points; files up to 16 MiB.
 * vs_tf_load is vs_tf_load_for_volume with vol = NULL (.1dt then fails). */
VS_API vs_status vs_tf_load(vs_context *ctx, const char *path, vs_tf_point **points, int *count);
VS_API vs_status vs_tf_load_for_volume(vs_context *ctx, const char *path, const vs_volume *vol,
                                       vs_tf_point **points, int *count);
VS_API void vs_tf_free(vs_tf_point *points);

/* ---- rendering ---- */
/* Reads s->struct_size bytes of the settings (newer fields keep their
 * defaults) and, on success, writes s->stats_size bytes of *stats (may be
 * NULL).  A struct_size or stats_size this library does not know (settings
 * never initialised, or from a newer header) is VS_ERR_INVALID_ARGUMENT. */
VS_API vs_status vs_render(vs_context *ctx, const vs_volume *vol, const vs_settings *s,
                           vs_image *out, vs_stats *stats);
VS_API void vs_image_free(vs_image *img);

/* ---- images (OpenImageIO) ---- */
/* Format from the extension: .png (8-bit, or 16-bit with bits=16), .exr
 * (float), .tif/.tiff.  Written to a temporary name and renamed. */
VS_API vs_status vs_image_write(vs_context *ctx, const char *path, const vs_image *img, int bits);
VS_API vs_status vs_image_read(vs_context *ctx, const char *path, vs_image *out);

/* Several images of one size as one file: an animated GIF (.gif: 8-bit,
 * composited over black because GIF has no partial transparency, fps frames
 * per second, looping forever) or a multi-page TIFF (.tif/.tiff, 8-bit
 * RGBA).  Written to a temporary name and renamed, like vs_image_write. */
VS_API vs_status vs_image_write_frames(vs_context *ctx, const char *path, const vs_image *frames, int count,
                                       double fps);

typedef struct vs_image_diff {
    double rmse, psnr, ssim, max_abs;
} vs_image_diff;
/* Over all four channels; psnr is +INFINITY for identical images. */
VS_API vs_status vs_image_compare(vs_context *ctx, const vs_image *a, const vs_image *b,
                                  vs_image_diff *out);

/* ---- profiling ---- */
/* A timeline of frames: set vs_settings.trace to a trace and every vs_render
 * with those settings appends its spans (the frame's serial parts on thread
 * 0, the calling thread; per worker, each tile and inside it each stage of
 * each sheet).  vs_trace_write saves them as Chrome Trace Event JSON, which
 * Perfetto (ui.perfetto.dev) and chrome://tracing open.  A trace serves one
 * vs_render at a time. */
VS_API vs_status vs_trace_create(vs_trace **out);
VS_API void vs_trace_release(vs_trace *t);
VS_API size_t vs_trace_spans(const vs_trace *t); /* spans recorded so far */
VS_API vs_status vs_trace_write(vs_context *ctx, const vs_trace *t, const char *path);

/* Stats as JSON into buf, like snprintf: returns the bytes needed.  Writes
 * the fields st->struct_size covers; a size this library does not know
 * gives "" and 0.  NULL st gives every field as zero. */
VS_API size_t vs_stats_to_json(const vs_stats *st, char *buf, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
