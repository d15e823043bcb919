/* vsplat-bench peers: vsplat against VolPack's octree renderer in one run.
 *
 * The same volumes, views and image size are rendered by VolPack
 * (vpRenderRawVolume with a min-max octree: classification per frame, one
 * thread; an optional build dependency, CMake defines VSPLAT_HAVE_VOLPACK) and
 * by every vsplat splatting pipeline on --threads threads (default 2), the
 * configurations interleaved frame by frame; each prints its frame-time median
 * and the ratio to VolPack.  Fidelity comes from the same run: the first view
 * of each renderer is compared with vsplat's ray caster (exact Gaussian) at
 * the same size, and peers_NAME.png shows ray caster | vsplat post-cd |
 * VolPack side by side.
 *
 * Matching VolPack to vsplat (docs/DESIGN.md §2):
 *  - voxels: VolPack takes 8-bit scalars; u8 volumes are handed over as they
 *    are, anything else is mapped linearly from its value range to 0..255
 *    (the CT's HU), and the opacity ramp is evaluated at each byte's value;
 *  - classification: opacity 0 at LO - W rising linearly to 1 at LO + W, on
 *    the scalar alone (no gradient-magnitude term), a 256-entry table;
 *  - camera: orthographic; the model matrix holds the rotation (rows right,
 *    up, dir of vsplat's camera) and the
 *    spacing (normalised to the smallest, so the shading table, which VolPack
 *    computes in object space, stays unit-scaled); the view matrix moves the
 *    voxel centres onto vsplat's (VolPack puts voxel i at i - n/2, vsplat at
 *    i - (n-1)/2); the window gives vsplat's pixels per mm;
 *  - shading: VolPack's lookup shader (one material, grey) with vsplat's
 *    Blinn-Phong constants (ambient 0.2, diffuse 0.6, specular 0.2,
 *    exponent 20), two-sided, a headlight; normals are VolPack's own
 *    (central differences of the voxels, 13-bit code, vpVolumeNormals);
 *  - thresholds: VP_MAX_RAY_OPACITY = vsplat's occlusion threshold (0.995),
 *    VP_MIN_VOXEL_OPACITY 0 (only fully transparent voxels dropped, as
 *    vsplat's relevant-voxel list); a second VolPack row uses the values its
 *    manual suggests (0.95 and 0.05).
 * A VolPack frame is vpShadeTable (the table depends on the view) plus
 * vpRenderRawVolume; building the octree and the normals is setup, as
 * vsplat's relevant-voxel list is. */
#include "bench.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#ifdef VSPLAT_HAVE_VOLPACK
#include <volpack.h>


/* ---- VolPack ---- */

typedef struct vp_voxel {
    short normal;          /* field 0: encoded normal (shading)   */
    unsigned char density; /* field 1: the 8-bit scalar (classify) */
    unsigned char pad;
} vp_voxel;

typedef struct vp_peer {
    vpContext *vpc;
    vp_voxel *voxels;
    unsigned char *scalars;
    float ramp[256];
    float shade[VP_NORM_MAX + 1];
    unsigned char *img; /* luminance + alpha, row 0 at the bottom */
    int W, H;
    int dims[3];
    double sp[3], spmin;
    double lo, hi;      /* value range mapped to 0..255 (hi == lo: u8 as is) */
} vp_peer;

static int vp_check(vp_peer *p, int r, const char *what)
{
    if (r == VP_OK) return 0;
    fprintf(stderr, "vsplat-bench: peers: VolPack %s: %s\n", what, vpGetErrorString(vpGetError(p->vpc)));
    return 1;
}

static void vp_free(vp_peer *p)
{
    if (p->vpc) vpDestroyContext(p->vpc);
    free(p->voxels);
    free(p->scalars);
    free(p->img);
    memset(p, 0, sizeof *p);
}

/* The byte VolPack sees for data value v, and the value a byte stands for. */
static double vp_byte_value(const vp_peer *p, int b)
{
    return p->hi > p->lo ? p->lo + (p->hi - p->lo) * b / 255.0 : (double)b;
}

static int vp_setup(vp_peer *p, vs_volume *vol, int W, int H, double iso, double ramp, double max_ray,
                    double min_voxel)
{
    memset(p, 0, sizeof *p);
    vs_volume_dims(vol, p->dims);
    vs_volume_spacing(vol, p->sp);
    p->spmin = fmin(p->sp[0], fmin(p->sp[1], p->sp[2]));
    p->W = W;
    p->H = H;
    const size_t n = (size_t)p->dims[0] * p->dims[1] * p->dims[2];
    p->scalars = malloc(n);
    p->voxels = malloc(n * sizeof *p->voxels);
    p->img = calloc((size_t)W * H, 2);
    p->vpc = vpCreateContext();
    if (!p->scalars || !p->voxels || !p->img || !p->vpc) {
        fprintf(stderr, "vsplat-bench: peers: out of memory for VolPack\n");
        return 1;
    }
    /* the same voxels: u8 as is, anything else mapped from its range to 0..255 */
    const void *data = vs_volume_data(vol);
    vs_type t = vs_volume_type(vol);
    if (t == VS_U8) {
        memcpy(p->scalars, data, n);
    } else {
        vs_volume_range(vol, &p->lo, &p->hi);
        double sc = p->hi > p->lo ? 255.0 / (p->hi - p->lo) : 0.0;
        for (size_t i = 0; i < n; i++) {
            double v = t == VS_I16   ? ((const int16_t *)data)[i]
                       : t == VS_U16 ? ((const uint16_t *)data)[i]
                                     : ((const float *)data)[i];
            long b = lround((v - p->lo) * sc);
            p->scalars[i] = (unsigned char)(b < 0 ? 0 : b > 255 ? 255 : b);
        }
    }
    /* the opacity ramp of docs/DESIGN.md §2 at each byte's value */
    for (int b = 0; b < 256; b++) {
        double a = (vp_byte_value(p, b) - (iso - ramp)) / (2.0 * ramp);
        p->ramp[b] = (float)(a < 0 ? 0 : a > 1 ? 1 : a);
    }
    vpContext *c = p->vpc;
    const int nx = p->dims[0], ny = p->dims[1], nz = p->dims[2];
    int r = vpSetVolumeSize(c, nx, ny, nz);
    if (!r) r = vpSetVoxelSize(c, (int)sizeof(vp_voxel), 2, 1, 1);
    if (!r) r = vpSetVoxelField(c, 0, (int)sizeof(short), (int)offsetof(vp_voxel, normal), VP_NORM_MAX);
    if (!r) r = vpSetVoxelField(c, 1, 1, (int)offsetof(vp_voxel, density), 255);
    if (!r)
        r = vpSetRawVoxels(c, p->voxels, (int)(n * sizeof(vp_voxel)), (int)sizeof(vp_voxel),
                           nx * (int)sizeof(vp_voxel), nx * ny * (int)sizeof(vp_voxel));
    if (!r) r = vpVolumeNormals(c, p->scalars, (int)n, 1, VP_SKIP_FIELD, 0);
    if (!r) r = vpSetClassifierTable(c, 0, 1, p->ramp, (int)sizeof p->ramp);
    if (!r) r = vpMinMaxOctreeThreshold(c, 0, 4);
    if (!r) r = vpCreateMinMaxOctree(c, 0, 4);
    if (!r) r = vpSetLookupShader(c, 1, 1, 0, p->shade, (int)sizeof p->shade, 0, NULL, 0);
    if (!r) r = vpSetMaterial(c, VP_MATERIAL0, VP_AMBIENT, VP_BOTH_SIDES, 0.2, 0.2, 0.2);
    if (!r) r = vpSetMaterial(c, VP_MATERIAL0, VP_DIFFUSE, VP_BOTH_SIDES, 0.6, 0.6, 0.6);
    if (!r) r = vpSetMaterial(c, VP_MATERIAL0, VP_SPECULAR, VP_BOTH_SIDES, 0.2, 0.2, 0.2);
    if (!r) r = vpSetMaterial(c, VP_MATERIAL0, VP_SHINYNESS, VP_BOTH_SIDES, 20.0, 0.0, 0.0);
    /* the model matrix is the identity here: the light is in eye space, from the eye */
    if (!r) r = vpSetLight(c, VP_LIGHT0, VP_DIRECTION, 0.0, 0.0, 1.0);
    if (!r) r = vpSetLight(c, VP_LIGHT0, VP_COLOR, 1.0, 1.0, 1.0);
    if (!r) r = vpEnable(c, VP_LIGHT0, 1);
    if (!r) r = vpEnable(c, VP_LIGHT_BOTH_SIDES, 1);
    if (!r) r = vpSetd(c, VP_MAX_RAY_OPACITY, max_ray);
    if (!r) r = vpSetd(c, VP_MIN_VOXEL_OPACITY, min_voxel);
    if (!r) r = vpSetImage(c, p->img, W, H, 2 * W, VP_LUMINANCEA);
    return vp_check(p, r, "setup");
}

/* vsplat's camera (src/camera.c) as VolPack matrices. */
static int vp_view(vp_peer *p, double az_deg, double el_deg, double zoom)
{
    const double deg = M_PI / 180.0;
    double ca = cos(az_deg * deg), sa = sin(az_deg * deg), ce = cos(el_deg * deg), se = sin(el_deg * deg);
    const double dir[3] = {-sa * ce, ca * ce, -se}, right[3] = {ca, sa, 0.0}, up[3] = {-sa * se, ca * se, ce};
    const double *rows[3] = {right, up, dir};
    /* eye z along vsplat's viewing direction: VolPack composites from low to
     * high eye z after its viewport flip (with -dir one sees the back) */
    const double sgn[3] = {1.0, 1.0, 1.0};
    int maxdim = p->dims[0];
    double extent = 0.0;
    for (int a = 0; a < 3; a++) {
        if (p->dims[a] > maxdim) maxdim = p->dims[a];
        extent = fmax(extent, p->dims[a] * p->sp[a]);
    }
    /* object o (VolPack: voxel i at (i - n/2)/maxdim) -> world mm
     * w = (o*maxdim + 0.5)*sp;  K scales mm into the model's units */
    const double K = maxdim * p->spmin;
    vpMatrix4 model, view;
    memset(model, 0, sizeof model);
    memset(view, 0, sizeof view);
    for (int r = 0; r < 3; r++) {
        double tr = 0.0;
        for (int a = 0; a < 3; a++) {
            model[r][a] = sgn[r] * rows[r][a] * p->sp[a] / p->spmin;
            tr += sgn[r] * rows[r][a] * 0.5 * p->sp[a];
        }
        view[r][r] = 1.0;
        view[r][3] = tr / K;
    }
    model[3][3] = view[3][3] = 1.0;
    const double px = zoom * p->W / extent * K; /* pixels per model unit */
    const double half = 0.5 * sqrt(3.0) * maxdim * 1.6; /* depth range, generous */
    /* vsplat's pixel x sits at px*x + (W-1)/2, VolPack's at px*(x - left):
     * against the ray caster this offset beats a half pixel either way */
    const double l = -0.5 * (p->W - 1) / px, b = -0.5 * (p->H - 1) / px;
    int r = vpCurrentMatrix(p->vpc, VP_MODEL);
    if (!r) r = vpSetMatrix(p->vpc, model);
    if (!r) r = vpCurrentMatrix(p->vpc, VP_VIEW);
    if (!r) r = vpSetMatrix(p->vpc, view);
    if (!r) r = vpCurrentMatrix(p->vpc, VP_PROJECT);
    if (!r) r = vpIdentityMatrix(p->vpc);
    if (!r) r = vpWindow(p->vpc, VP_PARALLEL, l, l + p->W / px, b, b + p->H / px, -half, half);
    if (!r) r = vpCurrentMatrix(p->vpc, VP_MODEL);
    return vp_check(p, r, "view");
}

static double vp_frame(vp_peer *p, double az, double el, double zoom, int *fail)
{
    if (vp_view(p, az, el, zoom)) {
        *fail = 1;
        return NAN;
    }
    double t0 = bench_now_ms();
    int r = vpShadeTable(p->vpc);
    if (!r) r = vpRenderRawVolume(p->vpc);
    double ms = bench_now_ms() - t0;
    if (vp_check(p, r, "render")) *fail = 1;
    return ms;
}

/* VolPack's image (associated luminance + alpha, row 0 at the bottom) as
 * vsplat's (straight RGBA float, row 0 at the top). */
static int vp_to_image(const vp_peer *p, vs_image *out)
{
    out->width = p->W;
    out->height = p->H;
    out->rgba = malloc((size_t)p->W * p->H * 4 * sizeof(float));
    if (!out->rgba) return 1;
    for (int y = 0; y < p->H; y++) {
        const unsigned char *src = p->img + (size_t)(p->H - 1 - y) * p->W * 2;
        float *dst = out->rgba + (size_t)y * p->W * 4;
        for (int x = 0; x < p->W; x++) {
            float a = src[2 * x + 1] / 255.0f;
            float l = a > 0 ? fminf(1.0f, src[2 * x] / 255.0f / a) : 0.0f;
            dst[4 * x] = dst[4 * x + 1] = dst[4 * x + 2] = l;
            dst[4 * x + 3] = a;
        }
    }
    return 0;
}

/* ---- configurations ---- */

/* the 4 vsplat pipelines, post-cd from the level of detail whose voxels
 * lie up to 5 pixels apart (level 1 on both heads: at or above VolPack's
 * PSNR, so the two compare at equal fidelity), VolPack (matched), VolPack
 * (suggested) */
enum { NVS = 5, NCONF = NVS + 2 };

typedef struct peer_conf {
    const char *label;
    int volpack;      /* 0: vsplat; 1, 2: VolPack with vsplat's / the manual's thresholds */
    vs_pipeline pipeline;
    double lod_px;    /* vsplat's lod_pixels; 0: the settings' */
    int level;        /* the level of detail its first view splatted */
    vs_context *ctx;
    vp_peer vp;
    double *ms;
    int nms, fail, rebuilds, threads;
    vs_image first;   /* the first view's image */
    vs_image_diff d;
    int have_d;
} peer_conf;

static void side_by_side(const bench_opts *o, const char *name, const vs_image *imgs[3])
{
    const int W = imgs[0]->width, H = imgs[0]->height;
    vs_image s = {3 * W, H, calloc((size_t)3 * W * H * 4, sizeof(float))};
    if (!s.rgba) return;
    for (int k = 0; k < 3; k++)
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const float *src = imgs[k]->rgba + ((size_t)y * W + x) * 4;
                float *dst = s.rgba + ((size_t)y * 3 * W + (size_t)k * W + x) * 4;
                /* over black, opaque: the panels' transparency would hide the differences */
                for (int c = 0; c < 3; c++) dst[c] = src[c] * src[3];
                dst[3] = 1.0f;
            }
    char path[4096];
    snprintf(path, sizeof path, "%s/peers_%s.png", o->out_dir, name);
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) == VS_OK) {
        if (vs_image_write(ctx, path, &s, 8) != VS_OK)
            fprintf(stderr, "vsplat-bench: peers: %s\n", vs_last_error(ctx));
        else
            printf("wrote %s (ray caster | vsplat post-cd | VolPack, over black)\n", path);
        vs_context_release(ctx);
    }
    free(s.rgba);
}

static int run_peer(const bench_opts *o, const bench_peer_case *pd, FILE *csv)
{
    const char *key = o->quick ? pd->quick : pd->input;
    vs_volume *vol = NULL;
    int ls = bench_load(o, key, &vol);
    if (ls) return ls < 0;
    const int nviews = o->quick ? 4 : 12;
    const int runs = bench_runs(o, 3, 1);
    int failed = 0;

    vs_settings base;
    bench_peer_settings(o, pd, &base);
    const int size = base.width, threads = base.threads;
    const double iso = base.iso_lo, ramp = base.ramp;

    static const struct {
        vs_pipeline pipeline;
        double lod_px;
        const char *label;
    } pipes[NVS] = {{VS_PIPELINE_POST_CD, 0, NULL},
                    {VS_PIPELINE_PRE, 0, NULL},
                    {VS_PIPELINE_POST_GS, 0, NULL},
                    {VS_PIPELINE_POST_ALPHA, 0, NULL},
                    {VS_PIPELINE_POST_CD, 5.0, "post-cd lod 5"}};
    peer_conf conf[NCONF];
    memset(conf, 0, sizeof conf);
    for (int c = 0; c < NCONF; c++) {
        peer_conf *pc = &conf[c];
        pc->ms = calloc((size_t)runs * nviews, sizeof *pc->ms);
        if (!pc->ms) failed = 1;
        if (c < NVS) {
            pc->pipeline = pipes[c].pipeline;
            pc->lod_px = pipes[c].lod_px;
            pc->label = pipes[c].label ? pipes[c].label : vs_pipeline_name(pipes[c].pipeline);
            pc->threads = threads;
            if (vs_context_create(&pc->ctx) != VS_OK) failed = 1;
        } else {
            pc->volpack = c - NVS + 1;
            pc->label = pc->volpack == 1 ? "volpack" : "volpack-0.95";
            pc->threads = 1;
            double t0 = bench_now_ms();
            if (vp_setup(&pc->vp, vol, size, size, iso, ramp, pc->volpack == 1 ? base.occlusion_threshold : 0.95,
                         pc->volpack == 1 ? 0.0 : 0.05))
                pc->fail = 1;
            else if (pc->volpack == 1)
                fprintf(stderr, "peers %s: VolPack normals and octree %.0f ms\n", pd->name, bench_now_ms() - t0);
        }
    }
    if (failed) goto done;

    /* the reference, first view: vsplat's ray caster with the exact Gaussian */
    vs_settings rs = base;
    rs.pipeline = VS_PIPELINE_RAYCAST;
    rs.ray_step = o->quick ? 0.05 : 0.1;
    rs.ray_analytic = 0;
    rs.ray_trilinear = 0;
    vs_image ref = {0, 0, NULL};
    vs_stats rst;
    double tr = bench_now_ms();
    if (vs_render(conf[0].ctx, vol, &rs, &ref, &rst) != VS_OK) {
        fprintf(stderr, "vsplat-bench: peers %s: reference: %s\n", pd->name, vs_last_error(conf[0].ctx));
        failed = 1;
        goto done;
    }
    fprintf(stderr, "peers %s: reference ray caster (step %.2f) %.0f ms\n", pd->name, rs.ray_step,
            bench_now_ms() - tr);

    /* warm-up = the first view, kept for the comparison */
    for (int c = 0; c < NCONF; c++) {
        peer_conf *pc = &conf[c];
        if (pc->fail) continue;
        if (pc->volpack) {
            vp_frame(&pc->vp, pd->az, pd->el, base.zoom, &pc->fail);
            if (!pc->fail && vp_to_image(&pc->vp, &pc->first)) pc->fail = 1;
        } else {
            vs_settings s = base;
            s.pipeline = pc->pipeline;
            if (pc->lod_px > 0) s.lod_pixels = pc->lod_px;
            vs_stats st;
            if (vs_render(pc->ctx, vol, &s, &pc->first, &st) != VS_OK) {
                fprintf(stderr, "vsplat-bench: peers %s %s: %s\n", pd->name, pc->label, vs_last_error(pc->ctx));
                pc->fail = 1;
            } else {
                pc->threads = st.threads;
                pc->level = st.lod_level;
            }
        }
        if (!pc->fail && vs_image_compare(conf[0].ctx, &ref, &pc->first, &pc->d) == VS_OK) pc->have_d = 1;
    }

    /* timed: runs x views, every configuration per view, the start rotating */
    const int total = runs * nviews;
    for (int r = 0; r < runs; r++)
        for (int v = 0; v < nviews; v++) {
            const int step = r * nviews + v;
            bench_progress(pd->name, step, total, "frames");
            const double az = pd->az + 360.0 * v / nviews;
            for (int k = 0; k < NCONF; k++) {
                peer_conf *pc = &conf[(k + step) % NCONF];
                if (pc->fail) continue;
                if (pc->volpack) {
                    double ms = vp_frame(&pc->vp, az, pd->el, base.zoom, &pc->fail);
                    pc->ms[pc->nms++] = ms;
                } else {
                    vs_settings s = base;
                    s.pipeline = pc->pipeline;
                    if (pc->lod_px > 0) s.lod_pixels = pc->lod_px;
                    s.azimuth = az;
                    vs_image img = {0, 0, NULL};
                    vs_stats st;
                    if (vs_render(pc->ctx, vol, &s, &img, &st) != VS_OK) {
                        fprintf(stderr, "vsplat-bench: peers %s %s: %s\n", pd->name, pc->label,
                                vs_last_error(pc->ctx));
                        pc->fail = 1;
                    } else {
                        if (st.ms_relevant > 0) pc->rebuilds++;
                        pc->ms[pc->nms++] = st.ms_total;
                    }
                    vs_image_free(&img);
                }
            }
        }
    bench_progress_end();

    {
        int dims[3];
        vs_volume_dims(vol, dims);
        printf("-- %s (%s, %dx%dx%d %s), iso %g ramp %g, views %g+k*%g,%g, %dx%d, %d frames x %d runs --\n",
               pd->name, key, dims[0], dims[1], dims[2], vs_type_name(vs_volume_type(vol)), iso, ramp, pd->az,
               360.0 / nviews, pd->el, size, size, nviews, runs);
        if (conf[NVS].vp.hi > conf[NVS].vp.lo)
            printf("VolPack gets 8-bit voxels: %g..%g mapped linearly to 0..255 (%.2f per step)\n",
                   conf[NVS].vp.lo, conf[NVS].vp.hi, (conf[NVS].vp.hi - conf[NVS].vp.lo) / 255.0);
    }
    double vp_med = NAN;
    bench_summary sum[NCONF];
    for (int c = 0; c < NCONF; c++) {
        peer_conf *pc = &conf[c];
        sum[c].median = sum[c].min = sum[c].max = NAN;
        if (pc->fail || !pc->nms) continue;
        sum[c].median = bench_median(pc->ms, pc->nms); /* sorts */
        sum[c].min = pc->ms[0];
        sum[c].max = pc->ms[pc->nms - 1];
        if (pc->volpack == 1) vp_med = sum[c].median;
    }
    printf("%-21s %7s %10s %19s %10s %8s %7s\n", "renderer", "threads", "median_ms", "min-max", "vs_volpack",
           "psnr_dB", "ssim");
    for (int c = 0; c < NCONF; c++) {
        peer_conf *pc = &conf[c];
        char name[32];
        snprintf(name, sizeof name, "%s%s", pc->volpack ? "" : "vsplat ", pc->label);
        if (pc->fail) {
            printf("%-21s failed\n", name);
            failed = 1;
            continue;
        }
        double ratio = sum[c].median / vp_med;
        printf("%-21s %7d %10.2f %9.2f-%-9.2f %9.2fx %8.2f %7.4f\n", name, pc->threads, sum[c].median, sum[c].min,
               sum[c].max, ratio, pc->have_d ? pc->d.psnr : NAN, pc->have_d ? pc->d.ssim : NAN);
        fprintf(csv, "%s,%s,%d,%s,%s,%d,%d,%.3f,%.3f,%.3f,%.4f,%.4f,%.5f\n", pd->name, key, size,
                pc->volpack ? "volpack" : "vsplat", pc->label, pc->threads, pc->nms, sum[c].median, sum[c].min,
                sum[c].max, ratio, pc->have_d ? pc->d.psnr : NAN, pc->have_d ? pc->d.ssim : NAN);
        if (pc->rebuilds)
            fprintf(stderr, "peers %s %s: note: %d timed frames rebuilt the relevant-voxel list\n", pd->name,
                    pc->label, pc->rebuilds);
    }
    for (int c = 0; c < NVS; c++)
        if (conf[c].lod_px > 0 && !conf[c].fail)
            printf("(vsplat %s: level %d of the volume's levels of detail)\n", conf[c].label, conf[c].level);
    fflush(csv);
    if (!conf[0].fail && !conf[NVS].fail) {
        const vs_image *imgs[3] = {&ref, &conf[0].first, &conf[NVS].first};
        side_by_side(o, pd->name, imgs);
    }
    vs_image_free(&ref);

done:
    for (int c = 0; c < NCONF; c++) {
        free(conf[c].ms);
        vs_image_free(&conf[c].first);
        if (conf[c].ctx) vs_context_release(conf[c].ctx);
        if (conf[c].volpack) vp_free(&conf[c].vp);
    }
    vs_volume_release(vol);
    return failed;
}

int bench_peers(const bench_opts *o)
{
    if (bench_results_dir(o)) return 2;
    FILE *csv = bench_result_open(o, "peers.csv");
    if (!csv) return 2;
    fprintf(csv, "volume,input,size,renderer,pipeline,threads,frames,median_ms,min_ms,max_ms,ratio_to_volpack,"
                 "psnr_vs_raycast,ssim_vs_raycast\n");
    printf("\nPeers: vsplat (%d threads) against VolPack's octree renderer (vpRenderRawVolume, 1 thread), "
           "frames interleaved, medians; PSNR/SSIM of the first view against vsplat's exact-Gaussian ray "
           "caster; machine: %s; load average %s\n",
           o->threads ? o->threads : 2, bench_machine(), bench_loadavg());
    int failed = 0;
    for (int i = 0; i < bench_npeer_cases; i++) failed += run_peer(o, &bench_peer_cases[i], csv);
    fclose(csv);
    return failed ? 2 : 0;
}

#else /* !VSPLAT_HAVE_VOLPACK */

int bench_peers(const bench_opts *o)
{
    (void)o;
    printf("peers: skipped: VolPack (volpack.h, -lvolpack; Debian libvolpack1-dev) was not found when "
           "vsplat-bench was built\n");
    return 0;
}

#endif
