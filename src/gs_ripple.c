/* Post-gs without the kernel's lattice ripple (gs_ripple.h).
 *
 * The kernel h(u) = b exp(-a |u|^2) summed over the lattice is
 * b prod_a theta(u_a), theta(x) = sum_n exp(-a (x - n)^2), whose Fourier
 * series is sqrt(pi / a) (1 + c cos 2 pi x + ...) with c = 2 exp(-pi^2 / a)
 * (1.6e-3; the next term's is 2 exp(-4 pi^2 / a), 8.6e-13).  To first order in c
 * the sum is 1 + c sum_a cos 2 pi u_a, and its gradient per index axis
 * -2 pi c sin 2 pi u_a.  A sheet holds the kernel averaged over its slab
 * along the view direction e (index per view unit; the splat weights are
 * b / s): over the slab from u that gradient integrates to A_a(u) = c
 * (cos 2 pi (u_a + s e_a) - cos 2 pi u_a) / e_a, so the sheet's ripple
 * gradient in view space (pixels, view units) is Minv^T A / s over a value
 * of 1 to first order.  classify_gs divides the splatted gradient by s
 * once more (g = grad S / s), so a pixel of value q takes g - q Minv^T A /
 * s^2: the gradient of the normalised reconstruction S / W over s, up to
 * the factor 1 / W (1 +- 0.5 %), which shading does not see. */
#include "gs_ripple.h"

#include <math.h>

/* cos and sin of 2 pi u: the table's entry below u and the rest by its
 * Taylor series (under 0.025 rad: series error under 2e-8, float rounding
 * about 6e-8) */
static inline void sincos_2pi(const vs_gs_ripple *r, double u, float *c, float *s)
{
    double f = (u - floor(u)) * VS_RIPPLE_TAB;
    int i = (int)f;
    if (i >= VS_RIPPLE_TAB) i = VS_RIPPLE_TAB - 1;
    const float d = (float)((f - i) * (2.0 * M_PI / VS_RIPPLE_TAB)), d2 = d * d;
    const float cd = 1.0f - 0.5f * d2, sd = d * (1.0f - d2 * (1.0f / 6.0f));
    *c = r->cs[i][0] * cd - r->cs[i][1] * sd;
    *s = r->cs[i][1] * cd + r->cs[i][0] * sd;
}

/* cos and sin of 2 pi w l for the lanes l < 8, and of 2 pi w 8 */
static void lanes(double w, float cl[8], float sl[8], float *c8, float *s8)
{
    for (int l = 0; l < 8; l++) {
        cl[l] = (float)cos(2.0 * M_PI * w * l);
        sl[l] = (float)sin(2.0 * M_PI * w * l);
    }
    *c8 = (float)cos(2.0 * M_PI * w * 8);
    *s8 = (float)sin(2.0 * M_PI * w * 8);
}

/* the lanes of a sheet whose pixels are 1 / isk apart at depth 0 (1:
 * orthographic); its gradients stay per pixel at depth 0, as post-gs
 * splats them */
static void sheet_lanes(const vs_gs_ripple *r, double isk, vs_ripple_lanes *L)
{
    *L = r->L;
    for (int a = 0; a < 3; a++) lanes(r->ux[a] * isk, L->cl[a], L->sl[a], &L->c8[a], &L->s8[a]);
}

void vs_gs_ripple_setup(vs_frame *F)
{
    vs_gs_ripple *r = &F->ripple;
    r->on = F->pipeline == VS_PIPELINE_POST_GS && F->s->gs_normalize;
    if (!r->on) return;
    const vs_camera *cam = &F->cam;
    const double s = F->fp.slab, c = 2.0 * exp(-M_PI * M_PI / F->fp.a);
    for (int i = 0; i < VS_RIPPLE_TAB; i++) {
        r->cs[i][0] = (float)cos(2.0 * M_PI * i / VS_RIPPLE_TAB);
        r->cs[i][1] = (float)sin(2.0 * M_PI * i / VS_RIPPLE_TAB);
    }
    for (int a = 0; a < 3; a++) {
        r->ux[a] = cam->Minv[a][0];
        r->uy[a] = cam->Minv[a][1];
        r->uz[a] = cam->Minv[a][2];
        r->u0[a] = -(cam->Minv[a][0] * cam->t[0] + cam->Minv[a][1] * cam->t[1] + cam->Minv[a][2] * cam->t[2]);
        /* A(u) = c (cos 2 pi (u + s e) - cos 2 pi u) / e as ca cos 2 pi u + cb sin 2 pi u */
        const double e = cam->Minv[a][2], w = 2.0 * M_PI * s * e;
        r->L.ca[a] = (float)(fabs(w) > 1e-6 ? -2.0 * c * sin(0.5 * w) * sin(0.5 * w) / e : -c * M_PI * w * s);
        r->L.cb[a] = (float)(fabs(w) > 1e-6 ? -c * sin(w) / e : -2.0 * M_PI * c * s);
        for (int j = 0; j < 3; j++) r->L.m[a][j] = (float)(cam->Minv[a][j] / (s * s));
        lanes(r->ux[a], r->L.cl[a], r->L.sl[a], &r->L.c8[a], &r->L.s8[a]);
    }
}

const vs_ripple_row *vs_gs_ripple_at(const vs_frame *F, int k, int x, int y, vs_ripple_row *R, vs_ripple_lanes *sheet,
                                     int *sheet_k)
{
    const vs_gs_ripple *r = &F->ripple;
    const vs_camera *cam = &F->cam;
    double x0 = x, y0 = y;
    R->L = &r->L;
    if (cam->persp) {
        /* sheet k's pixels seen from their depth-0 points, a pixel being
         * 1 / sk there */
        const double isk = 1.0 / vs_camera_sheet_scale(cam, k, F->fp.slab);
        x0 = cam->cx + (x - cam->cx) * isk;
        y0 = cam->cy + (y - cam->cy) * isk;
        if (*sheet_k != k) sheet_lanes(r, isk, sheet);
        *sheet_k = k;
        R->L = sheet;
    }
    const double z = k * F->fp.slab;
    for (int a = 0; a < 3; a++)
        sincos_2pi(r, r->u0[a] + r->ux[a] * x0 + r->uy[a] * y0 + r->uz[a] * z, &R->C[a], &R->S[a]);
    return R;
}
