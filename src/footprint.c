/* Kernel geometry and pre-integrated tables for one frame (see footprint.h). */
#include "gaussian.h"
#include "context.h"
#include "footprint.h"
#include "kernels.h"

#include <math.h>
#include <stdlib.h>

void vs_footprint_free(vs_footprint *fp)
{
    free(fp->exp_table);
    free(fp->depth_table);
    free(fp->slab_d);
    free(fp->slab_e);
    fp->exp_table = fp->depth_table = fp->slab_d = fp->slab_e = NULL;
}

/* The gradient's x and y come from pixels 1/m voxels apart, its z from
 * sheets a slab apart, and shading follows the gradient's direction, so
 * what matters is that the three differences follow detail alike.  Seen
 * small, a sheet carries detail near its pixels' limit, where the
 * two-point difference falls short of the derivative (at 0.8 pixel a
 * voxel the kernel passes detail four pixels in period at 0.87 of its
 * strength; of its derivative the two-point difference takes 0.64, the
 * four-point stencil 0.85); seen large, the sheets lie further apart than
 * the pixels and the difference across them falls short.  Either stencil
 * alone turns the normal where the other direction's difference is left
 * two-point (at 1-1.9 pixels a voxel each measured 0.1-0.4 dB further from
 * the ray caster); both together were 0.1-1.8 dB closer from 0.8 to 1.4
 * pixels a voxel (the Colin27 heads, the engine, the CT head at 256^2-448^2,
 * against the exact-Gaussian ray caster with and without its lattice
 * ripple), at 5-17 % of a frame for the in-sheet stencil's two-pixel tile
 * seam.  Past 1.5 the in-sheet stencil gains under 0.1 dB
 * (docs/PERFORMANCE.md, "In-sheet differences").  m is measured along the
 * footprint's narrowest direction, where Qxx's larger eigenvalue is
 * a / m^2. */
static double px_per_voxel(const vs_footprint *fp)
{
    const double A = fp->A, B = fp->B, C = fp->C;
    const double l = 0.5 * (A + C) + sqrt(0.25 * (A - C) * (A - C) + B * B);
    return l > 0.0 ? sqrt(fp->a / l) : 0.0;
}

/* In a sheet: the four-point stencil up to 1.4 pixels a voxel, the
 * two-point one from 1.5, mixed linearly between so that a zoom does not
 * jump. */
float vs_cd_wide(const vs_footprint *fp)
{
    const double m = px_per_voxel(fp);
    if (!(m > 0.0)) return 0.0f;
    double beta = (1.5 - m) / 0.1;
    if (!(beta > 0.0)) return 0.0f;
    if (beta > 1.0) beta = 1.0;
    return (float)(beta / 12.0);
}

/* Across sheets: none up to m slab = 0.7 (there the two-point difference
 * across a slab follows the detail the in-sheet ones do), the stencil from
 * 1.0, mixed linearly between.  render.c leaves pre-integrated sheets out:
 * there it measured 0.2-0.6 dB further at every size. */
float vs_cd_wide_z(const vs_footprint *fp, double slab_voxels)
{
    const double r = px_per_voxel(fp) * slab_voxels;
    double beta = (r - 0.7) / 0.3;
    if (!(beta > 0.0)) return 0.0f;
    if (beta > 1.0) beta = 1.0;
    return (float)(beta / 12.0);
}

vs_status vs_footprint_setup(vs_context *ctx, const vs_settings *s, const vs_camera *cam,
                             vs_footprint *fp)
{
    if (!(s->kernel_radius >= 0.5 && s->kernel_radius <= 8.0))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "kernel radius %g must lie in [0.5, 8]",
                            s->kernel_radius);
    if (!(s->slab >= 0.01 && s->slab <= 64.0))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "slab thickness %g must lie in [0.01, 64]", s->slab);
    if (s->footprint_resolution < 8 || s->footprint_resolution > (1 << 20))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "footprint resolution %d must lie in [8, 2^20]",
                            s->footprint_resolution);
    if (s->depth_resolution < 8 || s->depth_resolution > (1 << 16))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "depth resolution %d must lie in [8, 65536]",
                            s->depth_resolution);
    fp->a = 2.0 * M_LN2;
    fp->R = s->kernel_radius;
    fp->b = vs_kernel_b(fp->R);
    fp->emax = fp->a * fp->R * fp->R;
    fp->slab = s->slab;
    fp->slab_d = fp->slab_e = NULL; /* vs_footprint_slab_tables */
    fp->slab_n = fp->slab_w = 0;
    fp->slab_scale = 0.0f;
    /* Q = a Minv^T Minv (view space, Minv maps view -> index) */
    double Q[3][3];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            double q = 0;
            for (int k = 0; k < 3; k++) q += cam->Minv[k][r] * cam->Minv[k][c];
            Q[r][c] = fp->a * q;
        }
    double A = Q[0][0], B = Q[0][1], C = Q[1][1];
    /* A cross term at rounding level is 0: it comes from an axis of the
     * grid that lies in the image plane, seen through a rotation whose sines
     * and cosines are not exact (the CT head turned about its anisotropic
     * axis gives |B| ~ 1e-17..1e-33).  Kept, it would shift each footprint
     * row by that many pixels and send every section of the view down the
     * skewed-block path instead of the row-times-column one. */
    if (fabs(B) <= 1e-12 * (A + C)) B = 0.0;
    double det = A * C - B * B;
    /* s = -Qxx^-1 Qxz */
    double sx = -(C * Q[0][2] - B * Q[1][2]) / det;
    double sy = -(-B * Q[0][2] + A * Q[1][2]) / det;
    fp->kappa = Q[2][2] + Q[0][2] * sx + Q[1][2] * sy;
    fp->A = (float)A;
    fp->B = (float)B;
    fp->C = (float)C;
    fp->row_k = (float)(C - B * B / A);
    fp->row_shift = (float)(-B / A);
    fp->sx = (float)sx;
    fp->sy = (float)sy;
    fp->sheared = fabs(sx) > 1e-9 || fabs(sy) > 1e-9;
    /* Isotropic voxels (any view) and anisotropic ones seen along an axis:
     * the footprint is an outer product of a row and a column of weights */
    fp->separable = !fp->sheared && B == 0.0;
    fp->Qzx = Q[2][0];
    fp->Qzy = Q[2][1];
    fp->rz = sqrt(fp->emax / fp->kappa);
    fp->vspan = (int)ceilf(2.0f * (float)fp->rz / (float)fp->slab) + 1;
    /* footprint extent: the ellipse d^T Qxx d <= emax has half-widths
     * sqrt(emax * (Qxx^-1)_xx), plus the largest shift within +-rz */
    fp->rx = sqrt(fp->emax * C / det) + fabs(sx) * fp->rz;
    fp->ry = sqrt(fp->emax * A / det) + fabs(sy) * fp->rz;
    if (!isfinite(fp->rx) || !isfinite(fp->ry) || !isfinite(fp->rz) || fp->rx > 1e6 || fp->ry > 1e6)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                            "zoom too large: a footprint would span %g pixels", 2 * fp->rx);

    fp->exp_n = s->footprint_resolution;
    fp->exp_scale = (float)((fp->exp_n - 1) / fp->emax);
    fp->exp_table = malloc((size_t)(fp->exp_n + 1) * sizeof(float));
    fp->depth_n = (int)ceil(2.0 * fp->rz * s->depth_resolution) + 2;
    if (fp->depth_n > (1 << 24)) fp->depth_n = 1 << 24;
    fp->depth_scale = (float)((fp->depth_n - 1) / (2.0 * fp->rz));
    fp->depth_table = malloc((size_t)(fp->depth_n + 1) * sizeof(float));
    if (!fp->exp_table || !fp->depth_table) {
        vs_footprint_free(fp);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "footprint tables: out of memory");
    }
    /* entries 0..exp_n-1 cover [0, emax]; lookups past emax return 0 */
    for (int i = 0; i < fp->exp_n; i++) fp->exp_table[i] = (float)exp(-(double)i / fp->exp_scale);
    fp->exp_table[fp->exp_n] = fp->exp_table[fp->exp_n - 1];
    double sk = sqrt(fp->kappa), base = erf(-sk * fp->rz);
    for (int i = 0; i <= fp->depth_n; i++) {
        double z = -fp->rz + i / (double)fp->depth_scale;
        if (z > fp->rz) z = fp->rz;
        fp->depth_table[i] = (float)(0.5 * sqrt(M_PI / fp->kappa) * (erf(sk * z) - base));
    }
    return VS_OK;
}

vs_status vs_footprint_slab_tables(vs_context *ctx, const vs_settings *s, vs_footprint *fp)
{
    /* a row of integrals per 1/depth_resolution of phi (at most 2^14
     * rows), so that a voxel reads one row pair, not a depth-table pair
     * per slab boundary */
    const int nd = fp->vspan < VS_MAX_SHEETS_VOXEL ? fp->vspan : VS_MAX_SHEETS_VOXEL;
    const double rows = ceil(fp->slab * s->depth_resolution);
    fp->slab_n = rows < 1.0 ? 1 : rows > (1 << 14) ? 1 << 14 : (int)rows;
    fp->slab_w = (nd + 7) & ~7;
    fp->slab_scale = (float)(fp->slab_n / fp->slab);
    free(fp->slab_d);
    free(fp->slab_e);
    fp->slab_d = malloc((size_t)(fp->slab_n + 1) * fp->slab_w * sizeof(float));
    fp->slab_e = malloc((size_t)(fp->slab_n + 1) * fp->slab_w * sizeof(float));
    if (!fp->slab_d || !fp->slab_e) {
        vs_footprint_free(fp);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "footprint tables: out of memory");
    }
    const double sk = sqrt(fp->kappa), norm = 0.5 * sqrt(M_PI / fp->kappa);
    for (int r = 0; r <= fp->slab_n; r++) {
        const double phi = r * fp->slab / fp->slab_n;
        float *d = fp->slab_d + (size_t)r * fp->slab_w, *e = fp->slab_e + (size_t)r * fp->slab_w;
        /* the slabs' ends, from the voxel's centre: one erf and one exp
         * each, shared by the slabs either side */
        double g0 = 0.0, x0 = 0.0;
        for (int j = 0; j <= nd; j++) {
            const double b = j * fp->slab - phi - fp->rz;
            const double t = b < -fp->rz ? -fp->rz : b > fp->rz ? fp->rz : b;
            const double g = erf(sk * t), x = fabs(b) < fp->rz ? exp(-fp->kappa * b * b) : 0.0;
            if (j > 0) {
                d[j - 1] = (float)(norm * (g - g0));
                e[j - 1] = (float)(x - x0);
            }
            g0 = g;
            x0 = x;
        }
        for (int j = nd; j < fp->slab_w; j++) d[j] = e[j] = 0.0f;
    }
    return VS_OK;
}
