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

#include <limits.h>
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

/* cos and sin of 2 pi w l for the lanes l < 8 */
static void lanes(double w, float cl[8], float sl[8])
{
    for (int l = 0; l < 8; l++) {
        cl[l] = (float)cos(2.0 * M_PI * w * l);
        sl[l] = (float)sin(2.0 * M_PI * w * l);
    }
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
        lanes(r->ux[a], r->L.cl[a], r->L.sl[a]);
    }
}

/* floor(x / 8) for any int */
static inline int block_of(int x) { return x >= 0 ? x / 8 : -((7 - x) / 8); }

size_t vs_gs_ripple_tile_floats(int tw, int th) { return 6 * ((size_t)tw / 8 + 3 + (size_t)th); }

void vs_gs_ripple_tile_init(vs_gs_ripple_tile *T, float *tables, int x0, int y0, int tw, int th)
{
    T->k = T->kc = INT_MIN;
    T->b0 = block_of(x0);
    /* the own columns' blocks and one past them (a span's last vector
     * reads it): at most tw / 8 + 3 */
    T->nb = block_of(x0 + tw - 1) + 2 - T->b0;
    T->y0 = y0;
    T->nr = th;
    T->xr = (float(*)[6])tables;
    T->yr = T->xr + T->nb;
}

/* With perspective sheet k's pixels are 1 / sk apart at depth 0: pixel
 * (x, y) lies at (cx (1 - isk) + isk x, cy (1 - isk) + isk y) there. */
static double sheet_isk(const vs_frame *F, int k)
{
    return F->cam.persp ? 1.0 / vs_camera_sheet_scale(&F->cam, k, F->fp.slab) : 1.0;
}

/* The tables for sheet k. */
static void tile_tables(const vs_frame *F, int k, vs_gs_ripple_tile *T)
{
    const vs_gs_ripple *r = &F->ripple;
    const vs_camera *cam = &F->cam;
    const double isk = sheet_isk(F, k);
    T->k = k;
    T->kc = INT_MIN;
    if (cam->persp) {
        T->L = r->L;
        for (int a = 0; a < 3; a++) lanes(r->ux[a] * isk, T->L.cl[a], T->L.sl[a]);
    }
    for (int b = 0; b < T->nb; b++)
        for (int a = 0; a < 3; a++) sincos_2pi(r, r->ux[a] * isk * 8.0 * (T->b0 + b), &T->xr[b][a], &T->xr[b][3 + a]);
    for (int y = 0; y < T->nr; y++)
        for (int a = 0; a < 3; a++) sincos_2pi(r, r->uy[a] * isk * (T->y0 + y), &T->yr[y][a], &T->yr[y][3 + a]);
}

const vs_ripple_row *vs_gs_ripple_at(const vs_frame *F, int k, int x, int y, vs_ripple_row *R, vs_gs_ripple_tile *T)
{
    const vs_gs_ripple *r = &F->ripple;
    const vs_camera *cam = &F->cam;
    if (T->k == INT_MIN || (cam->persp && T->k != k)) tile_tables(F, k, T);
    if (T->kc != k) {
        /* the phase of pixel (0, 0) at sheet k */
        const double isk = sheet_isk(F, k);
        const double ox = cam->persp ? cam->cx * (1.0 - isk) : 0.0, oy = cam->persp ? cam->cy * (1.0 - isk) : 0.0;
        for (int a = 0; a < 3; a++)
            sincos_2pi(r, r->u0[a] + r->ux[a] * ox + r->uy[a] * oy + r->uz[a] * (k * F->fp.slab), &T->C0[a], &T->S0[a]);
        T->kc = k;
    }
    /* the row's phase at x = 0: sheet k's at (0, 0) turned by row y's */
    const float *yr = T->yr[y - T->y0];
    for (int a = 0; a < 3; a++) {
        R->C[a] = T->C0[a] * yr[a] - T->S0[a] * yr[3 + a];
        R->S[a] = T->S0[a] * yr[a] + T->C0[a] * yr[3 + a];
    }
    R->L = cam->persp ? &T->L : &r->L;
    const int b = block_of(x);
    R->xr = (const float(*)[6])T->xr + (b - T->b0);
    R->m = x - 8 * b;
    return R;
}
