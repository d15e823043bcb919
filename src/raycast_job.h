/* The reference ray caster's shared state (raycast.c casts, raycast_skip.c
 * builds the empty-space skipping grid). */
#ifndef VS_RAYCAST_JOB_H
#define VS_RAYCAST_JOB_H

#include "camera.h"
#include "classify.h"
#include "light.h"
#include "volume.h"

#include <math.h>
#include <stdatomic.h>
#include <stdint.h>

struct vs_pool;

enum { MODE_ANALYTIC, MODE_GAUSS, MODE_TRILINEAR };
enum { BRICK = 2, MAX_TAPS = 20 }; /* 2^3 bricks: the kernel's reach dominates */

typedef struct rc_job {
    const struct vs_volume *vol;
    const vs_settings *s;
    vs_camera cam;
    vs_classify *cls;
    vs_light light;
    int mode;
    int normalize;         /* Gaussian: weights over their lattice sum     */
    int faces;             /* the faces would show (vs_classify_faces,
                              face_cover.h): samples inside the volume's
                              faces, reconstructed from the voxels that
                              reach alone                                   */
    double R, R2, b;       /* kernel radius, its square, normalization      */
    double t_near;         /* depth rays start at (vs_camera_near_cut)      */
    double base;           /* sampled volumes: values are reconstructed less
                              this (the volume's minimum), as splatting does,
                              so that outside the volume reads as the minimum */
    double step;           /* view units                                    */
    double box_lo[3], box_hi[3]; /* index box where samples are taken      */
    int refine;            /* bisect iso crossings (analytic, iso-range)    */
    /* empty-space skipping: brick b covers points [org + B b, org + B (b+1)) */
    double org;
    int nb[3];
    uint8_t *skip;         /* 1: no point of the brick can have opacity > 0 */
    float *rgba;
    double *ms;            /* per worker: time spent casting rows           */
    atomic_int rows_done, cancel;
} rc_job;

/* ---- voxel access: values less base; outside the volume, and non-finite
 * values, count as base (0 here) ---- */

/* Values of row (j,k) at x = i0..i1 (all inside), less base, into out[]. */
static inline void vs_rc_fetch_row(const struct vs_volume *v, int j, int k, int i0, int i1, double *out, double base)
{
    size_t row = ((size_t)k * v->dims[1] + j) * v->dims[0];
    int n = i1 - i0 + 1;
    switch (v->type) {
    case VS_U8: {
        const uint8_t *p = (const uint8_t *)v->data + row + i0;
        for (int i = 0; i < n; i++) out[i] = p[i] - base;
    } break;
    case VS_I16: {
        const int16_t *p = (const int16_t *)v->data + row + i0;
        for (int i = 0; i < n; i++) out[i] = p[i] - base;
    } break;
    case VS_U16: {
        const uint16_t *p = (const uint16_t *)v->data + row + i0;
        for (int i = 0; i < n; i++) out[i] = p[i] - base;
    } break;
    default: {
        const float *p = (const float *)v->data + row + i0;
        for (int i = 0; i < n; i++) out[i] = isfinite(p[i]) ? p[i] - base : 0.0;
    } break;
    }
}

/* The brick grid of J->skip (J->org, J->nb set too), on the pool. */
vs_status vs_raycast_build_skip(vs_context *ctx, rc_job *J, struct vs_pool *pool);

#endif
