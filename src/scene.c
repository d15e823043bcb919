/* Synthetic scenes: cube, sphere, ml (Marschner-Lobb), head (3-D Shepp-Logan)
 * and cell (microscopy-like tree of tubes).  Scenes with a closed form also
 * carry it (vs_analytic, in voxel-index coordinates) so that the reference
 * ray caster can render ground truth.  All parameters an analytic function
 * needs live in analytic.params: there is no global mutable state. */
#include "context.h"
#include "volume.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ cube */
/* params: [0] lo, [1] hi of the box, the same on every axis. */
static double cube_f(const void *prm, const double p[3])
{
    const double *q = prm;
    for (int a = 0; a < 3; a++)
        if (!(p[a] >= q[0] && p[a] <= q[1])) return 0.0;
    return 1.0;
}

static void cube_grad(const void *prm, const double p[3], double g[3])
{
    const double *q = prm;
    double c = 0.5 * (q[0] + q[1]), h = 0.5 * (q[1] - q[0]);
    /* The face whose plane is "most exceeded" is the face a crossing ray
     * passes through (inside: the nearest face). */
    int best = 0;
    double bd = -INFINITY;
    for (int a = 0; a < 3; a++) {
        double d = fabs(p[a] - c) - h;
        if (d > bd) {
            bd = d;
            best = a;
        }
    }
    g[0] = g[1] = g[2] = 0.0;
    g[best] = p[best] >= c ? -1.0 : 1.0; /* points into the dense region */
}

static vs_status make_cube(vs_context *ctx, int n, struct vs_volume **out)
{
    if (n < 8)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                            "scene cube:%d: N must be at least 8 to hold the 8^3 cube", n);
    const int dims[3] = {n, n, n};
    struct vs_volume *v;
    vs_status st = vs_volume_alloc(ctx, VS_F32, dims, NULL, &v);
    if (st != VS_OK) return st;
    float *d = v->data;
    int lo = n / 2 - 4, hi = n / 2 + 3;
    for (int k = lo; k <= hi; k++)
        for (int j = lo; j <= hi; j++)
            for (int i = lo; i <= hi; i++) d[((size_t)k * n + j) * n + i] = 1.0f;
    v->has_analytic = 1;
    v->analytic.f = cube_f;
    v->analytic.grad = cube_grad;
    v->analytic.iso = 0.5;
    /* iso-0.5 edge halfway between the last 1-voxel and the first 0-voxel */
    v->analytic.params[0] = lo - 0.5;
    v->analytic.params[1] = hi + 0.5;
    v->default_iso = 0.5;
    v->default_ramp = 0.02;
    *out = v;
    return VS_OK;
}

/* ---------------------------------------------------------------- sphere */
/* params: [0..2] centre, [3] radius R, [4] ramp half-width w (index units).
 * f = clamp(0.5 + (R - |p-c|)/(2w), 0, 1): a linear distance ramp, so the
 * iso-0.5 surface is the sphere of radius R. */
static double sphere_f(const void *prm, const double p[3])
{
    const double *q = prm;
    double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
    double r = sqrt(dx * dx + dy * dy + dz * dz);
    double f = 0.5 + (q[3] - r) / (2.0 * q[4]);
    return f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f;
}

static void sphere_grad(const void *prm, const double p[3], double g[3])
{
    const double *q = prm;
    double d[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
    double r = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double f = 0.5 + (q[3] - r) / (2.0 * q[4]);
    g[0] = g[1] = g[2] = 0.0;
    if (!(r > 0.0) || f <= 0.0 || f >= 1.0) return; /* flat where clamped */
    for (int a = 0; a < 3; a++) g[a] = -d[a] / (r * 2.0 * q[4]);
}

static vs_status make_sphere(vs_context *ctx, int n, struct vs_volume **out)
{
    const int dims[3] = {n, n, n};
    struct vs_volume *v;
    vs_status st = vs_volume_alloc(ctx, VS_F32, dims, NULL, &v);
    if (st != VS_OK) return st;
    double *q = v->analytic.params;
    q[0] = q[1] = q[2] = 0.5 * (n - 1);
    q[3] = 0.3 * n;
    q[4] = 4.0;
    float *d = v->data;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                const double p[3] = {i, j, k};
                d[((size_t)k * n + j) * n + i] = (float)sphere_f(q, p);
            }
    v->has_analytic = 1;
    v->analytic.f = sphere_f;
    v->analytic.grad = sphere_grad;
    v->analytic.iso = 0.5;
    v->default_iso = 0.5;
    v->default_ramp = 0.02;
    *out = v;
    return VS_OK;
}

/* ------------------------------------------------------ Marschner-Lobb */
/* params: [0] N, [1] f_M, [2] alpha.  x = -1 + 2 i/(N-1) on every axis. */
static double ml_f(const void *prm, const double p[3])
{
    const double *q = prm;
    double s = 2.0 / (q[0] - 1.0), fm = q[1], al = q[2];
    double x = -1.0 + s * p[0], y = -1.0 + s * p[1], z = -1.0 + s * p[2];
    double r = sqrt(x * x + y * y);
    double rho_r = cos(2.0 * M_PI * fm * cos(M_PI * r / 2.0));
    return (1.0 - sin(M_PI * z / 2.0) + al * (1.0 + rho_r)) / (2.0 * (1.0 + al));
}

static void ml_grad(const void *prm, const double p[3], double g[3])
{
    const double *q = prm;
    double s = 2.0 / (q[0] - 1.0), fm = q[1], al = q[2];
    double x = -1.0 + s * p[0], y = -1.0 + s * p[1], z = -1.0 + s * p[2];
    double r = sqrt(x * x + y * y);
    double k = 1.0 / (2.0 * (1.0 + al));
    /* d rho_r/dr * (1/r) = sin(2 pi fM cos(pi r/2)) pi^2 fM sin(pi r/2)/r;
     * sin(pi r/2)/r -> pi/2 at the axis, so the expression stays finite. */
    double sinc = r > 1e-9 ? sin(M_PI * r / 2.0) / r : M_PI / 2.0;
    double drr = sin(2.0 * M_PI * fm * cos(M_PI * r / 2.0)) * M_PI * M_PI * fm * sinc;
    g[0] = k * al * drr * x * s;
    g[1] = k * al * drr * y * s;
    g[2] = -k * (M_PI / 2.0) * cos(M_PI * z / 2.0) * s;
}

static vs_status make_ml(vs_context *ctx, int n, struct vs_volume **out)
{
    const int dims[3] = {n, n, n};
    struct vs_volume *v;
    vs_status st = vs_volume_alloc(ctx, VS_F32, dims, NULL, &v);
    if (st != VS_OK) return st;
    double *q = v->analytic.params;
    q[0] = n;
    q[1] = 6.0;
    q[2] = 0.25;
    float *d = v->data;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                const double p[3] = {i, j, k};
                d[((size_t)k * n + j) * n + i] = (float)ml_f(q, p);
            }
    v->has_analytic = 1;
    v->analytic.f = ml_f;
    v->analytic.grad = ml_grad;
    v->analytic.iso = 0.5;
    v->default_iso = 0.5;
    v->default_ramp = 0.02;
    *out = v;
    return VS_OK;
}

/* ------------------------------------------------------------------ head */
/* 3-D Shepp-Logan, "modified" (Toft's higher-contrast intensities), as in
 * Schabel's phantom3d: A, semi-axes a b c, centre x0 y0 z0, Euler angles
 * phi theta psi (degrees, zxz).  All theta are 0, so each rotation is about
 * z by phi+psi.  We place each ellipsoid geometrically, u = R (X - X0)
 * (phantom3d subtracts the centre after rotating; the difference only moves
 * the two tilted ventricles slightly). */
typedef struct head_ellipsoid {
    double A, ax[3], c[3], phi, theta, psi;
} head_ellipsoid;

enum { HEAD_N = 10 };
static const head_ellipsoid head_table[HEAD_N] = {
    {1.0, {.6900, .920, .810}, {0, 0, 0}, 0, 0, 0},
    {-.8, {.6624, .874, .780}, {0, -.0184, 0}, 0, 0, 0},
    {-.2, {.1100, .310, .220}, {.22, 0, 0}, -18, 0, 10},
    {-.2, {.1600, .410, .280}, {-.22, 0, 0}, 18, 0, 10},
    {.1, {.2100, .250, .410}, {0, .35, -.15}, 0, 0, 0},
    {.1, {.0460, .046, .050}, {0, .1, .25}, 0, 0, 0},
    {.1, {.0460, .046, .050}, {0, -.1, .25}, 0, 0, 0},
    {.1, {.0460, .023, .050}, {-.08, -.605, 0}, 0, 0, 0},
    {.1, {.0230, .023, .020}, {0, -.606, 0}, 0, 0, 0},
    {.1, {.0230, .046, .020}, {.06, -.605, 0}, 0, 0, 0},
};

/* params: [0..2] index of the phantom origin, [3..5] phantom units per index
 * step, [6 + 2e], [7 + 2e]: cos, sin of ellipsoid e's z-rotation. */
static void head_local(const double *q, int e, const double p[3], double u[3])
{
    const head_ellipsoid *E = &head_table[e];
    double X = (p[0] - q[0]) * q[3] - E->c[0];
    double Y = (p[1] - q[1]) * q[4] - E->c[1];
    double Z = (p[2] - q[2]) * q[5] - E->c[2];
    double cs = q[6 + 2 * e], sn = q[7 + 2 * e];
    u[0] = cs * X + sn * Y;
    u[1] = -sn * X + cs * Y;
    u[2] = Z;
}

static double head_q(const double *q, int e, const double p[3])
{
    const head_ellipsoid *E = &head_table[e];
    double u[3];
    head_local(q, e, p, u);
    double s = 0.0;
    for (int a = 0; a < 3; a++) s += (u[a] / E->ax[a]) * (u[a] / E->ax[a]);
    return s;
}

static double head_f(const void *prm, const double p[3])
{
    const double *q = prm;
    /* every other ellipsoid lies inside the skull's outer one: a quick out
     * for empty space (the ray caster samples it a lot) */
    if (head_q(q, 0, p) > 1.0) return 0.0;
    double f = 0.0;
    for (int e = 0; e < HEAD_N; e++)
        if (head_q(q, e, p) <= 1.0) f += head_table[e].A;
    return f;
}

/* The indicator sum has no gradient; we return the unit normal of the
 * ellipsoid boundary nearest to p (first-order distance |sqrt(q)-1|/|grad
 * sqrt(q)|), oriented towards increasing f and scaled by |A|.  At a refined
 * iso crossing that is the normal of the boundary that was crossed. */
static void head_grad(const void *prm, const double p[3], double g[3])
{
    const double *q = prm;
    double best = INFINITY;
    g[0] = g[1] = g[2] = 0.0;
    for (int e = 0; e < HEAD_N; e++) {
        const head_ellipsoid *E = &head_table[e];
        double u[3];
        head_local(q, e, p, u);
        double s2 = 0.0, du[3];
        for (int a = 0; a < 3; a++) {
            s2 += (u[a] / E->ax[a]) * (u[a] / E->ax[a]);
            du[a] = 2.0 * u[a] / (E->ax[a] * E->ax[a]); /* dq/du */
        }
        double cs = q[6 + 2 * e], sn = q[7 + 2 * e];
        /* dq/dindex = (R^T dq/du) * (phantom units per index) */
        double gi[3] = {(cs * du[0] - sn * du[1]) * q[3], (sn * du[0] + cs * du[1]) * q[4],
                        du[2] * q[5]};
        double m = sqrt(gi[0] * gi[0] + gi[1] * gi[1] + gi[2] * gi[2]);
        if (!(m > 0.0) || !(s2 > 0.0)) continue;
        double s = sqrt(s2);
        double dist = fabs(s - 1.0) * 2.0 * s / m; /* |s-1| / |grad s| */
        if (dist < best) {
            best = dist;
            for (int a = 0; a < 3; a++) g[a] = -E->A * gi[a] / m;
        }
    }
}

static vs_status make_head(vs_context *ctx, int nx, struct vs_volume **out)
{
    /* 256x256x145 by default; head:N scales z with x,y. */
    int nz = (int)lround(nx * 145.0 / 256.0);
    if (nz < 2) nz = 2;
    const int dims[3] = {nx, nx, nz};
    struct vs_volume *v;
    vs_status st = vs_volume_alloc(ctx, VS_F32, dims, NULL, &v);
    if (st != VS_OK) return st;
    double *q = v->analytic.params;
    /* The phantom's [-1,1] box is mapped onto the full index box on every
     * axis (voxel 0 at -1, voxel n-1 at +1), so the head fills the volume:
     * with spacing 1 it is physically flattened in z by 144/255, like a
     * scan with fewer slices than in-plane pixels. */
    for (int a = 0; a < 3; a++) {
        q[a] = 0.5 * (dims[a] - 1);
        q[3 + a] = 2.0 / (dims[a] - 1);
    }
    for (int e = 0; e < HEAD_N; e++) {
        double ang = (head_table[e].phi + head_table[e].psi) * (M_PI / 180.0);
        q[6 + 2 * e] = cos(ang);
        q[7 + 2 * e] = sin(ang);
    }
    /* Rasterize ellipsoid by ellipsoid within its bounding box, with the same
     * inside test as head_f so samples equal the analytic function. */
    float *d = v->data;
    for (int e = 0; e < HEAD_N; e++) {
        const head_ellipsoid *E = &head_table[e];
        double cs = q[6 + 2 * e], sn = q[7 + 2 * e];
        /* world half-extents of the rotated ellipsoid (X = R^T u) */
        double ext[3] = {sqrt(cs * cs * E->ax[0] * E->ax[0] + sn * sn * E->ax[1] * E->ax[1]),
                         sqrt(sn * sn * E->ax[0] * E->ax[0] + cs * cs * E->ax[1] * E->ax[1]),
                         E->ax[2]};
        int lo[3], hi[3];
        for (int a = 0; a < 3; a++) {
            lo[a] = (int)floor(q[a] + (E->c[a] - ext[a]) / q[3 + a]) - 1;
            hi[a] = (int)ceil(q[a] + (E->c[a] + ext[a]) / q[3 + a]) + 1;
            if (lo[a] < 0) lo[a] = 0;
            if (hi[a] > dims[a] - 1) hi[a] = dims[a] - 1;
        }
        float A = (float)E->A;
        for (int k = lo[2]; k <= hi[2]; k++)
            for (int j = lo[1]; j <= hi[1]; j++)
                for (int i = lo[0]; i <= hi[0]; i++) {
                    const double p[3] = {i, j, k};
                    if (head_q(q, e, p) <= 1.0) d[((size_t)k * dims[1] + j) * dims[0] + i] += A;
                }
    }
    v->has_analytic = 1;
    v->analytic.f = head_f;
    v->analytic.grad = head_grad;
    v->analytic.iso = 0.5;
    /* Toft intensities: skull shell 1.0, brain 0.2, ventricles 0, small
     * structures 0.3 -> iso 0.5 shows the skull. */
    v->default_iso = 0.5;
    v->default_ramp = 0.02; /* 2 % of the range [0,1] */
    *out = v;
    return VS_OK;
}

/* ------------------------------------------------------------------ cell */
/* Deterministic random numbers: splitmix64 (state on the stack). */
static uint64_t splitmix64(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static double rnd_uniform(uint64_t *s) { return (splitmix64(s) >> 11) * (1.0 / 9007199254740992.0); }

typedef struct cell_branch {
    double p[3], dir[3], r, intensity;
    int depth;
} cell_branch;

typedef struct cell_raster {
    uint8_t *sig; /* tube signal, max-combined */
    int dims[3];
    double sp[3];   /* spacing: physical units per index step */
    double zpsf;    /* axial elongation of the point-spread function */
} cell_raster;

/* A tapering tube from a (radius ra) to b (radius rb) with a Gaussian cross
 * profile I exp(-ln2 (d/r)^2): the half-maximum sits at the tube surface. */
static void cell_segment(cell_raster *cr, const double a[3], const double b[3], double ra, double rb,
                         double I)
{
    double rmax = ra > rb ? ra : rb;
    double reach = 2.6 * rmax; /* profile < 1% of I beyond 2.6 r */
    int lo[3], hi[3];
    for (int x = 0; x < 3; x++) {
        double m = x == 2 ? reach * cr->zpsf : reach;
        double mn = (a[x] < b[x] ? a[x] : b[x]) - m, mx = (a[x] > b[x] ? a[x] : b[x]) + m;
        lo[x] = (int)floor(mn / cr->sp[x]);
        hi[x] = (int)ceil(mx / cr->sp[x]);
        if (lo[x] < 0) lo[x] = 0;
        if (hi[x] > cr->dims[x] - 1) hi[x] = cr->dims[x] - 1;
        if (lo[x] > hi[x]) return;
    }
    double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double L2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    for (int k = lo[2]; k <= hi[2]; k++)
        for (int j = lo[1]; j <= hi[1]; j++) {
            uint8_t *row = cr->sig + ((size_t)k * cr->dims[1] + j) * cr->dims[0];
            for (int i = lo[0]; i <= hi[0]; i++) {
                double p[3] = {i * cr->sp[0] - a[0], j * cr->sp[1] - a[1], k * cr->sp[2] - a[2]};
                double t = L2 > 0 ? (p[0] * ab[0] + p[1] * ab[1] + p[2] * ab[2]) / L2 : 0.0;
                t = t < 0 ? 0 : t > 1 ? 1 : t;
                double dx = p[0] - t * ab[0], dy = p[1] - t * ab[1], dz = (p[2] - t * ab[2]) / cr->zpsf;
                double r = ra + t * (rb - ra);
                double u = (dx * dx + dy * dy + dz * dz) / (r * r);
                if (u > 6.8) continue;
                double val = I * exp(-M_LN2 * u);
                int iv = (int)(val + 0.5);
                if (iv > row[i]) row[i] = (uint8_t)(iv > 255 ? 255 : iv);
            }
        }
}

static void normalize(double v[3])
{
    double m = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (m > 0) {
        v[0] /= m; v[1] /= m; v[2] /= m;
    } else {
        v[0] = 1; v[1] = 0; v[2] = 0;
    }
}

static vs_status make_cell(vs_context *ctx, int nx, struct vs_volume **out)
{
    /* 512x512x76 u8 with spacing 1,1,2.5: a confocal stack with thick
     * slices.  cell:N scales the whole scene with x,y. */
    int nz = (int)lround(nx * 76.0 / 512.0);
    if (nz < 2) nz = 2;
    const int dims[3] = {nx, nx, nz};
    const double spacing[3] = {1.0, 1.0, 2.5};
    struct vs_volume *v;
    vs_status st = vs_volume_alloc(ctx, VS_U8, dims, spacing, &v);
    if (st != VS_OK) return st;
    size_t nvox = (size_t)dims[0] * dims[1] * dims[2];
    cell_raster cr = {.sig = calloc(nvox, 1), .dims = {dims[0], dims[1], dims[2]},
                      .sp = {1.0, 1.0, 2.5}, .zpsf = 1.6};
    enum { MAX_PENDING = 512, MAX_SEGMENTS = 3000 };
    cell_branch *stack = malloc(MAX_PENDING * sizeof *stack);
    if (!cr.sig || !stack) {
        free(cr.sig);
        free(stack);
        vs_volume_release(v);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "scene cell: out of memory");
    }
    const double sc = nx / 512.0; /* lengths are designed for 512 */
    const double ext[3] = {(dims[0] - 1) * 1.0, (dims[1] - 1) * 1.0, (dims[2] - 1) * 2.5};
    const double ctr[3] = {0.5 * ext[0], 0.5 * ext[1], 0.5 * ext[2]};
    uint64_t rng = 0x5EEDC0FFEE1234ull;

    /* soma: a short fat tube (a rounded blob, slightly elongated) */
    {
        double a[3] = {ctr[0] - 6 * sc, ctr[1] - 4 * sc, ctr[2]};
        double b[3] = {ctr[0] + 6 * sc, ctr[1] + 4 * sc, ctr[2]};
        cell_segment(&cr, a, b, 16 * sc, 14 * sc, 235);
    }
    int np = 0;
    const int primaries = 7;
    for (int b = 0; b < primaries; b++) {
        double az = 2.0 * M_PI * (b + 0.6 * rnd_uniform(&rng)) / primaries;
        double el = (rnd_uniform(&rng) - 0.5) * 0.5;
        cell_branch *br = &stack[np++];
        br->dir[0] = cos(az) * cos(el);
        br->dir[1] = sin(az) * cos(el);
        br->dir[2] = sin(el);
        for (int x = 0; x < 3; x++) br->p[x] = ctr[x] + 12 * sc * br->dir[x];
        br->r = (4.5 + 1.5 * rnd_uniform(&rng)) * sc;
        br->intensity = 175 + 35 * rnd_uniform(&rng);
        br->depth = 0;
    }
    int segments = 0;
    while (np > 0 && segments < MAX_SEGMENTS) {
        cell_branch br = stack[--np];
        while (br.r > 1.1 * sc && segments < MAX_SEGMENTS) {
            double len = (10 + 10 * rnd_uniform(&rng)) * sc;
            /* random walk of the direction; z is damped to stay in the slab */
            for (int x = 0; x < 3; x++) br.dir[x] += 0.45 * (rnd_uniform(&rng) - 0.5);
            br.dir[2] *= 0.7;
            normalize(br.dir);
            double nxt[3], r1 = br.r * (0.94 + 0.03 * rnd_uniform(&rng));
            int inside = 1;
            for (int x = 0; x < 3; x++) {
                nxt[x] = br.p[x] + len * br.dir[x];
                if (nxt[x] < -10 * sc || nxt[x] > ext[x] + 10 * sc) inside = 0;
            }
            /* keep the tree in the stack: reflect z at the slab faces */
            if (nxt[2] < 3.0 || nxt[2] > ext[2] - 3.0) br.dir[2] = -br.dir[2];
            cell_segment(&cr, br.p, nxt, br.r, r1, br.intensity);
            segments++;
            if (!inside) break;
            memcpy(br.p, nxt, sizeof nxt);
            br.r = r1;
            if (br.depth < 5 && np < MAX_PENDING && rnd_uniform(&rng) < 0.16) {
                cell_branch *ch = &stack[np++];
                *ch = br;
                double side[3] = {-br.dir[1], br.dir[0], (rnd_uniform(&rng) - 0.5) * 0.4};
                double sgn = rnd_uniform(&rng) < 0.5 ? -1.0 : 1.0;
                double ang = 0.5 + 0.5 * rnd_uniform(&rng);
                for (int x = 0; x < 3; x++) ch->dir[x] = cos(ang) * br.dir[x] + sgn * sin(ang) * side[x];
                normalize(ch->dir);
                ch->r = br.r * 0.75;
                ch->intensity = br.intensity * (0.85 + 0.15 * rnd_uniform(&rng));
                ch->depth = br.depth + 1;
                br.r *= 0.9;
            }
        }
    }
    free(stack);

    /* Camera noise: background offset + Gaussian-ish read noise, signal-
     * dependent shot noise, and sparse bright speckle.  A counter-based hash
     * per voxel keeps it deterministic. */
    uint8_t *d = v->data;
    for (size_t i = 0; i < nvox; i++) {
        uint64_t h = 0xC0FFEEull ^ (i * 0x9E3779B97F4A7C15ull);
        uint64_t r0 = splitmix64(&h), r1 = splitmix64(&h);
        double u0 = (double)(r0 & 0xFFFFF) / 1048576.0, u1 = (double)((r0 >> 20) & 0xFFFFF) / 1048576.0,
               u2 = (double)((r0 >> 40) & 0xFFFFF) / 1048576.0;
        double gauss = (u0 + u1 + u2 - 1.5) * 2.0; /* ~N(0,1) */
        double s = cr.sig[i];
        double val = 14.0 + 5.0 * gauss + s * (1.0 + 0.12 * gauss);
        if ((r1 & 0xFFF) < 2) val += 40.0 + 80.0 * (double)((r1 >> 12) & 0xFF) / 255.0;
        int iv = (int)lround(val);
        d[i] = (uint8_t)(iv < 0 ? 0 : iv > 255 ? 255 : iv);
    }
    free(cr.sig);
    v->has_analytic = 0;
    /* half-maximum of the dimmest branches (~175/2) plus the background */
    v->default_iso = 100.0;
    v->default_ramp = 10.0;
    *out = v;
    return VS_OK;
}

/* ---------------------------------------------------------------- entry */
vs_status vs_volume_scene(vs_context *ctx, const char *spec, vs_volume **out)
{
    if (!out) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "scene: NULL output");
    *out = NULL;
    if (!spec) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "scene: NULL name");
    char name[32];
    const char *colon = strchr(spec, ':');
    size_t len = colon ? (size_t)(colon - spec) : strlen(spec);
    if (len == 0 || len >= sizeof name)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                            "scene '%s': expected NAME or NAME:N (cube, sphere, ml, head, cell)", spec);
    memcpy(name, spec, len);
    name[len] = '\0';
    long n = -1;
    if (colon) {
        char *end = NULL;
        errno = 0;
        n = strtol(colon + 1, &end, 10);
        if (end == colon + 1 || *end != '\0' || errno != 0 || n < 2 || n > 1024)
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                                "scene '%s': N must be an integer in 2..1024", spec);
    }
    struct vs_volume *v = NULL;
    vs_status st;
    if (!strcmp(name, "cube"))
        st = make_cube(ctx, n > 0 ? (int)n : 16, &v);
    else if (!strcmp(name, "sphere"))
        st = make_sphere(ctx, n > 0 ? (int)n : 64, &v);
    else if (!strcmp(name, "ml"))
        st = make_ml(ctx, n > 0 ? (int)n : 41, &v);
    else if (!strcmp(name, "head"))
        st = make_head(ctx, n > 0 ? (int)n : 256, &v);
    else if (!strcmp(name, "cell"))
        st = make_cell(ctx, n > 0 ? (int)n : 512, &v);
    else
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                            "unknown scene '%s' (known: cube, sphere, ml, head, cell)", name);
    if (st != VS_OK) return st;
    vs_volume_update_range(v);
    *out = v;
    return VS_OK;
}
