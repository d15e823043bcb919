/* Volumes inside the library: the voxels, their value range, and the
 * analytic function of a synthetic scene (the ray caster's ground truth). */
#ifndef VS_VOLUME_H
#define VS_VOLUME_H

#include "vsplat.h"
#include <math.h>
#include <stddef.h>
#include <stdint.h>

/* An analytic scene definition: f and its gradient at a point given in
 * voxel-index coordinates (continuous; voxel i sits at index i).  Used by the
 * reference ray caster as ground truth.  `params` points into the volume. */
typedef struct vs_analytic {
    double (*f)(const void *params, const double p[3]);
    void (*grad)(const void *params, const double p[3], double g[3]);
    double iso;          /* the scene's natural iso-value                    */
    double params[64];   /* scene parameters, copied with the volume         */
} vs_analytic;

struct vs_volume {
    vs_type type;
    int dims[3];
    double spacing[3];
    double vmin, vmax;   /* value range (finite values)                       */
    void *data;          /* dims[0]*dims[1]*dims[2] elements, x fastest        */
    int has_analytic;
    vs_analytic analytic;
    double default_iso;  /* scene's iso; NAN if none                          */
    double default_ramp; /* scene's ramp; NAN if none                         */
    /* Index to world: world = affine[0..2][0..2] * (i,j,k) + affine[.][3], in
     * millimetres, world axes RAS (+x right, +y anterior, +z superior), rows
     * of a 3x4 matrix.  Without orientation (raw, image stacks, scenes) it is
     * diag(spacing) with has_orientation 0.  spacing[a] is always the norm of
     * column a. */
    double affine[3][4];
    int has_orientation;
    uint64_t serial;     /* unique per allocation and per vs_volume_update_range:
                            what caches key on (an address can be reused, and
                            data rewritten in place keeps it) */
    uint64_t data_serial; /* the same, but kept by vs_volume_set_range: what
                             depends on the voxels alone (levels of detail) */
    /* who frees data: the library (wrapped 0) or the caller's release
     * callback (vs_volume_wrap, src/volume_wrap.c) */
    int wrapped;
    vs_release_fn release;
    void *release_user;
};

size_t vs_type_size(vs_type t);
/* Value of voxel at linear index i as double. */
static inline double vs_volume_at(const struct vs_volume *v, size_t i)
{
    switch (v->type) {
    case VS_U8: return ((const uint8_t *)v->data)[i];
    case VS_I16: return ((const int16_t *)v->data)[i];
    case VS_U16: return ((const uint16_t *)v->data)[i];
    default: return ((const float *)v->data)[i];
    }
}
/* The value less base, as splatted (non-finite values read as base). */
static inline float vs_volume_density_above(const struct vs_volume *v, size_t i, double base)
{
    double x = vs_volume_at(v, i);
    return isfinite(x) ? (float)(x - base) : 0.0f;
}
/* The value at linear index i, non-finite values read as 0 (what
 * pre-shaded splatting classifies them as). */
static inline float vs_volume_density(const struct vs_volume *v, size_t i) { return vs_volume_density_above(v, i, 0.0); }
/* The smallest of the three spacings (mm): the view unit of depth and
 * what opacity is per. */
static inline double vs_volume_finest(const struct vs_volume *v)
{
    double m = v->spacing[0];
    for (int a = 1; a < 3; a++)
        if (v->spacing[a] < m) m = v->spacing[a];
    return m;
}
/* Set the index-to-world (RAS, mm) transform from a loader; the spacing
 * becomes its column norms.  VS_ERR_INVALID_ARGUMENT (volume unchanged) if a
 * column is zero, not finite or the matrix is singular. */
vs_status vs_volume_set_affine(vs_context *ctx, struct vs_volume *v, const double m[3][4]);
/* A volume with checked sizes and no data yet (vs_volume_wrap): data NULL.
 * Sets ctx error. */
vs_status vs_volume_alloc_shell(vs_context *ctx, vs_type type, const int dims[3],
                                const double spacing[3], struct vs_volume **out);
/* What sampled reconstructions read outside the volume (and for
 * non-finite values): its minimum when that is below 0 (CT's air, -1000 HU
 * or the scanner's padding), else 0; so the faces of a CT volume draw no
 * surface at an iso-value between air and 0.  0 also for a constant
 * volume (it would have no faces) and for ranges that float cannot hold
 * shifted.  Post-classified splatting and the ray caster reconstruct the
 * values less this and add it back. */
double vs_volume_base(const struct vs_volume *v);
/* Allocate a volume with checked sizes; data zeroed. Sets ctx error. */
vs_status vs_volume_alloc(vs_context *ctx, vs_type type, const int dims[3],
                          const double spacing[3], struct vs_volume **out);

/* Store n floats from linear index `at` on: rounded to nearest and
 * saturated for the integer types (filtered copies: levels, resampling). */
void vs_volume_store_floats(struct vs_volume *v, size_t at, const float *x, int n);

/* Index coordinate c along axis a of `from` as an index along axis a of
 * `to`, a copy of it placed with the same axis directions (a level of
 * detail, the copy on cubic voxels): through both transforms. */
double vs_volume_index_in(const struct vs_volume *from, const struct vs_volume *to, int a, double c);

/* out[i] = w x[i] (first) or out[i] += w x[i] for the n voxels from linear
 * index `at`, as float; a non-finite value reads as `base` (filtered
 * copies: levels, resampling). */
void vs_volume_axpy_floats(const struct vs_volume *v, size_t at, size_t n, float w, float base, int first, float *out);

/* A filtered copy (a level, the copy on cubic voxels) takes its volume's
 * range and default classification: the classification is the same. */
void vs_volume_share_classification(struct vs_volume *copy, const struct vs_volume *v);

/* What a filtered copy of a volume (its levels, its copy on cubic voxels)
 * was made from, so that its cache knows what changed since: new voxels
 * or spacing (made anew), a new range (the same voxels, classified anew),
 * a new transform (the same voxels, placed anew). */
typedef struct vs_volume_stamp {
    const struct vs_volume *vol;
    uint64_t serial, data_serial;
    double spacing[3], affine[3][4];
    int has_orientation;
    double base; /* vs_volume_base: what copies read outside and for non-finite voxels */
} vs_volume_stamp;
void vs_volume_stamp_take(vs_volume_stamp *st, const struct vs_volume *v);
/* The same volume, voxels, spacing and value outside (vs_volume_base,
 * which a declared range can move): what a copy made from the voxels
 * (levels, the cubic copy, normal codes) depends on. */
int vs_volume_stamp_same_field(const vs_volume_stamp *st, const struct vs_volume *v);
/* The same transform and orientation. */
int vs_volume_stamp_same_place(const vs_volume_stamp *st, const struct vs_volume *v);

#endif
