/* The volume's faces when the fall-off to the value outside would show
 * (face_cover.h). */
#include "face_cover.h"
#include "camera.h"
#include "volume.h"

#include <math.h>

/* The share at index t of voxels i0..i1 in the 1-D lattice sum of the
 * kernel 2^(-2 u^2), |u| <= R, u = (t - i) / f (f: the kernel's width in
 * these voxels), and its derivative in t (dshare may be NULL).  Exactly 1
 * (derivative 0) where every lattice point within R f lies inside. */
static double face_share(double t, int i0, int i1, double R, double f, double *dshare)
{
    if (dshare) *dshare = 0.0;
    R *= f;
    if (!(t + R >= i0 && t - R <= i1)) return 0.0; /* no voxel within R (and t fits an int below) */
    const int lo = (int)ceil(t - R), hi = (int)floor(t + R);
    if (lo >= i0 && hi <= i1) return 1.0;
    const double inv_f = 1.0 / f; /* 1 but for a level of the cubic copy */
    double N = 0.0, D = 0.0, dN = 0.0, dD = 0.0;
    for (int i = lo; i <= hi; i++) {
        const double u = (t - i) * inv_f, g = exp2(-2.0 * u * u), dg = -4.0 * M_LN2 * u * g * inv_f;
        D += g;
        dD += dg;
        if (i >= i0 && i <= i1) {
            N += g;
            dN += dg;
        }
    }
    if (!(D > 0.0)) return 0.0;
    if (dshare) *dshare = (dN * D - N * dD) / (D * D);
    return N / D;
}

/* The pixels [*a, *b) of a row whose sheet points lie at least the
 * kernel's reach R[a] inside every face (shares exactly 1): idx_a(x) =
 * i0[a] + x di[a], the voxels inside [in0[a], in1[a]]. */
static void interior_run(const double i0[3], const double di[3], const int *in0, const int *in1, const double R[3],
                         int x0, int x1, int *a, int *b)
{
    double u0[3], u1[3], lo, hi;
    for (int k = 0; k < 3; k++) {
        u0[k] = in0[k] + R[k];
        u1[k] = in1[k] - R[k];
    }
    vs_camera_row_within(i0, di, u0, u1, &lo, &hi);
    lo = lo > x0 ? lo : x0; /* the real x range kept */
    hi = hi < x1 - 1 ? hi : x1 - 1;
    /* rounded inwards, one pixel more each side for the affine step's
     * rounding; clamped first, as a near-parallel axis puts them far off */
    lo = lo > x1 ? x1 : lo;
    hi = hi < x0 - 1 ? x0 - 1 : hi > x1 ? x1 : hi;
    *a = (int)ceil(lo) + 1;
    *b = (int)floor(hi);
    if (*b < *a) *a = *b = x0;
}

/* Depths across a slab at which the share is averaged (the sheet holds the
 * kernels integrated over its slab): its middle alone up to a slab of one
 * voxel (closer to the ray caster there: tubes through 48^3 tissue under
 * --iso 50:100, 128^2, 31.9 dB against 31.3 with three depths), else the
 * midpoint rule with two depths a voxel of slab and one more, at most
 * FACE_DEPTHS (slab 2: 13.0 dB with the middle alone, the faces drawn as
 * stripes; 26.6 dB). */
#define FACE_DEPTHS 16

void vs_face_norm_sheet(const tile_ctx *t, int k, float *buf, const rect *bb, int ch, int gs)
{
    const vs_frame *F = t->F;
    const vs_camera *cam = &F->cam;
    const struct vs_volume *vol = F->vol, *cv = F->cover;
    const int *in0 = F->cover_in0, *in1 = F->cover_in1;
    const double R = F->s->kernel_radius, slab = F->fp.slab, z = (k + 0.5) * slab;
    const double nq = slab <= 1.0 ? 1.0 : fmin(FACE_DEPTHS, ceil(2.0 * slab) + 1.0);
    const int n = (int)nq;
    /* d(cover index) / d(splatted index), and the kernel's reach, per axis */
    double sc[3], reach[3];
    for (int a = 0; a < 3; a++) {
        sc[a] = vol->spacing[a] / cv->spacing[a];
        reach[a] = R * F->cover_scale[a];
    }
    const int x0 = bb->x0 > 0 ? bb->x0 : 0, x1 = bb->x1 < t->bw ? bb->x1 : t->bw;
    const int y0 = bb->y0 > 0 ? bb->y0 : 0, y1 = bb->y1 < t->bh ? bb->y1 : t->bh;
    for (int y = y0; y < y1; y++) {
        /* a point's index is affine in x along a row at each depth
         * (perspective too: a depth's scale is one number) */
        double i0[FACE_DEPTHS][3], di[FACE_DEPTHS][3];
        int ra = x0, rb = x1;
        for (int q = 0; q < n; q++) {
            const double zq = z + slab * ((q + 0.5) / n - 0.5);
            double i1[3];
            const double v0[3] = {t->ox, y + t->oy, zq}, v1[3] = {t->ox + 1.0, y + t->oy, zq};
            vs_camera_view_to_index(cam, v0, i0[q]);
            vs_camera_view_to_index(cam, v1, i1);
            for (int a = 0; a < 3; a++) {
                di[q][a] = (i1[a] - i0[q][a]) * sc[a];
                i0[q][a] = cv == vol ? i0[q][a] : vs_volume_index_in(vol, cv, a, i0[q][a]);
            }
            int qa, qb; /* the pixels inside at every depth are skipped */
            interior_run(i0[q], di[q], in0, in1, reach, x0, x1, &qa, &qb);
            ra = qa > ra ? qa : ra;
            rb = qb < rb ? qb : rb;
        }
        if (rb <= ra) ra = rb = x1;
        for (int x = x0; x < x1; x++) {
            if (x >= ra && x < rb) x = rb;
            if (x >= x1) break;
            /* nothing splatted here (no relevant voxel reaches): nothing to divide */
            float *p = buf + ((size_t)y * t->stride + x) * ch;
            int any = 0;
            for (int i = 0; i < ch; i++) any |= p[i] != 0.0f;
            if (!any) continue;
            /* the share averaged over the slab, and its view-space gradient */
            double C = 0.0, dC[3] = {0.0, 0.0, 0.0};
            for (int q = 0; q < n; q++) {
                double c[3], dc[3], Cq = 1.0;
                for (int a = 0; a < 3; a++) {
                    c[a] = face_share(i0[q][a] + x * di[q][a], in0[a], in1[a], R, F->cover_scale[a], gs ? &dc[a] : NULL);
                    Cq *= c[a];
                }
                C += Cq;
                if (!gs) continue;
                for (int a = 0; a < 3; a++) {
                    const double dCa = dc[a] * c[(a + 1) % 3] * c[(a + 2) % 3] * sc[a];
                    for (int j = 0; j < 3; j++) dC[j] += dCa * cam->Minv[a][j];
                }
            }
            C /= nq;
            /* inside, or so far out that nothing reaches (clipped anyway) */
            if (C >= 1.0 || C < 1e-3) continue;
            const double inv = 1.0 / C;
            if (!gs) {
                for (int i = 0; i < ch; i++) p[i] = (float)(p[i] * inv);
                continue;
            }
            /* (S / C)' = (S' - (S / C) C') / C, C' in view units (x, y per
             * pixel, z per view unit) as the splatted gradient's; S and S'
             * are both integrals over the slab, so S / C carries its length
             * and C' is not scaled by it */
            const double S = p[0] * inv;
            p[0] = (float)S;
            for (int j = 0; j < 3; j++) p[1 + j] = (float)((p[1 + j] - S * dC[j] / nq) * inv);
        }
    }
}
