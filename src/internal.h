/* Internal interfaces shared by the library's files.  Not installed. */
#ifndef VS_INTERNAL_H
#define VS_INTERNAL_H

#include "vsplat.h"
#include <math.h>
#include <stdarg.h>
#include <stdint.h>

/* ---- volumes ---- */

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
    uint64_t serial;     /* unique per allocation and per vs_volume_update_range:
                            what caches key on (an address can be reused, and
                            data rewritten in place keeps it) */
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
/* What a splat is weighted by: the value at linear index i, non-finite
 * values read as 0 (empty space). */
static inline float vs_volume_density(const struct vs_volume *v, size_t i)
{
    double x = vs_volume_at(v, i);
    return isfinite(x) ? (float)x : 0.0f;
}
/* Central-difference gradient on the grid at voxel (i, j, k), linear index
 * idx, in index units (one-sided at the borders; non-finite results 0):
 * what the pre-shaded pipelines shade a voxel by. */
static inline void vs_volume_grid_gradient(const struct vs_volume *v, int i, int j, int k, size_t idx, float g[3])
{
    const int p[3] = {i, j, k};
    const int *d = v->dims;
    const size_t st[3] = {1, (size_t)d[0], (size_t)d[0] * d[1]};
    for (int a = 0; a < 3; a++) {
        int lo = p[a] > 0 ? 1 : 0, hi = p[a] < d[a] - 1 ? 1 : 0;
        double gr = 0.0;
        if (lo + hi > 0) {
            double fh = vs_volume_at(v, idx + hi * st[a]);
            double fl = vs_volume_at(v, idx - lo * st[a]);
            gr = (fh - fl) / (lo + hi);
            if (!isfinite(gr)) gr = 0.0;
        }
        g[a] = (float)gr;
    }
}
/* Allocate a volume with checked sizes; data zeroed. Sets ctx error. */
vs_status vs_volume_alloc(vs_context *ctx, vs_type type, const int dims[3],
                          const double spacing[3], struct vs_volume **out);

/* ---- context ---- */
struct vs_pool;
struct vs_relevant_cache;
struct vs_shade_lut;
struct vs_context {
    char error[512];
    struct vs_pool *pool;       /* created lazily, reused across frames        */
    int pool_threads;
    int pool_pin;
    struct vs_relevant_cache *relevant; /* relevant-voxel list, reused          */
    uint64_t otsu_serial;               /* default iso (Otsu) of the volume with
                                           this serial (0: none): a full pass
                                           over the volume, once, not per frame */
    double otsu_iso;
    struct vs_shade_lut *shade_lut;     /* normal and shading tables, rebuilt
                                           only when their size or the light
                                           changes (a headlight never does) */
    const struct vs_oiio_api *oiio;     /* image I/O module, loaded on first use */
    void *oiio_handle;                  /* its dlopen handle                     */
};

/* Set the last-error message (printf-style); returns status for chaining. */
vs_status vs_set_error(vs_context *ctx, vs_status st, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* ---- camera (DESIGN.md §2) ---- */
/* World space: physical units (mm), volume centred at the origin, voxel i at
 * (i - (n-1)/2) * spacing.  View space: x right and y down in pixels, z along
 * the viewing direction in "view units" (the smallest voxel spacing). */
typedef struct vs_camera {
    int width, height;
    double right[3], up[3], dir[3]; /* world-space unit vectors               */
    double px_per_mm;               /* pixels per world unit                  */
    double z_per_mm;                /* view units per world unit              */
    double center_world[3];         /* world point at the image centre        */
    /* index -> view: v = M * idx + t  (x,y pixels, z view units)            */
    double M[3][3], t[3];
    double Minv[3][3];              /* view -> index (for ray casting)        */
    double unit_mm;                 /* one view unit in mm (smallest spacing) */
    /* Perspective (settings.perspective_fov > 0): the eye sits persp_dz view
     * units in front of the z = 0 plane (through the image centre's world
     * point), where the scale is the orthographic one.  A point at depth z
     * appears scaled by s(z) = persp_dz / (persp_dz + z) about the image
     * centre; sheets stay planes of constant z, parallel to the image.
     * Nothing nearer than near_z is drawn.  Orthographic: persp = 0, s = 1,
     * near_z = -INFINITY. */
    int persp;
    double persp_dz;                /* eye distance from z = 0 (view units)   */
    double focal_px;                /* focal length in pixels                 */
    double near_z;                  /* near clipping plane (view units)       */
    double cx, cy;                  /* image centre (pixels)                  */
} vs_camera;

vs_status vs_camera_setup(vs_context *ctx, const struct vs_volume *vol,
                          const vs_settings *s, vs_camera *cam);
/* index -> view before the perspective divide: x, y are where the point
 * would appear at depth 0 (its image position when orthographic), z the
 * depth in view units. */
void vs_camera_index_to_view0(const vs_camera *cam, const double idx[3], double v[3]);
/* view (x, y in image pixels after the perspective divide, depth z) ->
 * index; with perspective only for z > near_z. */
void vs_camera_view_to_index(const vs_camera *cam, const double v[3], double idx[3]);
/* Image scale at depth z relative to z = 0 (1 for orthographic). */
static inline double vs_camera_scale(const vs_camera *cam, double z)
{
    return cam->persp ? cam->persp_dz / (cam->persp_dz + z) : 1.0;
}
/* Scale of sheet k (slabs of thickness `slab`): at its slab's middle depth,
 * held at the near plane's for sheets before it.  Every sheet-level use of
 * the scale (section placement, tables, gradients) takes it from here. */
static inline double vs_camera_sheet_scale(const vs_camera *cam, int k, double slab)
{
    const double z = (k + 0.5) * slab;
    return vs_camera_scale(cam, z > cam->near_z ? z : cam->near_z);
}
/* The image box (x0, x1, y0, y1) covered by points whose depth-0 position
 * lies in [xo0, xo1] x [yo0, yo1] at depths in [z0, z1] (z0 >= near_z). */
static inline void vs_camera_depth_box(const vs_camera *cam, double xo0, double xo1, double yo0, double yo1,
                                       double z0, double z1, double box[4])
{
    box[0] = xo0, box[1] = xo1, box[2] = yo0, box[3] = yo1;
    if (!cam->persp) return;
    /* linear in the position for a fixed scale and in the scale for a fixed
     * position: the extremes lie at the corners */
    const double sn = vs_camera_scale(cam, z0), sf = vs_camera_scale(cam, z1);
    const double c[2] = {cam->cx, cam->cy}, lo[2] = {xo0, yo0}, hi[2] = {xo1, yo1};
    for (int a = 0; a < 2; a++) {
        double p[4] = {c[a] + (lo[a] - c[a]) * sn, c[a] + (lo[a] - c[a]) * sf, c[a] + (hi[a] - c[a]) * sn,
                       c[a] + (hi[a] - c[a]) * sf};
        double mn = p[0], mx = p[0];
        for (int i = 1; i < 4; i++) {
            if (p[i] < mn) mn = p[i];
            if (p[i] > mx) mx = p[i];
        }
        box[2 * a] = mn;
        box[2 * a + 1] = mx;
    }
}
/* The ray through image pixel (x, y) in index space: the point at depth z is
 * org + z dir. */
void vs_camera_ray(const vs_camera *cam, double x, double y, double org[3], double dir[3]);
/* Perspective: length of the ray through pixel (x, y) per unit of depth
 * (1 for orthographic), for opacity correction. */
static inline double vs_camera_ray_length(const vs_camera *cam, double x, double y)
{
    if (!cam->persp) return 1.0;
    double u = (x - cam->cx) / cam->focal_px, v = (y - cam->cy) / cam->focal_px;
    return sqrt(1.0 + u * u + v * v);
}

/* ---- classification (transfer function) ---- */
#define VS_TF_TABLE 4096
typedef struct vs_classify {
    double lo, hi, ramp;   /* iso-range in use (hi may be +INF)               */
    double vmin, vmax;     /* domain of the table                             */
    double scale;          /* (VS_TF_TABLE-1)/(vmax-vmin)                     */
    float color[VS_TF_TABLE][3];
    float alpha[VS_TF_TABLE]; /* opacity per view unit                        */
    double alpha_lo, alpha_hi; /* values outside which alpha is 0: relevant range */
    int use_points;        /* piecewise-linear function given                 */
} vs_classify;

/* Build from settings and the volume (iso from histogram if not given). */
vs_status vs_classify_setup(vs_context *ctx, const struct vs_volume *vol,
                            const vs_settings *s, vs_classify *c);
/* Exact evaluation (no table): opacity per unit length and colour. */
void vs_classify_eval(const vs_classify *c, const vs_settings *s, double value,
                      float rgb[3], float *alpha);
/* Table lookup (linear interpolation; clamps outside the domain). */
static inline float vs_classify_alpha(const vs_classify *c, float value)
{
    float x = (float)((value - c->vmin) * c->scale);
    if (!(x > 0.0f)) x = 0.0f; /* also catches NaN */
    if (x >= (float)(VS_TF_TABLE - 1)) return c->alpha[VS_TF_TABLE - 1];
    int i = (int)x;
    float f = x - (float)i;
    return c->alpha[i] + f * (c->alpha[i + 1] - c->alpha[i]);
}
/* Opacity for a sample of length `len` view units: 1-(1-a)^len. */
static inline double vs_opacity_correct(double a, double len)
{
    if (a <= 0.0) return 0.0;
    if (a >= 1.0) return 1.0;
    return 1.0 - pow(1.0 - a, len);
}

/* ---- lighting (shared by every pipeline and the ray caster) ---- */
/* Normals and light live in the eye frame: e1 = right, e2 = down (-up),
 * e3 = viewing direction; orthonormal in world units. */
typedef struct vs_light {
    double L[3];   /* unit vector towards the light, eye frame              */
    double H[3];   /* Blinn half vector between L and the eye                */
    double ka, kd, ks, n;
} vs_light;
void vs_light_setup(const vs_settings *s, const vs_camera *cam, vs_light *l);
/* Phong terms for a normal in the eye frame (right, down, forward; any
 * length).  Two-sided: a normal facing away from the eye is flipped.  A zero
 * normal is treated as facing the eye, so homogeneous regions are defined.
 * colour = material * (*diffuse) + (*specular). */
void vs_light_eval(const vs_light *l, const double n[3], double *diffuse, double *specular);

/* ---- kernel (Gaussian h(r) = b 2^(-2 r^2), truncated at radius R) ---- */
double vs_kernel_b(double radius);  /* normalizing constant */

/* ---- ray caster ---- */
vs_status vs_raycast_render(vs_context *ctx, const struct vs_volume *vol,
                            const vs_settings *s, vs_image *out, vs_stats *st);

/* ---- timing ---- */
double vs_now_ms(void);

#endif
