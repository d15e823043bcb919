/* Command-line parsing for the vsplat tool (see cli_args.h). */
#include "cli_args.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---- errors ---- */

#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static int fail(char *err, size_t cap, const char *fmt, ...)
{
    if (err && cap) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, cap, fmt, ap);
        va_end(ap);
    }
    return 1;
}

/* ---- numbers ---- */

/* A whole string as a finite double. */
static int to_double(const char *s, double *out)
{
    if (!s || !*s) return 0;
    char *end = NULL;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end != '\0' || errno == ERANGE || !isfinite(v)) return 0;
    *out = v;
    return 1;
}

/* A whole string as an int in [lo, hi]. */
static int to_int(const char *s, long lo, long hi, int *out)
{
    if (!s || !*s) return 0;
    char *end = NULL;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end != '\0' || errno == ERANGE || v < lo || v > hi) return 0;
    *out = (int)v;
    return 1;
}

/* Exactly n comma-separated finite doubles. */
static int to_doubles(const char *s, int n, double *out)
{
    char buf[256];
    size_t len = strlen(s);
    if (len == 0 || len >= sizeof buf) return 0;
    memcpy(buf, s, len + 1);
    char *p = buf;
    for (int i = 0; i < n; i++) {
        char *comma = strchr(p, ',');
        if (i < n - 1) {
            if (!comma) return 0;
            *comma = '\0';
        } else if (comma) {
            return 0;
        }
        if (!to_double(p, &out[i])) return 0;
        p = comma ? comma + 1 : p;
    }
    return 1;
}

/* ---- the option table ---- */

enum opt_id {
    O_HELP, O_OUTPUT, O_SCENE, O_PIPELINE, O_ISO, O_RAMP, O_OPACITY, O_MATERIAL, O_BACKGROUND,
    O_TF, O_SIZE, O_VIEW, O_ZOOM, O_PERSPECTIVE, O_CENTER, O_SLAB, O_KRADIUS, O_FOOTPRINT, O_SEAM, O_THREADS,
    O_ISA, O_NO_PIN, O_NO_OCCL, O_OCCL_T, O_NO_TILES, O_TILE_SIZE, O_EXACT_N, O_NORMAL_LUT,
    O_RAY_STEP, O_TRILINEAR, O_RAY_NORMALIZE, O_NO_GS_NORMALIZE, O_NO_ANALYTIC, O_LIGHT, O_AMBIENT, O_DIFFUSE, O_SPECULAR,
    O_SHININESS, O_DIMS, O_TYPE, O_SPACING, O_ENDIAN, O_SERIES, O_BITS, O_STATS, O_PRINT_STATS, O_TRACE, O_QUIET,
    O_TURNTABLE, O_FPS, O_UP, O_ROLL, O_PREINT, O_NO_PREINT, O_LOD, O_NO_LOD, O_RESAMPLE, O_CD_STENCIL
};

typedef struct opt_def {
    const char *name;
    int has_arg;
    enum opt_id id;
    int info_ok; /* also accepted by `vsplat info` */
} opt_def;

static const opt_def opt_table[] = {
    {"--help", 0, O_HELP, 1},
    {"-h", 0, O_HELP, 1},
    {"-o", 1, O_OUTPUT, 0},
    {"--output", 1, O_OUTPUT, 0},
    {"--scene", 1, O_SCENE, 1},
    {"--pipeline", 1, O_PIPELINE, 0},
    {"--iso", 1, O_ISO, 0},
    {"--ramp", 1, O_RAMP, 0},
    {"--opacity", 1, O_OPACITY, 0},
    {"--material", 1, O_MATERIAL, 0},
    {"--background", 1, O_BACKGROUND, 0},
    {"--tf", 1, O_TF, 0},
    {"--turntable", 1, O_TURNTABLE, 0},
    {"--fps", 1, O_FPS, 0},
    {"--size", 1, O_SIZE, 0},
    {"--view", 1, O_VIEW, 0},
    {"--up", 1, O_UP, 0},
    {"--roll", 1, O_ROLL, 0},
    {"--zoom", 1, O_ZOOM, 0},
    {"--perspective", 1, O_PERSPECTIVE, 0},
    {"--center", 1, O_CENTER, 0},
    {"--slab", 1, O_SLAB, 0},
    {"--kernel-radius", 1, O_KRADIUS, 0},
    {"--footprint-res", 1, O_FOOTPRINT, 0},
    {"--seam", 1, O_SEAM, 0},
    {"--threads", 1, O_THREADS, 0},
    {"--isa", 1, O_ISA, 0},
    {"--no-pin", 0, O_NO_PIN, 0},
    {"--no-occlusion", 0, O_NO_OCCL, 0},
    {"--occlusion-threshold", 1, O_OCCL_T, 0},
    {"--no-tiles", 0, O_NO_TILES, 0},
    {"--tile-size", 1, O_TILE_SIZE, 0},
    {"--exact-normals", 0, O_EXACT_N, 0},
    {"--normal-lut", 1, O_NORMAL_LUT, 0},
    {"--preintegration", 0, O_PREINT, 0},
    {"--no-preintegration", 0, O_NO_PREINT, 0},
    {"--cd-stencil", 1, O_CD_STENCIL, 0},
    {"--no-gs-normalize", 0, O_NO_GS_NORMALIZE, 0},
    {"--lod", 1, O_LOD, 0},
    {"--no-lod", 0, O_NO_LOD, 0},
    {"--resample", 1, O_RESAMPLE, 0},
    {"--ray-step", 1, O_RAY_STEP, 0},
    {"--trilinear", 0, O_TRILINEAR, 0},
    {"--no-analytic", 0, O_NO_ANALYTIC, 0},
    {"--ray-normalize", 0, O_RAY_NORMALIZE, 0},
    {"--light", 1, O_LIGHT, 0},
    {"--ambient", 1, O_AMBIENT, 0},
    {"--diffuse", 1, O_DIFFUSE, 0},
    {"--specular", 1, O_SPECULAR, 0},
    {"--shininess", 1, O_SHININESS, 0},
    {"--dims", 1, O_DIMS, 1},
    {"--type", 1, O_TYPE, 1},
    {"--spacing", 1, O_SPACING, 1},
    {"--endian", 1, O_ENDIAN, 1},
    {"--series", 1, O_SERIES, 1},
    {"--bits", 1, O_BITS, 0},
    {"--stats", 1, O_STATS, 0},
    {"--print-stats", 0, O_PRINT_STATS, 0},
    {"--trace", 1, O_TRACE, 0},
    {"-q", 0, O_QUIET, 0},
    {"--quiet", 0, O_QUIET, 0},
};

/* Look up `arg` (possibly "--name=value"); sets *inline_val for the '=' form. */
static const opt_def *find_opt(const char *arg, const char **inline_val)
{
    *inline_val = NULL;
    const char *eq = strchr(arg, '=');
    size_t n = eq && arg[1] == '-' ? (size_t)(eq - arg) : strlen(arg);
    for (size_t i = 0; i < sizeof opt_table / sizeof opt_table[0]; i++) {
        const opt_def *d = &opt_table[i];
        if (strlen(d->name) == n && !strncmp(d->name, arg, n)) {
            if (n < strlen(arg)) *inline_val = arg + n + 1;
            return d;
        }
    }
    return NULL;
}

/* ---- value parsers: each returns 0 or a usage error ---- */

static int parse_range_double(const char *opt, const char *v, double lo, double hi, int lo_open,
                              double *out, char *err, size_t cap)
{
    double x;
    if (!to_double(v, &x)) return fail(err, cap, "%s: '%s' is not a number", opt, v);
    if (x > hi || x < lo || (lo_open && x == lo))
        return fail(err, cap, "%s: %s is out of range (%s%g..%g)", opt, v, lo_open ? "> " : "", lo, hi);
    *out = x;
    return 0;
}

static int parse_range_int(const char *opt, const char *v, long lo, long hi, int *out, char *err,
                           size_t cap)
{
    double x;
    if (to_int(v, lo, hi, out)) return 0;
    if (to_double(v, &x) && x == floor(x))
        return fail(err, cap, "%s: %s is out of range (%ld..%ld)", opt, v, lo, hi);
    return fail(err, cap, "%s: '%s' is not an integer", opt, v);
}

static int parse_color(const char *opt, const char *v, int n, float *out, char *err, size_t cap)
{
    double c[4];
    if (!to_doubles(v, n, c))
        return fail(err, cap, "%s: expected %s (numbers in 0..1), got '%s'", opt,
                    n == 3 ? "R,G,B" : "R,G,B,A", v);
    for (int i = 0; i < n; i++) {
        if (c[i] < 0.0 || c[i] > 1.0)
            return fail(err, cap, "%s: component %g is out of range (0..1)", opt, c[i]);
        out[i] = (float)c[i];
    }
    return 0;
}

static int parse_iso(const char *v, vs_settings *s, char *err, size_t cap)
{
    char buf[128];
    size_t len = strlen(v);
    if (len == 0 || len >= sizeof buf) return fail(err, cap, "--iso: expected LO[:HI], got '%s'", v);
    memcpy(buf, v, len + 1);
    char *colon = strchr(buf, ':');
    double lo, hi = INFINITY;
    if (colon) *colon = '\0';
    if (!to_double(buf, &lo)) return fail(err, cap, "--iso: expected LO[:HI] (numbers), got '%s'", v);
    if (colon) {
        const char *h = colon + 1;
        if (*h == '\0' || !strcasecmp(h, "inf") || !strcasecmp(h, "+inf")) {
            hi = INFINITY;
        } else if (!to_double(h, &hi)) {
            return fail(err, cap, "--iso: expected LO[:HI] (numbers), got '%s'", v);
        } else if (hi < lo) {
            return fail(err, cap, "--iso: HI %g is below LO %g (the range %s is empty)", hi, lo, v);
        }
    }
    s->has_iso = 1;
    s->iso_lo = lo;
    s->iso_hi = hi;
    return 0;
}

static int parse_size(const char *v, vs_settings *s, char *err, size_t cap)
{
    char buf[64];
    size_t len = strlen(v);
    int w, h;
    if (len == 0 || len >= sizeof buf) return fail(err, cap, "--size: expected WxH, got '%s'", v);
    memcpy(buf, v, len + 1);
    char *x = strchr(buf, 'x');
    if (!x) x = strchr(buf, 'X');
    if (!x) return fail(err, cap, "--size: expected WxH, got '%s'", v);
    *x = '\0';
    if (!to_int(buf, 1, VS_MAX_IMAGE_DIM, &w) || !to_int(x + 1, 1, VS_MAX_IMAGE_DIM, &h))
        return fail(err, cap, "--size: expected WxH with each side in 1..%d, got '%s'", VS_MAX_IMAGE_DIM, v);
    s->width = w;
    s->height = h;
    return 0;
}

static int parse_dims(const char *v, vs_load_options *l, char *err, size_t cap)
{
    double d[3];
    if (!to_doubles(v, 3, d)) return fail(err, cap, "--dims: expected X,Y,Z (integers), got '%s'", v);
    for (int i = 0; i < 3; i++) {
        if (d[i] != floor(d[i]) || d[i] < 1 || d[i] > VS_MAX_DIM)
            return fail(err, cap, "--dims: each dimension must be an integer in 1..%d, got '%s'", VS_MAX_DIM, v);
        l->dims[i] = (int)d[i];
    }
    return 0;
}

static int parse_type(const char *v, vs_load_options *l, char *err, size_t cap)
{
    static const struct {
        const char *name;
        vs_type t;
    } types[] = {{"u8", VS_U8}, {"i16", VS_I16}, {"u16", VS_U16}, {"f32", VS_F32}};
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
        if (!strcmp(v, types[i].name)) {
            l->type = types[i].t;
            return 0;
        }
    return fail(err, cap, "--type: expected u8, i16, u16 or f32, got '%s'", v);
}

static int parse_spacing(const char *v, vs_load_options *l, char *err, size_t cap)
{
    double d[3];
    if (!to_doubles(v, 3, d)) return fail(err, cap, "--spacing: expected SX,SY,SZ, got '%s'", v);
    for (int i = 0; i < 3; i++)
        if (!(d[i] > 0.0 && d[i] <= 1e6))
            return fail(err, cap, "--spacing: each spacing must be > 0 (and <= 1e6), got '%s'", v);
    l->has_spacing = 1;
    memcpy(l->spacing, d, sizeof d);
    return 0;
}

/* ---- the parser ---- */

typedef struct seen {
    int dims, type, endian, spacing;
    int iso, ramp, opacity, material, bits, fps; /* conflicts with --tf, GIF */
} seen;

static int apply(const opt_def *d, const char *v, cli_opts *o, seen *sn, char *err, size_t cap)
{
    vs_settings *s = &o->s;
    const char *n = d->name;
    double t[3];
    switch (d->id) {
    case O_HELP: o->help = 1; return 0;
    case O_OUTPUT: o->output = v; return 0;
    case O_SCENE:
        if (!*v) return fail(err, cap, "--scene: expected NAME[:N]");
        o->scene = v;
        return 0;
    case O_PIPELINE:
        if (vs_pipeline_parse(v, &s->pipeline) != VS_OK)
            return fail(err, cap, "--pipeline: expected pre, post-cd, post-gs, post-alpha or raycast, got '%s'", v);
        return 0;
    case O_ISO: sn->iso = 1; return parse_iso(v, s, err, cap);
    case O_RAMP: sn->ramp = 1; return parse_range_double(n, v, 0.0, 1e300, 0, &s->ramp, err, cap);
    case O_OPACITY: {
        double a;
        sn->opacity = 1;
        if (parse_range_double(n, v, 0.0, 1.0, 0, &a, err, cap)) return 1;
        s->iso_opacity = (float)a;
        return 0;
    }
    case O_MATERIAL: sn->material = 1; return parse_color(n, v, 3, s->material, err, cap);
    case O_BACKGROUND: return parse_color(n, v, 4, s->background, err, cap);
    case O_TF:
        if (!*v) return fail(err, cap, "--tf: expected a file name (.json, .1dt or .vtf)");
        o->tf_path = v;
        return 0;
    case O_TURNTABLE: return parse_range_int(n, v, 1, 3600, &o->turntable, err, cap);
    case O_FPS: sn->fps = 1; return parse_range_double(n, v, 0.0, 100.0, 1, &o->fps, err, cap);
    case O_SIZE: return parse_size(v, s, err, cap);
    case O_VIEW: {
        if (vs_view_parse(v, &s->view) == VS_OK) {
            s->azimuth = s->elevation = 0.0;
            return 0;
        }
        if (!to_doubles(v, 2, t))
            return fail(err, cap,
                        "--view: expected anterior, posterior, left, right, superior, inferior or AZ,EL in "
                        "degrees, got '%s'",
                        v);
        if (fabs(t[0]) > 1e6 || fabs(t[1]) > 1e6)
            return fail(err, cap, "--view: angle %g is out of range (-1e6..1e6)", fabs(t[0]) > 1e6 ? t[0] : t[1]);
        s->view = VS_VIEW_ANGLES;
        s->azimuth = t[0];
        s->elevation = t[1];
        return 0;
    }
    case O_UP:
        if (!to_doubles(v, 3, t)) return fail(err, cap, "--up: expected X,Y,Z (world direction shown upwards), got '%s'", v);
        if (t[0] == 0.0 && t[1] == 0.0 && t[2] == 0.0) return fail(err, cap, "--up: the direction must not be zero");
        s->has_up = 1;
        memcpy(s->up, t, sizeof s->up);
        return 0;
    case O_ROLL: return parse_range_double(n, v, -1e6, 1e6, 0, &s->roll, err, cap);
    case O_ZOOM: return parse_range_double(n, v, 0.0, 1000.0, 1, &s->zoom, err, cap);
    case O_PERSPECTIVE: return parse_range_double(n, v, 0.0, 170.0, 0, &s->perspective_fov, err, cap);
    case O_CENTER:
        if (!to_doubles(v, 3, t)) return fail(err, cap, "--center: expected X,Y,Z (voxel coordinates), got '%s'", v);
        s->has_center = 1;
        memcpy(s->center, t, sizeof s->center);
        return 0;
    case O_SLAB: return parse_range_double(n, v, 0.05, 64.0, 0, &s->slab, err, cap);
    case O_KRADIUS: return parse_range_double(n, v, 0.5, 8.0, 0, &s->kernel_radius, err, cap);
    case O_FOOTPRINT: return parse_range_int(n, v, 8, 65536, &s->footprint_resolution, err, cap);
    case O_SEAM:
        if (!strcmp(v, "auto")) {
            s->seam = -1;
            return 0;
        }
        return parse_range_int(n, v, -1, 16, &s->seam, err, cap);
    case O_THREADS: return parse_range_int(n, v, 0, 256, &s->threads, err, cap);
    case O_ISA:
        if (vs_isa_parse(v, &s->isa) != VS_OK)
            return fail(err, cap, "--isa: expected auto, scalar, sse4, avx2 or avx512, got '%s'", v);
        return 0;
    case O_NO_PIN: s->pin = 0; return 0;
    case O_NO_OCCL: s->occlusion = 0; return 0;
    case O_OCCL_T: return parse_range_double(n, v, 0.0, 1.0, 1, &s->occlusion_threshold, err, cap);
    case O_NO_TILES: s->tile_counters = 0; return 0;
    case O_TILE_SIZE: return parse_range_int(n, v, 8, 4096, &s->tile_size, err, cap);
    case O_EXACT_N: s->exact_normals = 1; return 0;
    case O_PREINT: s->preintegration = 1; return 0;
    case O_NO_PREINT: s->preintegration = 0; return 0;
    case O_CD_STENCIL:
        if (!strcmp(v, "auto")) s->cd_stencil = 0;
        else if (!strcmp(v, "2")) s->cd_stencil = 2;
        else if (!strcmp(v, "4")) s->cd_stencil = 4;
        else return fail(err, cap, "--cd-stencil: expected auto, 2 or 4, got '%s'", v);
        return 0;
    case O_LOD: return parse_range_double(n, v, 0.0, 1e6, 0, &s->lod_pixels, err, cap);
    case O_NO_LOD: s->lod_pixels = 0.0; return 0;
    case O_RESAMPLE:
        if (!strcmp(v, "auto")) s->resample = -1;
        else if (!strcmp(v, "on")) s->resample = 1;
        else if (!strcmp(v, "off")) s->resample = 0;
        else return fail(err, cap, "--resample: expected auto, on or off, got '%s'", v);
        return 0;
    case O_NORMAL_LUT: return parse_range_int(n, v, 8, 65536, &s->normal_lut_size, err, cap);
    case O_RAY_STEP: return parse_range_double(n, v, 0.001, 16.0, 0, &s->ray_step, err, cap);
    case O_TRILINEAR: s->ray_trilinear = 1; return 0;
    case O_NO_ANALYTIC: s->ray_analytic = 0; return 0;
    case O_RAY_NORMALIZE: s->ray_normalize = 1; return 0;
    case O_NO_GS_NORMALIZE: s->gs_normalize = 0; return 0;
    case O_LIGHT:
        if (!to_doubles(v, 3, t)) return fail(err, cap, "--light: expected X,Y,Z (direction towards the light), got '%s'", v);
        if (t[0] == 0.0 && t[1] == 0.0 && t[2] == 0.0)
            return fail(err, cap, "--light: the direction must not be zero");
        s->headlight = 0;
        memcpy(s->light_dir, t, sizeof s->light_dir);
        return 0;
    case O_AMBIENT: return parse_range_double(n, v, 0.0, 10.0, 0, &s->ambient, err, cap);
    case O_DIFFUSE: return parse_range_double(n, v, 0.0, 10.0, 0, &s->diffuse, err, cap);
    case O_SPECULAR: return parse_range_double(n, v, 0.0, 10.0, 0, &s->specular, err, cap);
    case O_SHININESS: return parse_range_double(n, v, 0.0, 10000.0, 0, &s->shininess, err, cap);
    case O_DIMS: sn->dims = 1; return parse_dims(v, &o->load, err, cap);
    case O_TYPE: sn->type = 1; return parse_type(v, &o->load, err, cap);
    case O_SPACING: sn->spacing = 1; return parse_spacing(v, &o->load, err, cap);
    case O_SERIES:
        if (!*v) return fail(err, cap, "--series: expected a SeriesInstanceUID or a series number");
        o->load.series = v;
        return 0;
    case O_ENDIAN:
        sn->endian = 1;
        if (!strcmp(v, "little")) o->load.endian = VS_ENDIAN_LITTLE;
        else if (!strcmp(v, "big")) o->load.endian = VS_ENDIAN_BIG;
        else return fail(err, cap, "--endian: expected little or big, got '%s'", v);
        return 0;
    case O_BITS:
        sn->bits = 1;
        if (strcmp(v, "8") && strcmp(v, "16")) return fail(err, cap, "--bits: expected 8 or 16, got '%s'", v);
        o->bits = atoi(v);
        return 0;
    case O_STATS:
        if (!*v) return fail(err, cap, "--stats: expected a file name");
        o->stats_path = v;
        return 0;
    case O_PRINT_STATS: o->print_stats = 1; return 0;
    case O_TRACE:
        if (!*v) return fail(err, cap, "--trace: expected a file name");
        o->trace_path = v;
        return 0;
    case O_QUIET: o->quiet = 1; return 0;
    }
    return fail(err, cap, "%s: unhandled option", n);
}

static int env_defaults(vs_settings *s, char *err, size_t cap)
{
    const char *t = getenv("VSPLAT_THREADS");
    if (t && *t && !to_int(t, 0, 256, &s->threads))
        return fail(err, cap, "VSPLAT_THREADS: expected an integer in 0..256, got '%s'", t);
    const char *i = getenv("VSPLAT_ISA");
    if (i && *i && vs_isa_parse(i, &s->isa) != VS_OK)
        return fail(err, cap, "VSPLAT_ISA: expected auto, scalar, sse4, avx2 or avx512, got '%s'", i);
    return 0;
}

static int parse_common(int argc, char **argv, cli_opts *o, int is_info, char *err, size_t cap)
{
    memset(o, 0, sizeof *o);
    vs_settings_init(&o->s);
    vs_load_options_init(&o->load);
    o->bits = 8;
    if (!is_info && env_defaults(&o->s, err, cap)) return 1;

    seen sn;
    memset(&sn, 0, sizeof sn);
    o->fps = 15.0;
    int only_positional = 0;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        if (only_positional || a[0] != '-' || a[1] == '\0') {
            if (o->input)
                return fail(err, cap, "more than one input given ('%s' and '%s')", o->input, a);
            o->input = a;
            continue;
        }
        if (!strcmp(a, "--")) {
            only_positional = 1;
            continue;
        }
        const char *val = NULL;
        const opt_def *d = find_opt(a, &val);
        if (!d || (is_info && !d->info_ok))
            return fail(err, cap, "%s: unknown option for '%s' (see vsplat %s --help)", a,
                        is_info ? "info" : "render", is_info ? "info" : "render");
        if (d->has_arg) {
            if (!val) {
                if (i + 1 >= argc) return fail(err, cap, "%s: missing value", d->name);
                val = argv[++i];
            }
        } else if (val) {
            return fail(err, cap, "%s: takes no value", d->name);
        }
        if (apply(d, val, o, &sn, err, cap)) return 1;
        if (o->help) return 0;
    }

    /* input */
    if (o->scene && o->input)
        return fail(err, cap, "give either an input file or --scene, not both ('%s' and --scene %s)", o->input,
                    o->scene);
    if (!o->scene && !o->input) return fail(err, cap, "no input: give a volume file or --scene NAME[:N]");
    if (sn.dims != sn.type)
        return fail(err, cap, "raw input needs both --dims X,Y,Z and --type u8|i16|u16|f32");
    if (sn.endian && !sn.dims) return fail(err, cap, "--endian applies to raw input only (give --dims and --type)");
    if (o->scene && (sn.dims || sn.spacing))
        return fail(err, cap, "--dims/--type/--spacing/--endian apply to volume files, not to --scene");
    o->load.raw = sn.dims;

    if (!is_info) {
        if (!o->output) return fail(err, cap, "no output: give -o OUT (.png, .exr, .tif, .tiff or .gif)");
        const char *fmt = cli_output_format(o->output);
        if (!fmt)
            return fail(err, cap, "%s: unknown image format (use .png, .exr, .tif, .tiff or .gif)", o->output);
        if (o->tf_path && (sn.iso || sn.ramp || sn.opacity || sn.material))
            return fail(err, cap, "--tf %s replaces --iso, --ramp, --opacity and --material: give one or the other",
                        o->tf_path);
        if (!strcmp(fmt, "gif") && sn.bits && o->bits != 8)
            return fail(err, cap, "--bits %d: GIF output is 8-bit", o->bits);
        if (sn.fps && strcmp(fmt, "gif"))
            return fail(err, cap, "--fps applies to animated GIF output (-o OUT.gif) only");
        if (o->turntable && strcmp(fmt, "gif")) {
            char probe[4096];
            if (cli_frame_name(o->output, o->turntable - 1, probe, sizeof probe))
                return fail(err, cap, "%s: path too long for the turntable frame names", o->output);
        }
        if (o->stats_path && !strcmp(o->stats_path, o->output))
            return fail(err, cap, "--stats: %s is also the output image", o->stats_path);
        if (o->trace_path && !strcmp(o->trace_path, o->output))
            return fail(err, cap, "--trace: %s is also the output image", o->trace_path);
        if (o->trace_path && o->stats_path && !strcmp(o->trace_path, o->stats_path))
            return fail(err, cap, "--trace: %s is also the --stats file", o->trace_path);
    }
    return 0;
}

int cli_parse_render(int argc, char **argv, cli_opts *o, char *err, size_t errcap)
{
    return parse_common(argc, argv, o, 0, err, errcap);
}

int cli_parse_info(int argc, char **argv, cli_opts *o, char *err, size_t errcap)
{
    return parse_common(argc, argv, o, 1, err, errcap);
}

void cli_settle_view(cli_opts *o, const vs_volume *vol)
{
    if (o->s.view != VS_VIEW_AUTO) return;
    double m[12];
    o->s.view = vs_volume_affine(vol, m) && o->s.azimuth == 0.0 && o->s.elevation == 0.0 ? VS_VIEW_ANTERIOR
                                                                                          : VS_VIEW_ANGLES;
}

const char *cli_output_format(const char *path)
{
    if (!path) return NULL;
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    if (!dot || dot == base) return NULL;
    if (!strcasecmp(dot, ".png")) return "png";
    if (!strcasecmp(dot, ".exr")) return "exr";
    if (!strcasecmp(dot, ".tif") || !strcasecmp(dot, ".tiff")) return "tiff";
    if (!strcasecmp(dot, ".gif")) return "gif";
    return NULL;
}

int cli_frame_name(const char *out, int frame, char *buf, size_t cap)
{
    const char *slash = strrchr(out, '/');
    const char *base = slash ? slash + 1 : out;
    const char *dot = strrchr(base, '.');
    size_t stem = dot && dot != base ? (size_t)(dot - out) : strlen(out);
    int n = snprintf(buf, cap, "%.*s_%04d%s", (int)stem, out, frame, out + stem);
    return n < 0 || (size_t)n >= cap ? 1 : 0;
}

/* ---- usage ---- */

void cli_usage(FILE *f)
{
    fprintf(f,
            "vsplat %s — volume splatting without the blur\n"
            "\n"
            "usage:\n"
            "  vsplat render INPUT [options] -o OUT   render a volume (INPUT: file, or --scene NAME[:N])\n"
            "  vsplat info INPUT [raw options]       dimensions, type, spacing, value range, default iso\n"
            "  vsplat compare A B                    rmse=… psnr=… ssim=… max=… of two images\n"
            "  vsplat --version | --help\n"
            "  vsplat render --help                  every render option\n"
            "\n"
            "exit codes: 0 success, 1 bad input or usage, 2 internal error\n"
            "environment: VSPLAT_THREADS, VSPLAT_ISA (defaults for --threads, --isa), VSPLAT_DATA\n",
            vs_version());
}

void cli_render_usage(FILE *f)
{
    fprintf(f,
            "usage: vsplat render INPUT [options] -o OUT\n"
            "       vsplat render --scene NAME[:N] [options] -o OUT\n"
            "\n"
            "input:\n"
            "  INPUT                  .nii/.nii.gz, .nrrd/.nhdr, .mha/.mhd, DICOM series (folder or one\n"
            "                         file), .tif/.tiff stack, folder or .tar of PNG slices, .den,\n"
            "                         or raw: with --dims and --type, or named NAME_XxYxZ_TYPE.raw\n"
            "                         (also .raw.gz, .bin, .vol; TYPE u8, i16, u16 or f32, optionally\n"
            "                         + le/be: e.g. ct_256x256x108_i16le.raw.gz).  Raw data and image\n"
            "                         stacks have no orientation (taken as RAS) and, raw, no spacing\n"
            "                         (1,1,1 unless --spacing): a note says so\n"
            "  --series UID|N         DICOM: the series to read from a folder holding several\n"
            "  --scene NAME[:N]       synthetic scene: cube, sphere, ml, head, cell (N voxels per side)\n"
            "  --dims X,Y,Z           raw input dimensions (with --type)\n"
            "  --type u8|i16|u16|f32  raw voxel type\n"
            "  --endian little|big    raw byte order (default little)\n"
            "  --spacing SX,SY,SZ     voxel spacing in mm (overrides the file's; keeps its orientation)\n"
            "output:\n"
            "  -o OUT                 image; format from the extension: .png, .exr, .tif, .tiff, .gif\n"
            "  --bits 8|16            PNG bit depth (default 8)\n"
            "  --stats FILE.json      per-stage timings and counts as JSON (- : on stdout)\n"
            "  --print-stats          per-stage timing table on stdout\n"
            "  --trace FILE.json      timeline of every thread's tiles and stages (Chrome Trace\n"
            "                         Event format: open in ui.perfetto.dev or chrome://tracing)\n"
            "  -q                     quiet: no summary line, no notes, no progress\n"
            "pipeline and classification:\n"
            "  --pipeline P           pre | post-cd | post-gs | post-alpha | raycast (default post-cd)\n"
            "  --iso LO[:HI]          iso-range in data units (default: Otsu threshold, open range)\n"
            "  --ramp W               opacity ramp half-width (default 2%% of the data range)\n"
            "  --opacity A            opacity inside the iso-range, 0..1 (default 1)\n"
            "  --material R,G,B       material colour, 0..1 (default 1,1,1)\n"
            "  --background R,G,B,A   background, 0..1 (default 0,0,0,0)\n"
            "  --tf FILE              transfer function: ParaView preset .json, ImageVis3D .1dt\n"
            "                         (spread over the data range) or vsplat .vtf (iso LO HI R G B A RAMP);\n"
            "                         replaces --iso/--ramp/--opacity/--material\n"
            "view:\n"
            "  --size WxH             image size (default 512x512)\n"
            "  --view V               anterior | posterior | left | right | superior | inferior, or\n"
            "                         AZ,EL: azimuth, elevation in degrees in the world frame (RAS:\n"
            "                         0,0 looks along +y from behind, +z up; 180,0 = anterior).\n"
            "                         Default: anterior for a volume with an orientation, else 0,0\n"
            "  --up X,Y,Z             world direction shown upwards (e.g. 0,0,1: superior up)\n"
            "  --roll DEG             turn the picture DEG degrees clockwise (after --up)\n"
            "  --zoom Z               largest extent spans Z of the image width (default 0.8)\n"
            "  --perspective FOV      perspective camera, vertical field of view in degrees, 0..170\n"
            "                         (default 0: orthographic); the centre plane keeps --zoom's scale\n"
            "  --center X,Y,Z         image centre in voxel coordinates (default: volume centre)\n"
            "  --turntable N          N frames, azimuth stepping 360/N from --view: OUT_0000.ext ...,\n"
            "                         or one animated GIF if OUT ends in .gif\n"
            "  --fps F                frames per second of an animated GIF (default 15)\n"
            "kernel and sheets:\n"
            "  --slab DS              sheet thickness in voxel units, 0.05..64 (default 1)\n"
            "  --kernel-radius R      Gaussian kernel radius, 0.5..8 (default 2)\n"
            "  --footprint-res N      footprint table entries per radius unit (default 256)\n"
            "  --seam N|auto          seam layer width in voxels (default auto)\n"
            "  --no-preintegration    classify each sheet alone (default: post-cd, -gs, -alpha classify\n"
            "                         the segment to the next sheet, pre-integrated, when the\n"
            "                         classification is translucent; --preintegration always)\n"
            "  --cd-stencil auto|2|4  post-cd's differences within and across sheets: 2 the paper's\n"
            "                         central differences, 4 a four-point stencil (auto: within a\n"
            "                         sheet where voxels lie under 1.5 pixels apart on the image,\n"
            "                         across plain sheets from 0.7 pixel a voxel times --slab,\n"
            "                         see vsplat(1))\n"
            "  --no-gs-normalize      post-gs: the paper's plain gradient splats, with the kernel's\n"
            "                         lattice ripple (default: the ripple taken out, see vsplat(1))\n"
            "leaving out work:\n"
            "  --lod PX               levels of detail: splat a filtered copy of the volume whose\n"
            "                         voxels lie at most PX pixels apart (default 1)\n"
            "  --no-lod               full resolution however small the volume is seen\n"
            "  --resample auto|on|off anisotropic voxels (1.25x thicker along an axis or more):\n"
            "                         splat a copy on cubic voxels that reconstructs the same\n"
            "                         field (auto: if it needs at most the volume's memory + 64 MB)\n"
            "  --no-occlusion         no early splat elimination\n"
            "  --occlusion-threshold T  opacity above which a pixel is occluded (default 0.995)\n"
            "  --no-tiles             no tile counters: shade every tile of every sheet\n"
            "  --tile-size N          tile edge in pixels, 8..4096 (default 64)\n"
            "  --exact-normals        exact normalization instead of the Clyne-Dennis LUT\n"
            "                         (post-shaded) or 16-bit normal codes (pre, post-alpha)\n"
            "  --normal-lut N         angle bins of the post-shaded shading table (default 256)\n"
            "lighting (one directional light, Phong):\n"
            "  --light X,Y,Z          direction towards the light, world space (turns the headlight off)\n"
            "  --ambient K  --diffuse K  --specular K  --shininess N   (defaults 0.2 0.6 0.2 20)\n"
            "reference ray caster (--pipeline raycast):\n"
            "  --ray-step S           step in voxel units (default 0.1)\n"
            "  --trilinear            trilinear instead of exact Gaussian reconstruction\n"
            "  --no-analytic          sample the voxels even if the scene is analytic\n"
            "  --ray-normalize        Gaussian weights over their sum: without the lattice ripple\n"
            "execution:\n"
            "  --threads N            worker threads, 0..256, 0 = one per core (default $VSPLAT_THREADS or 0)\n"
            "  --isa I                auto | scalar | sse4 | avx2 | avx512 (default $VSPLAT_ISA or auto)\n"
            "  --no-pin               do not bind workers to cores\n"
            "  --help                 this text\n");
}

void cli_info_usage(FILE *f)
{
    fprintf(f,
            "usage: vsplat info INPUT [--dims X,Y,Z --type u8|i16|u16|f32 [--endian little|big]]\n"
            "                         [--spacing SX,SY,SZ] [--series UID|N]\n"
            "       vsplat info --scene NAME[:N]\n"
            "prints dims, type, spacing, range, voxels, default_iso, analytic, orientation (the\n"
            "nearest anatomical direction of each index axis, e.g. RAS or LPS, or none) and transform\n"
            "(index to RAS millimetres, three rows), one 'key: value' per line.  Raw input: --dims and\n"
            "--type, or a name like NAME_XxYxZ_TYPE.raw (TYPE u8, i16, u16, f32; +le/be)\n");
}

vs_status cli_load_tf(vs_context *ctx, cli_opts *o, const vs_volume *vol, vs_tf_point **tf)
{
    *tf = NULL;
    if (!o->tf_path) return VS_OK;
    int n = 0;
    const vs_status st = vs_tf_load_for_volume(ctx, o->tf_path, vol, tf, &n);
    if (st != VS_OK) return st;
    o->s.tf = *tf;
    o->s.tf_count = n;
    return VS_OK;
}
