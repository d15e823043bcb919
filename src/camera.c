/* Orthographic or perspective camera with the conventions of docs/DESIGN.md §2. */
#include "camera.h"
#include "context.h"
#include "volume.h"

#include <math.h>

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

vs_status vs_camera_setup(vs_context *ctx, const struct vs_volume *vol,
                          const vs_settings *s, vs_camera *cam)
{
    if (s->width < 1 || s->height < 1 || s->width > VS_MAX_IMAGE_DIM || s->height > VS_MAX_IMAGE_DIM)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "image size %dx%d is out of range (1..%d)",
                            s->width, s->height, VS_MAX_IMAGE_DIM);
    if (!isfinite(s->azimuth) || !isfinite(s->elevation))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "view angles must be finite");
    if (!(s->zoom > 0.0) || !isfinite(s->zoom) || s->zoom > 1e6)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "zoom %g must be finite and > 0", s->zoom);
    if (!(s->perspective_fov >= 0.0 && s->perspective_fov <= 170.0))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                            "perspective field of view %g must lie in [0, 170] degrees (0 = orthographic)",
                            s->perspective_fov);
    const double deg = M_PI / 180.0;
    double ca = cos(s->azimuth * deg), sa = sin(s->azimuth * deg);
    double ce = cos(s->elevation * deg), se = sin(s->elevation * deg);
    cam->width = s->width;
    cam->height = s->height;
    /* view 0,0: look along +y, +x right, +z up; azimuth turns about +z,
     * positive elevation looks down from above. */
    cam->dir[0] = -sa * ce; cam->dir[1] = ca * ce; cam->dir[2] = -se;
    cam->right[0] = ca; cam->right[1] = sa; cam->right[2] = 0.0;
    cam->up[0] = -sa * se; cam->up[1] = ca * se; cam->up[2] = ce;

    double extent = 0.0, unit = INFINITY;
    for (int a = 0; a < 3; a++) {
        double e = vol->dims[a] * vol->spacing[a];
        if (e > extent) extent = e;
        if (vol->spacing[a] < unit) unit = vol->spacing[a];
    }
    cam->unit_mm = unit;
    cam->px_per_mm = s->zoom * s->width / extent;
    cam->z_per_mm = 1.0 / unit;
    for (int a = 0; a < 3; a++) {
        double c = s->has_center ? s->center[a] : 0.5 * (vol->dims[a] - 1);
        if (!isfinite(c))
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "center must be finite");
        cam->center_world[a] = (c - 0.5 * (vol->dims[a] - 1)) * vol->spacing[a];
    }
    /* index -> view */
    const double *rows[3] = {cam->right, cam->up, cam->dir};
    const double rs[3] = {cam->px_per_mm, -cam->px_per_mm, cam->z_per_mm};
    const double off[3] = {0.5 * (s->width - 1), 0.5 * (s->height - 1), 0.0};
    for (int r = 0; r < 3; r++) {
        double t = off[r];
        for (int a = 0; a < 3; a++) {
            cam->M[r][a] = rows[r][a] * vol->spacing[a] * rs[r];
            t += rows[r][a] * rs[r] * (-0.5 * (vol->dims[a] - 1) * vol->spacing[a] - cam->center_world[a]);
        }
        cam->t[r] = t;
    }
    cam->cx = off[0];
    cam->cy = off[1];
    cam->persp = s->perspective_fov > 0.0;
    cam->persp_dz = INFINITY;
    cam->focal_px = INFINITY;
    cam->near_z = -INFINITY;
    if (cam->persp) {
        /* vertical field of view, as VTK's view angle; the eye distance keeps
         * the z = 0 plane at the orthographic scale, so --zoom means the same
         * in both projections and a small angle tends to orthographic */
        cam->focal_px = 0.5 * s->height / tan(0.5 * s->perspective_fov * M_PI / 180.0);
        cam->persp_dz = cam->focal_px / cam->px_per_mm * cam->z_per_mm;
        /* nearer than 1/20 of the eye distance, footprints would grow past
         * 20x their size at the centre: clipped, like a camera's near plane */
        cam->near_z = -0.95 * cam->persp_dz;
    }
    /* view -> index: M = D R S with orthonormal R; invert analytically. */
    for (int a = 0; a < 3; a++)
        for (int r = 0; r < 3; r++)
            cam->Minv[a][r] = rows[r][a] / (vol->spacing[a] * rs[r]);
    (void)dot3;
    return VS_OK;
}

void vs_camera_index_to_view0(const vs_camera *cam, const double idx[3], double v[3])
{
    for (int r = 0; r < 3; r++)
        v[r] = cam->M[r][0] * idx[0] + cam->M[r][1] * idx[1] + cam->M[r][2] * idx[2] + cam->t[r];
}

void vs_camera_view_to_index(const vs_camera *cam, const double v[3], double idx[3])
{
    double x = v[0], y = v[1];
    if (cam->persp) {
        double sc = vs_camera_scale(cam, v[2]);
        x = cam->cx + (x - cam->cx) / sc;
        y = cam->cy + (y - cam->cy) / sc;
    }
    double d[3] = {x - cam->t[0], y - cam->t[1], v[2] - cam->t[2]};
    for (int a = 0; a < 3; a++)
        idx[a] = cam->Minv[a][0] * d[0] + cam->Minv[a][1] * d[1] + cam->Minv[a][2] * d[2];
}

void vs_camera_ray(const vs_camera *cam, double x, double y, double org[3], double dir[3])
{
    const double v0[3] = {x, y, 0.0};
    vs_camera_view_to_index(cam, v0, org);
    /* orthographic: along view z; perspective: the pixel's image-plane
     * offset grows by 1/persp_dz of itself per unit of depth */
    double dx = cam->persp ? (x - cam->cx) / cam->persp_dz : 0.0;
    double dy = cam->persp ? (y - cam->cy) / cam->persp_dz : 0.0;
    for (int a = 0; a < 3; a++) dir[a] = cam->Minv[a][0] * dx + cam->Minv[a][1] * dy + cam->Minv[a][2];
}
