/* A render case decoded from bytes, shared by the libFuzzer harness
 * (tests/fuzz/fuzz_render.c) and the seeded driver in the normal suite
 * (tests/test_render_fuzz.c).  The first bytes are the settings, the rest
 * the voxels, so that a mutation of one byte changes one thing.
 *
 * A case is a small volume of any voxel type with hostile values (NaN,
 * +-Inf, denormals, +-FLT_MAX, constant, one voxel, 1x1xN) and settings
 * from every corner: each pipeline and the ray caster, zoom 1e-3..1e3,
 * slab, kernel, perspective, views along the axes and grazing, tiles,
 * iso-ranges and stepped transfer functions with zero and full opacity,
 * cancellation.  rc_check() renders it with 1 thread and with 2 or 3 and
 * returns NULL, or what broke a promise: a status outside the enum, an
 * error without a message, an image of the wrong size, a colour that is
 * not finite, alpha outside [0,1], images that differ between thread
 * counts.  Sizes stay small so that a case takes milliseconds; in about a
 * third of the cases (shape bit 7) the volume is blown up 8x by
 * replication, up to 56 per side, so that small images splat levels of
 * detail (600 seeded cases reach levels 1-4 in 164 renders). */
#ifndef VS_RENDER_CASE_H
#define VS_RENDER_CASE_H

#include "vsplat.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct rc_bytes {
    const uint8_t *d;
    size_t n, i;
} rc_bytes;

static inline unsigned rc_u8(rc_bytes *b) { return b->i < b->n ? b->d[b->i++] : 0u; }
static inline unsigned rc_u16(rc_bytes *b) { return rc_u8(b) | rc_u8(b) << 8; }
static inline double rc_unit(rc_bytes *b) { return rc_u16(b) / 65535.0; }
/* lo..hi, evenly in the logarithm */
static inline double rc_log(rc_bytes *b, double lo, double hi) { return lo * pow(hi / lo, rc_unit(b)); }

/* Special float values, the hostile ones first. */
static inline float rc_special(unsigned k, float scale)
{
    switch (k % 16) {
    case 0: return NAN;
    case 1: return INFINITY;
    case 2: return -INFINITY;
    case 3: return 1e-40f;  /* denormal */
    case 4: return -1e-40f;
    case 5: return FLT_MAX;
    case 6: return -FLT_MAX;
    case 7: return FLT_MIN;
    case 8: return 0.0f;
    case 9: return -0.0f;
    case 10: return 1.0f;
    case 11: return -1.0f;
    default: return scale * (float)(k % 16 - 12) / 3.0f; /* 0, 1/3, 2/3, 1 of scale */
    }
}

typedef struct rc_case {
    vs_type type;
    int dims[3];
    double spacing[3];
    vs_settings s;
    vs_tf_point tf[8];
    int cancel_after; /* progress calls before asking to stop; <0 never */
    int threads_n;    /* the thread count compared with 1 */
    int blow_up;      /* replicate each voxel into 8^3 (levels of detail) */
} rc_case;

typedef struct rc_progress {
    int calls, cancel_after;
} rc_progress;

static inline int rc_progress_fn(void *user, double fraction)
{
    rc_progress *p = user;
    if (!(fraction >= 0.0 && fraction <= 1.0)) abort(); /* the API promises [0,1] */
    return p->cancel_after >= 0 && p->calls++ >= p->cancel_after;
}

/* Fills the voxels of v from the remaining bytes. */
static inline void rc_fill(rc_bytes *b, vs_volume *v, vs_type type, size_t n)
{
    unsigned mode = rc_u8(b) % 4; /* 0 per voxel, 1 constant, 2 one voxel, 3 ramp + specials */
    unsigned at = rc_u16(b);
    void *data = vs_volume_data(v);
    float scale = (float)rc_log(b, 1e-30, 1e30);
    for (size_t i = 0; i < n; i++) {
        unsigned k;
        if (mode == 1) k = at;
        else if (mode == 2) k = i == at % n ? at >> 4 : 8;
        else if (mode == 3) k = (i * 7 + at) % 23 == 0 ? rc_u8(b) : 12 + (unsigned)(i % 4);
        else k = rc_u8(b);
        unsigned k16 = k * 257u + (k >> 3);
        switch (type) {
        case VS_U8: ((uint8_t *)data)[i] = (uint8_t)(k % 4 == 0 ? 0 : k % 4 == 1 ? 255 : k); break;
        case VS_I16:
            ((int16_t *)data)[i] = (int16_t)(k % 4 == 0 ? INT16_MIN : k % 4 == 1 ? INT16_MAX : (int)k16 - 32768);
            break;
        case VS_U16: ((uint16_t *)data)[i] = (uint16_t)(k % 4 == 0 ? 0 : k % 4 == 1 ? 65535 : k16); break;
        default: ((float *)data)[i] = rc_special(k, scale); break;
        }
    }
    vs_volume_update_range(v);
}

/* Decodes the settings of a case. */
static inline void rc_decode(rc_bytes *b, rc_case *c)
{
    memset(c, 0, sizeof *c);
    vs_settings *s = &c->s;
    vs_settings_init(s);
    c->type = (vs_type)(rc_u8(b) % 4);
    unsigned shape = rc_u8(b);
    for (int a = 0; a < 3; a++) c->dims[a] = 1 + (int)(rc_u8(b) % 7);
    if (shape % 5 <= 1) { /* one voxel, or 1x1xN along any axis */
        c->dims[0] = c->dims[1] = c->dims[2] = 1;
        if (shape % 5 == 1) c->dims[(shape >> 3) % 3] = 2 + (int)((shape >> 5) % 7) * 2;
    } else {
        c->blow_up = (shape >> 7) & 1; /* a bit the shapes above do not read */
    }
    /* anisotropy up to 16:1 (at 165:1 with radius 7.75 one 20x9 image took
     * 1.2 s, 14 s under ASan: slow, not wrong) */
    for (int a = 0; a < 3; a++) c->spacing[a] = (rc_u8(b) & 1) ? rc_log(b, 0.25, 4.0) : 1.0;

    s->pipeline = (vs_pipeline)(rc_u8(b) % 5);
    s->width = 1 + (int)(rc_u8(b) % 24);
    s->height = 1 + (int)(rc_u8(b) % 24);
    unsigned view = rc_u8(b);
    static const double axes[6][2] = {{0, 0}, {90, 0}, {180, 0}, {270, 0}, {0, 90}, {0, -90}};
    if (view % 3 == 0) { /* along an axis */
        s->azimuth = axes[(view >> 2) % 6][0];
        s->elevation = axes[(view >> 2) % 6][1];
    } else if (view % 3 == 1) { /* grazing: a hair off an axis */
        double eps = rc_log(b, 1e-9, 1e-1) * ((view & 8) ? -1 : 1);
        s->azimuth = axes[(view >> 4) % 6][0] + ((view & 4) ? eps : 0.0);
        s->elevation = axes[(view >> 4) % 6][1] + ((view & 4) ? 0.0 : eps);
    } else {
        s->azimuth = rc_unit(b) * 720.0 - 360.0;
        s->elevation = rc_unit(b) * 360.0 - 180.0;
    }
    s->zoom = rc_log(b, 1e-3, 1e3);
    unsigned f = rc_u8(b);
    if (f & 1) {
        s->has_center = 1;
        for (int a = 0; a < 3; a++) s->center[a] = rc_unit(b) * 4.0 * c->dims[a] - 1.5 * c->dims[a];
    }
    if (f & 2) s->perspective_fov = 1.0 + rc_unit(b) * 169.0;
    if (f & 4) s->slab = rc_log(b, 0.01, 64.0);
    if (f & 8) s->kernel_radius = 0.5 + rc_unit(b) * 7.5;
    if (f & 16) s->footprint_resolution = 8 + (int)(rc_u8(b) % 250);
    if (f & 32) s->depth_resolution = 8 + (int)(rc_u8(b) * 4u);
    if (f & 64) s->seam = (int)(rc_u8(b) % 6) - 1;
    if (f & 128) s->tile_size = 8 + (int)(rc_u8(b) % 57);

    unsigned cl = rc_u8(b);
    if (cl % 3 == 1) { /* iso-range, ends from specials or the unit */
        s->has_iso = 1;
        unsigned e = rc_u8(b);
        double lo = (e & 1) ? rc_special(rc_u8(b), 1.0f) : rc_unit(b) * 2.0 - 0.5;
        double hi = (e & 2) ? INFINITY : (e & 4) ? lo : lo + rc_log(b, 1e-6, 1e6);
        if (c->type != VS_F32) lo *= 65535.0, hi *= 65535.0;
        s->iso_lo = lo;
        s->iso_hi = hi;
        s->ramp = (e & 8) ? -1.0 : (e & 16) ? 0.0 : rc_log(b, 1e-9, 1e9);
        s->iso_opacity = (e & 32) ? 0.0f : (e & 64) ? 1.0f : (float)rc_unit(b);
    } else if (cl % 3 == 2) { /* transfer function with steps */
        int n = 1 + (int)(rc_u8(b) % 8);
        double v = (rc_u8(b) & 1) ? rc_special(rc_u8(b), 1.0f) : rc_unit(b) - 0.25;
        if (!isfinite(v)) v = 0.0;
        for (int i = 0; i < n; i++) {
            unsigned p = rc_u8(b);
            if (i > 0 && (p & 3) != 0) v += (p & 4) ? rc_log(b, 1e-30, 1e30) : rc_unit(b); /* else a step */
            c->tf[i].value = c->type == VS_F32 ? v : v * 65535.0;
            c->tf[i].r = (float)((p >> 3) & 1);
            c->tf[i].g = (float)rc_unit(b);
            c->tf[i].b = 0.5f;
            c->tf[i].a = (p & 32) ? 0.0f : (p & 64) ? 1.0f : (float)rc_unit(b);
        }
        s->tf = c->tf;
        s->tf_count = n;
    } /* else the Otsu default */
    unsigned m = rc_u8(b);
    s->occlusion = m & 1;
    if (m & 2) s->occlusion_threshold = 1e-6 + rc_unit(b) * (1.0 - 1e-6);
    s->tile_counters = (m >> 2) & 1;
    s->exact_normals = (m >> 3) & 1;
    if (m & 16) s->normal_lut_size = 8 + (int)(rc_u8(b) % 250);
    if (m & 32) {
        s->headlight = 0;
        for (int a = 0; a < 3; a++) s->light_dir[a] = (m & 64) ? 0.0 : rc_unit(b) * 2.0 - 1.0; /* zero too */
    }
    if (m & 128) {
        s->ambient = rc_unit(b);
        s->diffuse = rc_unit(b) * 2.0;
        s->specular = rc_unit(b) * 2.0;
        s->shininess = rc_log(b, 1e-3, 1e4);
    }
    unsigned r = rc_u8(b);
    if (r & 1) s->ray_step = rc_log(b, 0.05, 1e4);
    s->ray_trilinear = (r >> 1) & 1;
    if (r & 4) {
        for (int i = 0; i < 4; i++) s->background[i] = (float)rc_unit(b);
    }
    s->isa = (vs_isa)((r >> 3) % 5); /* capped to what the CPU has */
    s->pin = 0;
    c->threads_n = 2 + (int)((r >> 6) & 1);
    unsigned k = rc_u8(b);
    c->cancel_after = k < 224 ? -1 : (int)(k - 224);
}

/* Renders one case; NULL if every promise held, else what failed (into
 * why).  *status gets the status of the 1-thread render.  ctxs[t] renders
 * with t threads (1..3): a context keeps its worker pool only while the
 * thread count stays the same, and making one (hwloc's topology) costs
 * far more than these renders. */
static inline const char *rc_check(vs_context *const ctxs[4], const uint8_t *data, size_t size, vs_status *status,
                                   char *why, size_t cap)
{
    vs_context *ctx = ctxs[1];
    rc_bytes b = {data, size, 0};
    rc_case c;
    rc_decode(&b, &c);
    *status = VS_OK;
    vs_volume *v = NULL;
    vs_status st = vs_volume_create(ctx, c.type, c.dims, c.spacing, &v);
    if (st != VS_OK) {
        snprintf(why, cap, "volume_create %dx%dx%d: %s", c.dims[0], c.dims[1], c.dims[2], vs_last_error(ctx));
        return why;
    }
    rc_fill(&b, v, c.type, (size_t)c.dims[0] * c.dims[1] * c.dims[2]);
    if (c.blow_up) {
        const int f = 8, big[3] = {c.dims[0] * f, c.dims[1] * f, c.dims[2] * f};
        vs_volume *w = NULL;
        if (vs_volume_create(ctx, c.type, big, c.spacing, &w) != VS_OK) {
            snprintf(why, cap, "volume_create %dx%dx%d: %s", big[0], big[1], big[2], vs_last_error(ctx));
            vs_volume_release(v);
            return why;
        }
        const size_t es = c.type == VS_U8 ? 1 : c.type == VS_F32 ? 4 : 2;
        const char *src = vs_volume_data(v);
        char *dst = vs_volume_data(w);
        for (int k = 0; k < big[2]; k++)
            for (int j = 0; j < big[1]; j++)
                for (int i = 0; i < big[0]; i++)
                    memcpy(dst + (((size_t)k * big[1] + j) * big[0] + i) * es,
                           src + (((size_t)(k / f) * c.dims[1] + j / f) * c.dims[0] + i / f) * es, es);
        vs_volume_update_range(w);
        vs_volume_release(v);
        v = w;
    }
    const char *fail = NULL;
    vs_image img[2] = {{0, 0, NULL}, {0, 0, NULL}};
    vs_status sts[2];
    for (int run = 0; run < 2 && !fail; run++) {
        rc_progress prog = {0, c.cancel_after};
        c.s.threads = run == 0 ? 1 : c.threads_n;
        ctx = ctxs[c.s.threads];
        c.s.progress = rc_progress_fn;
        c.s.progress_user = &prog;
        vs_stats stats;
        sts[run] = vs_render(ctx, v, &c.s, &img[run], &stats);
        if ((int)sts[run] < VS_OK || (int)sts[run] > VS_ERR_INTERNAL) {
            snprintf(why, cap, "status %d is not a vs_status", (int)sts[run]);
            fail = why;
        } else if (sts[run] == VS_ERR_INTERNAL || sts[run] == VS_ERR_OUT_OF_MEMORY) {
            snprintf(why, cap, "%s: %s", vs_status_string(sts[run]), vs_last_error(ctx));
            fail = why;
        } else if (sts[run] != VS_OK) {
            if (!*vs_last_error(ctx)) snprintf(why, cap, "status %d without a message", (int)sts[run]), fail = why;
            if (img[run].rgba) snprintf(why, cap, "status %d left an image", (int)sts[run]), fail = why;
        } else if (img[run].width != c.s.width || img[run].height != c.s.height || !img[run].rgba) {
            snprintf(why, cap, "image %dx%d for %dx%d", img[run].width, img[run].height, c.s.width, c.s.height);
            fail = why;
        } else {
            size_t np = (size_t)c.s.width * c.s.height;
            for (size_t i = 0; i < np && !fail; i++) {
                const float *p = img[run].rgba + 4 * i;
                if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]) || !(p[3] >= 0.0f && p[3] <= 1.0f)) {
                    snprintf(why, cap, "%s, %d thread(s): pixel %zu is %g %g %g %g", vs_pipeline_name(c.s.pipeline),
                             c.s.threads, i, p[0], p[1], p[2], p[3]);
                    fail = why;
                }
            }
        }
    }
    *status = sts[0];
    if (!fail && sts[0] != sts[1] && c.cancel_after < 0) {
        snprintf(why, cap, "status %d with 1 thread, %d with %d", (int)sts[0], (int)sts[1], c.threads_n);
        fail = why;
    }
    if (!fail && sts[0] == VS_OK && sts[1] == VS_OK &&
        memcmp(img[0].rgba, img[1].rgba, sizeof(float) * 4 * (size_t)c.s.width * c.s.height) != 0) {
        snprintf(why, cap, "%s: image with %d threads differs from 1 thread", vs_pipeline_name(c.s.pipeline),
                 c.threads_n);
        fail = why;
    }
    vs_image_free(&img[0]);
    vs_image_free(&img[1]);
    vs_volume_release(v);
    return fail;
}

#endif
