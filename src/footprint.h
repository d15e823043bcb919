/* Per-frame kernel geometry in view space and the pre-integrated tables.
 *
 * The kernel h(u) = b exp(-a |u|^2) (a = 2 ln 2) lives in voxel-index space
 * u; the camera maps index to view space linearly (v = M u), so in view space
 * h(v) = b exp(-v^T Q v) with Q = a Minv^T Minv.  Split Q into the in-sheet
 * block Qxx (2x2), the coupling Qxz and Qzz.  Then for a fixed depth z the
 * section is a 2-D Gaussian exp(-(d - s z)^T Qxx (d - s z)) centred at the
 * shift s z (s = -Qxx^-1 Qxz: non-zero only for anisotropic voxels seen
 * obliquely) times the depth term exp(-kappa z^2).  A slab [z0, z1) thus
 * contributes footprint(d - s zbar) * D(z0, z1), D being the integral of the
 * depth term (a difference of erf values), zbar its centroid. */
#ifndef VS_FOOTPRINT_H
#define VS_FOOTPRINT_H

#include "camera.h"

/* floor and ceil of a float known to lie well inside int's range (pixel and
 * sheet coordinates): exact, and a few instructions where the baseline
 * x86-64 floorf/ceilf are long sequences (SSE4.1's roundss is not baseline). */
static inline int vs_ifloor(float v)
{
    const int i = (int)v;
    return i - (v < (float)i);
}
static inline int vs_iceil(float v)
{
    const int i = (int)v;
    return i + (v > (float)i);
}

typedef struct vs_footprint {
    double a;            /* 2 ln 2                                            */
    double b;            /* kernel normalisation for radius R                  */
    double R;            /* kernel radius (index units)                        */
    double emax;         /* a R^2: exponent where the kernel is truncated      */
    float A, B, C;       /* Qxx = [[A, B], [B, C]] (per pixel^2)               */
    float row_k;         /* C - B^2/A: exponent per dy^2 of a row's weight     */
    float row_shift;     /* -B/A: a row's centre moves by row_shift * dy       */
    float sx, sy;        /* shift per view unit of depth                       */
    int sheared;         /* s != 0                                             */
    int separable;       /* B == 0 and no shear: footprint = row x column      */
    double kappa;        /* depth exponent per view unit^2                     */
    double rz;           /* depth half-extent (view units)                     */
    int vspan;           /* sheets one kernel can reach: ceil(2 rz / slab) + 1 */
    double rx, ry;       /* footprint half-extent in pixels (incl. shift)      */
    double slab;         /* sheet thickness (view units)                       */
    double Qzx, Qzy;     /* coupling terms for the z gradient splat            */
    /* exp(-t) for t in [0, emax], linear interpolation */
    int exp_n;
    float exp_scale;     /* (exp_n - 1) / emax                                 */
    float *exp_table;    /* exp_n + 1 entries                                  */
    /* depth integral G(z) = int_{-rz}^{z} exp(-kappa t^2) dt on [-rz, rz]      */
    int depth_n;
    float depth_scale;   /* (depth_n - 1) / (2 rz)                             */
    float *depth_table;  /* depth_n + 1 entries                                */
    /* A voxel's depth integrals over the slabs from its first sheet
     * (place_voxels, simd/kernels.h vs_place_in): row r, for a kernel that
     * starts phi = r / slab_scale into its first slab (r = 0..slab_n),
     * holds slab_w floats, the integrals over slabs 0..vspan-1 (at most
     * VS_MAX_SHEETS_VOXEL) and then zeros; slab_d of exp(-kappa t^2),
     * slab_e of its derivative (exp at the slab's ends, 0 past rz).
     * Made by vs_footprint_slab_tables, only for the voxel-at-a-time
     * paths that read them; NULL otherwise */
    int slab_n, slab_w;
    float slab_scale;
    float *slab_d, *slab_e;
} vs_footprint;

vs_status vs_footprint_setup(vs_context *ctx, const vs_settings *s, const vs_camera *cam,
                             vs_footprint *fp);
/* The slab tables above (after vs_footprint_setup); on failure the
 * footprint is freed. */
vs_status vs_footprint_slab_tables(vs_context *ctx, const vs_settings *s, vs_footprint *fp);

/* The in-sheet footprint seen s times larger (a perspective sheet): the
 * quadratic form in pixels shrinks by s^2; the tables are shared, read
 * only, and depth terms are unchanged. */
static inline vs_footprint vs_footprint_scaled(const vs_footprint *fp, float s)
{
    vs_footprint f = *fp;
    const float s2 = s * s;
    f.A /= s2;
    f.B /= s2;
    f.C /= s2;
    f.row_k /= s2;
    return f;
}
void vs_footprint_free(vs_footprint *fp);

/* Post-cd's weight of the four-point in-sheet differences for this
 * footprint (simd/kernels.h vs_shade_tabs cd_wide): 1/12 when voxels lie at
 * most 1.4 pixels apart on the image, 0 from 1.5 pixels, linear between. */
float vs_cd_wide(const vs_footprint *fp);
/* The same across sheets (vs_shade_tabs cd_wide_z), for sheets slab_voxels
 * voxels apart: 0 while sheets lie at most 0.7 pixel's worth of voxels
 * apart (m slab), 1/12 from 1.0, linear between. */
float vs_cd_wide_z(const vs_footprint *fp, double slab_voxels);

/* exp(-t) from a table of n entries, scale entries per unit of t >= 0 (the
 * SIMD kernels' reference reads it through this too). */
static inline float vs_exp_lookup(const float *table, int n, float scale, float t)
{
    float x = t * scale;
    if (!(x < (float)(n - 1))) return 0.0f; /* truncated (and NaN) */
    int i = (int)x;
    float f = x - (float)i;
    return table[i] + f * (table[i + 1] - table[i]);
}

static inline float vs_fp_exp(const vs_footprint *fp, float t)
{
    return vs_exp_lookup(fp->exp_table, fp->exp_n, fp->exp_scale, t);
}

/* G(z) from a depth table of n entries, scale entries per unit, starting
 * at -rz (the SIMD kernels' reference reads it through this too). */
static inline float vs_depth_lookup(const float *table, int n, float scale, float rz, float z)
{
    float x = (z + rz) * scale;
    if (!(x > 0.0f)) return 0.0f;
    if (x >= (float)(n - 1)) return table[n - 1];
    int i = (int)x;
    float f = x - (float)i;
    return table[i] + f * (table[i + 1] - table[i]);
}

/* G(z): integral of the depth term from -rz to z (clamped). */
static inline float vs_fp_depth(const vs_footprint *fp, float z)
{
    return vs_depth_lookup(fp->depth_table, fp->depth_n, fp->depth_scale, (float)fp->rz, z);
}

#endif
