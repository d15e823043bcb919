/* vsplat-bench inputs: where the real volumes are and how each is loaded
 * (file names, raw layout and spacing from ../shared/data/MANIFEST.md). */
#include "bench.h"

#include <math.h>

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#ifndef VSPLAT_SOURCE_DIR
#define VSPLAT_SOURCE_DIR "."
#endif

typedef struct input_def {
    const char *key;
    const char *file;
    int raw;
    int dims[3];
    vs_type type;
    int has_spacing;
    double spacing[3];
} input_def;

static const input_def inputs[] = {
    {"colin27", "colin27_ch2_mri_t1_head_181x217x181_u8.nii.gz", 0, {0, 0, 0}, VS_U8, 0, {0, 0, 0}},
    /* VolPack's brainsmall: the UNC MRbrain (1:1:2) reduced to 128x128x84, so about 1:1:1.3 */
    {"brain", "unc_mrbrain_volpack_brainsmall_128x128x84_u8.den", 0, {0, 0, 0}, VS_U8, 1, {1, 1, 1.3}},
    {"em", "isbi2012_sstem_drosophila_vnc_512x512x30_u8_png.tar", 0, {0, 0, 0}, VS_U8, 1, {4, 4, 50}},
    {"ct", "invesalius_cranium_ct_head_256x256x108_i16le.raw.gz", 1, {256, 256, 108}, VS_I16, 1,
     {0.9570312, 0.9570312, 1.5}},
};

static const input_def *find_input(const char *key)
{
    for (size_t i = 0; i < sizeof inputs / sizeof inputs[0]; i++)
        if (!strcmp(inputs[i].key, key)) return &inputs[i];
    return NULL;
}

const char *bench_data_dir(const char *override)
{
    static char buf[4096];
    if (override && *override) return override;
    const char *env = getenv("VSPLAT_DATA");
    if (env && *env) return env;
    snprintf(buf, sizeof buf, "%s/../shared/data", VSPLAT_SOURCE_DIR);
    return buf;
}

int bench_load(const bench_opts *o, const char *key, vs_volume **out)
{
    *out = NULL;
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) {
        fprintf(stderr, "vsplat-bench: cannot create a context\n");
        return -1;
    }
    vs_status st;
    const char *what = key;
    char path[4096];
    if (!strncmp(key, "scene:", 6)) {
        st = vs_volume_scene(ctx, key + 6, out);
    } else {
        const input_def *d = find_input(key);
        if (!d) {
            fprintf(stderr, "vsplat-bench: unknown input '%s'\n", key);
            vs_context_release(ctx);
            return -1;
        }
        snprintf(path, sizeof path, "%s/%s", o->data_dir, d->file);
        what = path;
        struct stat sb;
        if (stat(path, &sb) != 0) {
            fprintf(stderr, "vsplat-bench: %s: not found, cases on it skipped\n", path);
            vs_context_release(ctx);
            return 1;
        }
        vs_load_options lo;
        vs_load_options_init(&lo);
        lo.raw = d->raw;
        memcpy(lo.dims, d->dims, sizeof lo.dims);
        lo.type = d->type;
        lo.endian = VS_ENDIAN_LITTLE;
        lo.has_spacing = d->has_spacing;
        memcpy(lo.spacing, d->spacing, sizeof lo.spacing);
        st = vs_volume_load(ctx, path, &lo, out);
    }
    if (st != VS_OK) {
        fprintf(stderr, "vsplat-bench: %s: %s\n", what, vs_last_error(ctx));
        vs_context_release(ctx);
        *out = NULL;
        return -1;
    }
    vs_context_release(ctx);
    return 0;
}

const bench_peer_case bench_peer_cases[] = {
    {"colin27", "colin27", "scene:head:128", 45, 10, 180, 0, 0.5, 0.1},
    {"ct-head", "ct", "scene:head:128", 400, 100, 180, 15, 0.25, 0.03},
};
const int bench_npeer_cases = (int)(sizeof bench_peer_cases / sizeof bench_peer_cases[0]);

void bench_peer_settings(const bench_opts *o, const bench_peer_case *pc, vs_settings *s)
{
    vs_settings_init(s);
    s->width = s->height = o->quick ? 128 : 512;
    s->view = VS_VIEW_ANGLES;
    s->azimuth = pc->az;
    s->elevation = pc->el;
    s->has_iso = 1;
    s->iso_lo = o->quick ? pc->qiso : pc->iso;
    s->iso_hi = INFINITY;
    s->ramp = o->quick ? pc->qramp : pc->ramp;
    s->threads = o->threads ? o->threads : 2;
}
