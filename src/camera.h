/* The camera: world, index and view spaces, orthographic or perspective. */
#ifndef VS_CAMERA_H
#define VS_CAMERA_H

#include "volume.h"
#include <math.h>

/* World space: RAS millimetres (+x right, +y anterior, +z superior) through
 * the volume's index-to-world transform (vol->affine; diag(spacing) for a
 * volume without orientation).  The camera is set up there and carried into
 * the volume's "grid frame": millimetres along the index axes, g = spacing *
 * index, centred on the volume.  View space: x right and y down in pixels, z
 * along the viewing direction in "view units" (the smallest voxel spacing). */
typedef struct vs_camera {
    int width, height;
    /* The image axes as seen by a grid-frame gradient: the eye-frame normal
     * of a gradient g (per index step) is (gw.right, -gw.up, gw.dir) with gw
     * = g / spacing.  Orthonormal unless the transform is sheared. */
    double right[3], up[3], dir[3];
    double wright[3], wup[3], wdir[3]; /* the same in world space (unit)      */
    double px_per_mm;               /* pixels per world unit                  */
    double z_per_mm;                /* view units per world unit              */
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
/* Perspective: the depth from which splatting composites and the ray
 * caster samples, a whole number of slabs (view units).  Voxels whose
 * kernel (radius R voxels) crosses the near plane are dropped
 * (activate.c), so the sheets they reach, up to twice the kernel's depth
 * extent past it, are incomplete; two more sheets, which gradients and
 * pre-integration read, follow.  Orthographic: no limit. */
static inline double vs_camera_near_cut(const vs_camera *cam, double R, double slab)
{
    if (!cam->persp) return -INFINITY;
    const double rz = R * sqrt(cam->M[2][0] * cam->M[2][0] + cam->M[2][1] * cam->M[2][1] + cam->M[2][2] * cam->M[2][2]);
    return (ceil((cam->near_z + 2.0 * rz) / slab) + 2.0) * slab;
}
/* Along an image row whose points' index is i0 + x di (x in pixels), the
 * real x interval [*xlo, *xhi] where lo[a] <= index[a] <= hi[a] on every
 * axis; empty when *xhi < *xlo (an axis the row runs along keeps all or
 * nothing, by i0).  Its ends may be infinite or far off: clamp them before
 * converting to int. */
static inline void vs_camera_row_within(const double i0[3], const double di[3], const double lo[3], const double hi[3],
                                        double *xlo, double *xhi)
{
    double x0 = -INFINITY, x1 = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (di[a] == 0.0) {
            if (!(i0[a] >= lo[a] && i0[a] <= hi[a])) x1 = -INFINITY;
            continue;
        }
        double xa = (lo[a] - i0[a]) / di[a], xb = (hi[a] - i0[a]) / di[a];
        if (xa > xb) {
            const double sw = xa;
            xa = xb;
            xb = sw;
        }
        if (xa > x0) x0 = xa;
        if (xb < x1) x1 = xb;
    }
    *xlo = x0;
    *xhi = x1;
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

/* 1 when the volume's grid axes are orthogonal (a rotation or a signed
 * permutation of the world's, whatever their spacing), 0 when sheared. */
int vs_camera_grid_orthonormal(const struct vs_volume *vol);

/* The settings that frame `copy` (a level of detail of vol, or its copy on
 * cubic voxels: the same axis directions, placed in the same world) as s
 * frames vol: the zoom that keeps the pixels per millimetre (the camera
 * scales by the largest extent) and the centre as the copy's index. */
void vs_camera_settings_for_copy(const struct vs_volume *vol, const struct vs_volume *copy, const vs_settings *s,
                                 vs_settings *out);

#endif
