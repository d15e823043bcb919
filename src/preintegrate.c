/* Pre-integrated classification between sheets (preintegrate.h).  A sheet
 * samples the density once a slab, so where opacity changes within a slab
 * (a thin translucent layer, the edge of a narrow iso-range) plain sheets
 * see it or miss it depending on where the samples fall: concentric rings.
 * The table holds, for a segment of a given length (half a slab in a
 * frame) whose density runs linearly
 * from f to b, the opacity and emitted colour of the exact integral of the
 * transfer function along it, so every value between the two samples
 * counts.  The integral over a piece of the segment comes from prefix sums
 * of the extinction (and colour times extinction) over the classification
 * table, so a range narrower than a table step of the 2-D table is not
 * missed; the pieces are composited front to back, so that the front of a
 * segment hides its back (Engel, Kraus and Ertl's self-attenuation). */
#include "preintegrate.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "pool.h"
#include "timing.h"

/* pieces a segment is composited from */
#define PIECES 8

/* extinction per view unit of an opacity per view unit (1 is capped: a
 * fully opaque slab stays opaque to float precision) */
static double extinction(double a)
{
    if (!(a > 0.0)) return 0.0;
    if (a > 1.0 - 1e-6) a = 1.0 - 1e-6;
    return -log1p(-a);
}

typedef struct prefix {
    double *t, *k; /* t[i]: integral of extinction up to entry i; k[3i + c]: of colour c times it */
    const vs_classify *c;
} prefix;

/* integrals from the domain's start to value v (linear between entries) */
static void prefix_at(const prefix *P, double v, double out[4])
{
    const vs_classify *c = P->c;
    double x = (v - c->vmin) * c->scale;
    if (!(x > 0.0)) x = 0.0;
    if (x > VS_TF_TABLE - 1) x = VS_TF_TABLE - 1;
    int i = (int)x;
    if (i > VS_TF_TABLE - 2) i = VS_TF_TABLE - 2;
    double f = x - i;
    out[0] = P->t[i] + f * (P->t[i + 1] - P->t[i]);
    for (int ch = 0; ch < 3; ch++)
        out[1 + ch] = P->k[3 * i + ch] + f * (P->k[3 * (i + 1) + ch] - P->k[3 * i + ch]);
}

typedef struct build_job {
    vs_preint *p;
    const vs_classify *c;
    double slab;
    const prefix *P;
} build_job;

/* rows [task * ROWS, task * ROWS + ROWS) of the table */
#define ROWS 8
static void build_rows(void *arg, int worker, int task)
{
    (void)worker;
    const build_job *J = arg;
    vs_preint *p = J->p;
    const vs_classify *c = J->c;
    const prefix *P = J->P;
    const double len = J->slab / PIECES;
    for (int i = task * ROWS; i < task * ROWS + ROWS && i < VS_PREINT_N; i++) {
        const double vf = p->vmin + i / p->scale;
        for (int j = 0; j < VS_PREINT_N; j++) {
            const double vb = p->vmin + j / p->scale;
            double at[PIECES + 1][4];
            for (int m = 0; m <= PIECES; m++) prefix_at(P, vf + (vb - vf) * m / PIECES, at[m]);
            double A = 0.0, C[3] = {0.0, 0.0, 0.0};
            const double dv = (vb - vf) / PIECES;
            for (int m = 0; m < PIECES && A < 1.0; m++) {
                double tau, kc[3];
                if (fabs(dv) * c->scale > 1e-6) {
                    tau = (at[m + 1][0] - at[m][0]) / dv;
                    for (int ch = 0; ch < 3; ch++) kc[ch] = (at[m + 1][1 + ch] - at[m][1 + ch]) / dv;
                } else { /* a constant density: the table at it */
                    const double v = vf + (m + 0.5) * dv;
                    float rgb[3];
                    double x = (v - c->vmin) * c->scale;
                    int e = x <= 0.0 ? 0 : x >= VS_TF_TABLE - 1 ? VS_TF_TABLE - 1 : (int)lrint(x);
                    tau = extinction(c->alpha[e]);
                    memcpy(rgb, c->color[e], sizeof rgb);
                    for (int ch = 0; ch < 3; ch++) kc[ch] = rgb[ch] * tau;
                }
                if (!(tau > 0.0)) continue;
                const double a = -expm1(-tau * len), w = (1.0 - A) * a / tau;
                for (int ch = 0; ch < 3; ch++) C[ch] += w * kc[ch];
                A += (1.0 - A) * a;
            }
            if (!(A >= 1e-30)) { /* as good as transparent: no colour whose inverse overflows */
                A = 0.0;
                C[0] = C[1] = C[2] = 0.0;
            }
            float *e = p->tab + 4 * ((size_t)i * VS_PREINT_N + j);
            e[0] = (float)(A > 1.0 ? 1.0 : A);
            for (int ch = 0; ch < 3; ch++) e[1 + ch] = (float)C[ch];
        }
    }
}

/* The largest z with every entry (i, j), i, j <= z, transparent (0 when
 * the first is not, or only it is): the air below a transfer function's
 * first opacity, where classification need not look anything up. */
static int zero_block(const float *tab)
{
    if (tab[0] != 0.0f) return 0;
    int z = 0;
    while (z + 1 < VS_PREINT_N) {
        const int k = z + 1;
        for (int i = 0; i <= k; i++)
            if (tab[4 * ((size_t)k * VS_PREINT_N + i)] != 0.0f || tab[4 * ((size_t)i * VS_PREINT_N + k)] != 0.0f)
                return z;
        z = k;
    }
    return z;
}

int vs_preint_update(vs_preint *p, const vs_classify *c, double slab, struct vs_pool *pool)
{
    if (p->tab && p->key_slab == slab && p->key_vmin == c->vmin && p->key_scale == c->scale &&
        !memcmp(p->key_alpha, c->alpha, sizeof p->key_alpha) && !memcmp(p->key_color, c->color, sizeof p->key_color))
        return 1;
    const double t0 = vs_now_ms();
    if (!p->tab && !(p->tab = aligned_alloc(64, sizeof(float) * 4 * VS_PREINT_N * VS_PREINT_N))) return 0;
    prefix P = {malloc(sizeof(double) * VS_TF_TABLE), malloc(sizeof(double) * 3 * VS_TF_TABLE), c};
    if (!P.t || !P.k) {
        free(P.t);
        free(P.k);
        return 0;
    }
    /* trapezoids between table entries, one entry = 1 / scale value units */
    const double h = 1.0 / c->scale;
    double tprev = extinction(c->alpha[0]);
    P.t[0] = 0.0;
    for (int ch = 0; ch < 3; ch++) P.k[ch] = 0.0;
    for (int i = 1; i < VS_TF_TABLE; i++) {
        const double tau = extinction(c->alpha[i]);
        P.t[i] = P.t[i - 1] + 0.5 * h * (tprev + tau);
        for (int ch = 0; ch < 3; ch++)
            P.k[3 * i + ch] = P.k[3 * (i - 1) + ch] + 0.5 * h * (c->color[i - 1][ch] * tprev + c->color[i][ch] * tau);
        tprev = tau;
    }
    p->vmin = c->vmin;
    p->scale = (VS_PREINT_N - 1) / (c->vmax - c->vmin);
    p->tabs = (vs_preint_tabs){p->tab, (float)p->vmin, (float)p->scale, VS_PREINT_N, 0.0f};
    build_job J = {p, c, slab, &P};
    const int ntask = (VS_PREINT_N + ROWS - 1) / ROWS;
    if (pool)
        vs_pool_run(pool, ntask, build_rows, &J);
    else
        for (int t = 0; t < ntask; t++) build_rows(&J, 0, t);
    free(P.t);
    free(P.k);
    p->tabs.zero_x = (float)zero_block(p->tab);
    memcpy(p->key_alpha, c->alpha, sizeof p->key_alpha);
    memcpy(p->key_color, c->color, sizeof p->key_color);
    p->key_vmin = c->vmin;
    p->key_scale = c->scale;
    p->key_slab = slab;
    p->ms_build = vs_now_ms() - t0;
    return 1;
}

/* segments a kernel call takes */
enum { CHUNK = 64 };

void vs_preint_alpha_row_gs(const vs_preint *p, const vs_kernels *k, float base, float *alpha, const float *q4,
                            const float *qn4, int n)
{
    float f[CHUNK], m[CHUNK], b[CHUNK];
    for (int i0 = 0; i0 < n; i0 += CHUNK) {
        const int c = n - i0 < CHUNK ? n - i0 : CHUNK;
        for (int i = 0; i < c; i++) {
            const float *q = q4 + 4 * (i0 + i), *qn = qn4 + 4 * (i0 + i);
            f[i] = q[0] + base;
            m[i] = vs_preint_mid_gs(q, qn) + base;
            b[i] = qn[0] + base;
        }
        k->preint_alpha(alpha + i0, f, m, b, c, &p->tabs);
    }
}

void vs_preint_alpha_row_cd(const vs_preint *p, const vs_kernels *k, float base, float *alpha, const float *qp,
                            const float *q, const float *qn, int qs, int n)
{
    float f[CHUNK], m[CHUNK], b[CHUNK];
    for (int i0 = 0; i0 < n; i0 += CHUNK) {
        const int c = n - i0 < CHUNK ? n - i0 : CHUNK;
        for (int i = 0; i < c; i++) {
            const size_t j = (size_t)qs * (size_t)(i0 + i);
            f[i] = q[j] + base;
            m[i] = vs_preint_mid_cd(qp[j], q[j], qn[j]) + base;
            b[i] = qn[j] + base;
        }
        k->preint_alpha(alpha + i0, f, m, b, c, &p->tabs);
    }
}

void vs_preint_free(vs_preint *p)
{
    if (!p) return;
    free(p->tab);
    free(p);
}
