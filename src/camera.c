/* Orthographic or perspective camera with the conventions of docs/DESIGN.md §2. */
#include "camera.h"
#include "context.h"
#include "volume.h"

#include <math.h>
#include <string.h>

/* cos and sin of an angle in degrees, exact at multiples of 90 degrees so
 * that axis views, flips and permutations give exact zeros in the camera. */
static void cos_sin_deg(double deg, double *c, double *s)
{
    double q = deg / 90.0;
    if (q == floor(q) && fabs(q) < 1e15) {
        static const double cs[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
        long k = (long)fmod(q, 4.0);
        if (k < 0) k += 4;
        *c = cs[k][0];
        *s = cs[k][1];
        return;
    }
    *c = cos(deg * (M_PI / 180.0));
    *s = sin(deg * (M_PI / 180.0));
}

static void cross3(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The (azimuth, elevation) each view starts from (vsplat.h, vs_view).
 * AUTO is the front only for the default angles, so that a program that
 * sets its own angles gets them in the world frame. */
static int view_base(const vs_settings *s, int oriented, double *az, double *el)
{
    static const double base[8][2] = {{0, 0}, {0, 0}, {180, 0}, {0, 0}, {-90, 0}, {90, 0}, {0, 90}, {180, -90}};
    vs_view v = s->view;
    if ((int)v < 0 || (int)v > VS_VIEW_INFERIOR) return 0;
    if (v == VS_VIEW_AUTO && oriented && s->azimuth == 0.0 && s->elevation == 0.0) v = VS_VIEW_ANTERIOR;
    *az = base[v][0];
    *el = base[v][1];
    return 1;
}

/* The camera's world axes from the view settings. */
static vs_status world_axes(vs_context *ctx, const struct vs_volume *vol, const vs_settings *s, double R[3][3])
{
    double az0, el0;
    if (!view_base(s, vol->has_orientation, &az0, &el0))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "view %d is not a vs_view", (int)s->view);
    if (!isfinite(s->roll))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "roll must be finite");
    double ca, sa, ce, se;
    cos_sin_deg(az0 + s->azimuth, &ca, &sa);
    cos_sin_deg(el0 + s->elevation, &ce, &se);
    double *right = R[0], *up = R[1], *dir = R[2];
    /* view 0,0: look along +y, +x right, +z up; azimuth turns about +z,
     * positive elevation looks down from above.  right = dir x up. */
    dir[0] = -sa * ce; dir[1] = ca * ce; dir[2] = -se;
    right[0] = ca; right[1] = sa; right[2] = 0.0;
    up[0] = -sa * se; up[1] = ca * se; up[2] = ce;
    if (s->has_up) {
        const double *u = s->up;
        double n = sqrt(dot3(u, u));
        if (!isfinite(n) || !(n > 0.0))
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "up vector must be finite and not zero");
        double d = dot3(u, dir) / n, p[3];
        for (int a = 0; a < 3; a++) p[a] = u[a] / n - d * dir[a];
        double m = sqrt(dot3(p, p));
        if (!(m > 1e-6))
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                                "up vector %g,%g,%g lies along the viewing direction %g,%g,%g", u[0], u[1], u[2],
                                dir[0], dir[1], dir[2]);
        for (int a = 0; a < 3; a++) up[a] = p[a] / m;
        cross3(dir, up, right);
    }
    if (s->roll != 0.0) { /* the picture turns clockwise: the camera the other way */
        double c, sn, r0[3], u0[3];
        cos_sin_deg(s->roll, &c, &sn);
        for (int a = 0; a < 3; a++) r0[a] = right[a], u0[a] = up[a];
        for (int a = 0; a < 3; a++) {
            right[a] = c * r0[a] + sn * u0[a];
            up[a] = c * u0[a] - sn * r0[a];
        }
    }
    return VS_OK;
}

/* The volume's transform as grid frame -> world: the affine's columns scaled
 * to the current spacing (so a spacing set without the affine, e.g. a load
 * option, still counts), divided by the spacing.  Returns 1 if Q is a signed
 * permutation (perm[a], sign[a]: world axis and sign of grid axis a), 2 if
 * orthogonal, 0 if sheared. */
static int grid_frame(const struct vs_volume *vol, double Q[3][3], int perm[3], double sign[3])
{
    int signed_perm = 1, used = 0;
    for (int c = 0; c < 3; c++) {
        double n = sqrt(vol->affine[0][c] * vol->affine[0][c] + vol->affine[1][c] * vol->affine[1][c] +
                        vol->affine[2][c] * vol->affine[2][c]);
        int nz = 0;
        for (int r = 0; r < 3; r++) {
            Q[r][c] = vol->affine[r][c] / n;
            if (vol->affine[r][c] != 0.0) {
                nz++;
                perm[c] = r;
                sign[c] = vol->affine[r][c] > 0 ? 1.0 : -1.0;
            }
        }
        if (nz != 1 || (used & (1 << perm[c]))) signed_perm = 0;
        else used |= 1 << perm[c];
    }
    if (signed_perm) return 1;
    double err = 0.0;
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            double d = Q[0][a] * Q[0][b] + Q[1][a] * Q[1][b] + Q[2][a] * Q[2][b] - (a == b);
            if (fabs(d) > err) err = fabs(d);
        }
    return err < 1e-6 ? 2 : 0;
}

/* What --zoom scales: the volume's largest extent. */
static double largest_extent(const struct vs_volume *vol)
{
    double e = 0.0;
    for (int a = 0; a < 3; a++)
        if (vol->dims[a] * vol->spacing[a] > e) e = vol->dims[a] * vol->spacing[a];
    return e;
}

void vs_camera_settings_for_copy(const struct vs_volume *vol, const struct vs_volume *copy, const vs_settings *s,
                                 vs_settings *out)
{
    *out = *s;
    out->zoom = s->zoom * largest_extent(copy) / largest_extent(vol);
    out->has_center = 1;
    for (int a = 0; a < 3; a++)
        out->center[a] = vs_volume_index_in(vol, copy, a, s->has_center ? s->center[a] : 0.5 * (vol->dims[a] - 1));
}

int vs_camera_grid_orthonormal(const struct vs_volume *vol)
{
    double Q[3][3], sign[3];
    int perm[3];
    return grid_frame(vol, Q, perm, sign) != 0;
}

static int invert3(const double m[3][3], double o[3][3])
{
    double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    double c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
    if (!isfinite(det) || det == 0.0) return 0;
    o[0][0] = c00 / det;
    o[1][0] = c01 / det;
    o[2][0] = c02 / det;
    o[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / det;
    o[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / det;
    o[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / det;
    o[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / det;
    o[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / det;
    o[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / det;
    return 1;
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
    cam->width = s->width;
    cam->height = s->height;
    double W[3][3];
    vs_status st = world_axes(ctx, vol, s, W);
    if (st != VS_OK) return st;
    for (int a = 0; a < 3; a++) {
        cam->wright[a] = W[0][a];
        cam->wup[a] = W[1][a];
        cam->wdir[a] = W[2][a];
    }
    /* The camera's axes in the grid frame: rows of W Q.  A signed
     * permutation (no orientation, flips, permuted axes) picks entries, so
     * the result is exact. */
    double Q[3][3], sign[3] = {1, 1, 1}, rows[3][3];
    int perm[3] = {0, 1, 2};
    const int kind = grid_frame(vol, Q, perm, sign);
    for (int r = 0; r < 3; r++)
        for (int a = 0; a < 3; a++)
            rows[r][a] = kind == 1 ? (sign[a] > 0 ? W[r][perm[a]] : -W[r][perm[a]])
                                   : W[r][0] * Q[0][a] + W[r][1] * Q[1][a] + W[r][2] * Q[2][a];

    const double extent = largest_extent(vol);
    const double unit = vs_volume_finest(vol);
    cam->unit_mm = unit;
    cam->px_per_mm = s->zoom * s->width / extent;
    cam->z_per_mm = 1.0 / unit;
    double center[3], center_grid[3];
    for (int a = 0; a < 3; a++) {
        double c = s->has_center ? s->center[a] : 0.5 * (vol->dims[a] - 1);
        if (!isfinite(c))
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "center must be finite");
        center[a] = c;
        center_grid[a] = (c - 0.5 * (vol->dims[a] - 1)) * vol->spacing[a];
    }
    /* index -> view */
    const double rs[3] = {cam->px_per_mm, -cam->px_per_mm, cam->z_per_mm};
    const double off[3] = {0.5 * (s->width - 1), 0.5 * (s->height - 1), 0.0};
    if (kind) {
        /* orthonormal rows: M = diag(rs) rows diag(spacing), inverted
         * analytically */
        for (int r = 0; r < 3; r++) {
            double t = off[r];
            for (int a = 0; a < 3; a++) {
                cam->M[r][a] = rows[r][a] * vol->spacing[a] * rs[r];
                t += rows[r][a] * rs[r] * (-0.5 * (vol->dims[a] - 1) * vol->spacing[a] - center_grid[a]);
            }
            cam->t[r] = t;
        }
        for (int a = 0; a < 3; a++)
            for (int r = 0; r < 3; r++)
                cam->Minv[a][r] = rows[r][a] / (vol->spacing[a] * rs[r]);
        for (int a = 0; a < 3; a++) {
            cam->right[a] = rows[0][a];
            cam->up[a] = rows[1][a];
            cam->dir[a] = rows[2][a];
        }
    } else {
        /* A sheared transform is rendered as it says: M = diag(rs) W A with
         * A = Q diag(spacing), the grid's Gaussian kernels sheared with it;
         * the shading axes are spacing A^-1 W^T, so that gw = g / spacing
         * dotted with them is the world gradient A^-T g in the eye frame. */
        double A[3][3], Ai[3][3];
        for (int r = 0; r < 3; r++)
            for (int a = 0; a < 3; a++) A[r][a] = Q[r][a] * vol->spacing[a];
        if (!invert3(A, Ai)) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "volume transform is singular");
        for (int r = 0; r < 3; r++) {
            double t = off[r];
            for (int a = 0; a < 3; a++) {
                cam->M[r][a] = (W[r][0] * A[0][a] + W[r][1] * A[1][a] + W[r][2] * A[2][a]) * rs[r];
                t -= cam->M[r][a] * center[a];
            }
            cam->t[r] = t;
        }
        double Mc[3][3], Mi[3][3];
        memcpy(Mc, cam->M, sizeof Mc);
        if (!invert3(Mc, Mi)) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "volume transform is singular");
        memcpy(cam->Minv, Mi, sizeof Mi);
        for (int a = 0; a < 3; a++) {
            double *o[3] = {cam->right, cam->up, cam->dir};
            for (int r = 0; r < 3; r++)
                o[r][a] = vol->spacing[a] * (Ai[a][0] * W[r][0] + Ai[a][1] * W[r][1] + Ai[a][2] * W[r][2]);
        }
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
