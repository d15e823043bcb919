/* vsplat — command-line tool: render, info, compare (docs/DESIGN.md §2).
 *
 * Exit codes: 0 success, 1 bad input or usage (one line on stderr naming the
 * file or option and the problem), 2 internal error (out of memory, bug). */
#include "cli_args.h"
#include "vsplat.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

enum { EXIT_USAGE = 1, EXIT_INTERNAL = 2 };

static int exit_code_for(vs_status st)
{
    return st == VS_ERR_INTERNAL || st == VS_ERR_OUT_OF_MEMORY ? EXIT_INTERNAL : EXIT_USAGE;
}

/* One line: "vsplat: PATH: problem".  The library's message is used as is if
 * it already names the path. */
static int report(vs_context *ctx, vs_status st, const char *path)
{
    const char *msg = ctx ? vs_last_error(ctx) : "";
    if (!msg || !*msg) msg = vs_status_string(st);
    if (path && !strstr(msg, path))
        fprintf(stderr, "vsplat: %s: %s\n", path, msg);
    else
        fprintf(stderr, "vsplat: %s\n", msg);
    return exit_code_for(st);
}

static int usage_error(const char *msg)
{
    fprintf(stderr, "vsplat: %s\n", msg);
    return EXIT_USAGE;
}

/* The folder that will hold `path` must exist and be a writable directory. */
static int check_writable_dir(const char *path, char *err, size_t cap)
{
    char dir[4096];
    const char *slash = strrchr(path, '/');
    if (!slash) {
        strcpy(dir, ".");
    } else if (slash == path) {
        strcpy(dir, "/");
    } else {
        size_t n = (size_t)(slash - path);
        if (n >= sizeof dir) {
            snprintf(err, cap, "%s: path is too long", path);
            return 1;
        }
        memcpy(dir, path, n);
        dir[n] = '\0';
    }
    struct stat sb;
    if (stat(dir, &sb) != 0) {
        snprintf(err, cap, "%s: cannot write: folder %s does not exist", path, dir);
        return 1;
    }
    if (!S_ISDIR(sb.st_mode)) {
        snprintf(err, cap, "%s: cannot write: %s is not a folder", path, dir);
        return 1;
    }
    if (access(dir, W_OK) != 0) {
        snprintf(err, cap, "%s: cannot write: folder %s is not writable", path, dir);
        return 1;
    }
    if (stat(path, &sb) == 0 && S_ISDIR(sb.st_mode)) {
        snprintf(err, cap, "%s: cannot write: it is a folder", path);
        return 1;
    }
    return 0;
}

static int load_input(vs_context *ctx, const cli_opts *o, vs_volume **vol)
{
    vs_status st = o->scene ? vs_volume_scene(ctx, o->scene, vol)
                            : vs_volume_load(ctx, o->input, &o->load, vol);
    if (st != VS_OK) return report(ctx, st, o->scene ? "--scene" : o->input);
    return 0;
}

/* ---- orientation ---- */

/* The nearest anatomical axis of each index axis ("RAS", "LPS", ...): the
 * largest entry of the normalised columns first, then the next among the
 * remaining rows and columns.  *oblique: some axis is off its letter's
 * axis; *sheared: the columns are not orthogonal. */
static void orientation_code(const double m[12], char code[4], int *oblique, int *sheared)
{
    double q[3][3];
    for (int c = 0; c < 3; c++) {
        double n = sqrt(m[c] * m[c] + m[4 + c] * m[4 + c] + m[8 + c] * m[8 + c]);
        for (int r = 0; r < 3; r++) q[r][c] = n > 0 ? m[4 * r + c] / n : 0.0;
    }
    int row_used[3] = {0, 0, 0}, col_used[3] = {0, 0, 0};
    *oblique = 0;
    for (int k = 0; k < 3; k++) {
        int br = 0, bc = 0;
        double best = -1.0;
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                if (!row_used[r] && !col_used[c] && fabs(q[r][c]) > best) best = fabs(q[r][c]), br = r, bc = c;
        row_used[br] = col_used[bc] = 1;
        code[bc] = q[br][bc] > 0 ? "RAS"[br] : "LPI"[br];
        if (best < 1.0 - 1e-6) *oblique = 1;
    }
    code[3] = '\0';
    *sheared = 0;
    for (int a = 0; a < 3; a++)
        for (int b = a + 1; b < 3; b++)
            if (fabs(q[0][a] * q[0][b] + q[1][a] * q[1][b] + q[2][a] * q[2][b]) > 1e-4) *sheared = 1;
}

/* Raw formats and image stacks carry no spacing (TIFF resolution aside). */
static int format_has_spacing(const cli_opts *o)
{
    static const char *const ext[] = {".nii", ".nii.gz", ".hdr", ".img", ".hdr.gz", ".img.gz", ".nrrd", ".nhdr",
                                      ".mha", ".mhd"};
    if (o->load.raw) return 0;
    size_t n = strlen(o->input);
    for (size_t i = 0; i < sizeof ext / sizeof ext[0]; i++) {
        size_t m = strlen(ext[i]);
        if (n >= m && !strcasecmp(o->input + n - m, ext[i])) return 1;
    }
    return 0;
}

/* "Never silently assume": what the file did not say, on stderr. */
static void geometry_notes(const cli_opts *o, const vs_volume *vol)
{
    if (o->scene) return;
    double m[12], sp[3];
    if (vs_volume_affine(vol, m)) return;
    vs_volume_spacing(vol, sp);
    fprintf(stderr,
            "vsplat: note: %s: no orientation in the file; its x, y, z axes are taken as right, anterior, "
            "superior (RAS)\n",
            o->input);
    if (!o->load.has_spacing && !format_has_spacing(o) && sp[0] == 1.0 && sp[1] == 1.0 && sp[2] == 1.0)
        fprintf(stderr, "vsplat: note: %s: no voxel spacing in the file; assumed 1,1,1 (give --spacing SX,SY,SZ)\n",
                o->input);
}

/* ---- progress ---- */

/* On a terminal, a render that has run for a second shows its progress on
 * stderr ("\r", one line, cleared at the end); nothing otherwise. */
typedef struct progress {
    double t0, last;
    int frame, frames, shown;
} progress;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int show_progress(void *user, double fraction)
{
    progress *p = user;
    double t = now_s();
    if (t - p->t0 < 1.0 || (t - p->last < 0.1 && fraction < 1.0)) return 0;
    p->last = t;
    p->shown = 1;
    double all = (p->frame + fraction) / p->frames;
    if (p->frames > 1)
        fprintf(stderr, "\rvsplat: rendering frame %d of %d, %3.0f%%", p->frame + 1, p->frames, 100.0 * all);
    else
        fprintf(stderr, "\rvsplat: rendering %3.0f%%", 100.0 * all);
    fflush(stderr);
    return 0;
}

static void end_progress(progress *p)
{
    if (p->shown) fprintf(stderr, "\r\033[K");
    p->shown = 0;
}

/* ---- stats ---- */

/* The stats as JSON in a new buffer (its length in *len), or NULL with a
 * message naming `what` when out of memory. */
static char *stats_json(const vs_stats *st, const char *what, size_t *len)
{
    *len = vs_stats_to_json(st, NULL, 0);
    char *buf = malloc(*len + 1);
    if (!buf) {
        fprintf(stderr, "vsplat: %s: out of memory\n", what);
        return NULL;
    }
    vs_stats_to_json(st, buf, *len + 1);
    return buf;
}

/* JSON into "<path>.tmp.<pid>"; renamed into place by the caller. */
static int write_stats_tmp(const vs_stats *st, const char *path, char *tmp, size_t tmpcap)
{
    snprintf(tmp, tmpcap, "%s.tmp.%ld", path, (long)getpid());
    size_t need;
    char *buf = stats_json(st, path, &need);
    if (!buf) return EXIT_INTERNAL;
    FILE *f = fopen(tmp, "wb");
    if (!f) {
        fprintf(stderr, "vsplat: %s: cannot write: %s\n", path, strerror(errno));
        free(buf);
        return EXIT_USAGE;
    }
    int ok = fwrite(buf, 1, need, f) == need;
    ok = (fclose(f) == 0) && ok;
    free(buf);
    if (!ok) {
        fprintf(stderr, "vsplat: %s: cannot write: %s\n", path, strerror(errno));
        remove(tmp);
        return EXIT_USAGE;
    }
    return 0;
}

/* --stats -: the JSON on stdout. */
static int print_stats_json(const vs_stats *st)
{
    size_t need;
    char *buf = stats_json(st, "stats", &need);
    if (!buf) return EXIT_INTERNAL;
    int ok = fwrite(buf, 1, need, stdout) == need && fflush(stdout) == 0;
    free(buf);
    if (!ok) fprintf(stderr, "vsplat: stats: cannot write to standard output: %s\n", strerror(errno));
    return ok ? 0 : EXIT_INTERNAL;
}

static void print_stats_table(const vs_stats *st)
{
    const vs_stage_times *t = &st->ms_stage;
    double sum = t->setup + t->rasterize + t->gradient + t->shade + t->composite;
    printf("pipeline %s, isa %s, %d thread%s, %dx%d\n", st->pipeline ? st->pipeline : "?",
           st->isa ? st->isa : "?", st->threads, st->threads == 1 ? "" : "s", st->width, st->height);
    printf("voxels: %llu total, %llu relevant, %llu splatted, %llu culled", (unsigned long long)st->voxels_total,
           (unsigned long long)st->voxels_relevant, (unsigned long long)st->voxels_splatted,
           (unsigned long long)st->voxels_culled);
    if (st->lod_level > 0) printf(" (level of detail %d: the relevant and later counts are its)", st->lod_level);
    printf("\n");
    printf("sheets: %llu, tile-sheets shaded: %llu of %llu\n", (unsigned long long)st->sheets,
           (unsigned long long)st->tiles_shaded, (unsigned long long)st->tiles_total);
    printf("%-22s %12s %7s\n", "stage", "ms", "share");
    const struct {
        const char *name;
        double v;
    } rows[5] = {{"setup", t->setup},
                 {"rasterize", t->rasterize},
                 {"gradient", t->gradient},
                 {"shade", t->shade},
                 {"composite", t->composite}};
    for (int i = 0; i < 5; i++)
        printf("%-22s %12.3f %6.1f%%\n", rows[i].name, rows[i].v, sum > 0 ? 100.0 * rows[i].v / sum : 0.0);
    printf("%-22s %12.3f\n", "sum (over threads)", sum);
    printf("%-22s %12.3f\n", "relevant-voxel list", st->ms_relevant);
    if (st->ms_lod > 0) printf("%-22s %12.3f\n", "levels of detail", st->ms_lod);
    printf("%-22s %12.3f\n", "total (wall clock)", st->ms_total);
    if (st->pin_warning) printf("note: binding workers to cores failed\n");
    fflush(stdout); /* keep the table ahead of later stderr lines */
}

/* ---- rendering one image or a turntable ---- */

static void remove_frames(const cli_opts *o, int n)
{
    char name[4200];
    for (int f = 0; f < n; f++)
        if (!cli_frame_name(o->output, f, name, sizeof name)) remove(name);
}

/* Renders o->turntable frames (or one image) and writes them: OUT itself,
 * OUT_0000.ext ... for a turntable, or one animated GIF.  --stats gets the
 * last frame's figures.  On failure nothing half-finished is left. */
static int render_and_write(vs_context *ctx, const vs_volume *vol, cli_opts *o)
{
    const int is_gif = !strcmp(cli_output_format(o->output), "gif");
    const int nframes = o->turntable > 0 ? o->turntable : 1;
    const int sequence = o->turntable > 0 && !is_gif;
    const double az0 = o->s.azimuth;
    vs_image *frames = NULL;
    if (is_gif) {
        double bytes = (double)nframes * o->s.width * o->s.height * 4.0 * sizeof(float);
        if (bytes > 4.0 * 1024 * 1024 * 1024) {
            fprintf(stderr, "vsplat: %s: %d frames of %dx%d need %.1f GiB for an animated GIF; "
                            "write a PNG sequence (-o OUT.png) instead\n",
                    o->output, nframes, o->s.width, o->s.height, bytes / (1024.0 * 1024 * 1024));
            return EXIT_USAGE;
        }
        frames = calloc((size_t)nframes, sizeof *frames);
        if (!frames) {
            fprintf(stderr, "vsplat: %s: out of memory\n", o->output);
            return EXIT_INTERNAL;
        }
    }
    vs_stats stats;
    memset(&stats, 0, sizeof stats);
    vs_trace *trace = NULL;
    if (o->trace_path) {
        if (vs_trace_create(&trace) != VS_OK) {
            fprintf(stderr, "vsplat: %s: out of memory\n", o->trace_path);
            free(frames);
            return EXIT_INTERNAL;
        }
        o->s.trace = trace;
    }
    double ms_all = 0.0;
    int rc = 0, written = 0;
    char name[4200];
    progress prog = {now_s(), 0.0, 0, nframes, 0};
    if (!o->quiet && isatty(STDERR_FILENO)) {
        o->s.progress = show_progress;
        o->s.progress_user = &prog;
    }
    for (int f = 0; f < nframes && !rc; f++) {
        prog.frame = f;
        o->s.azimuth = az0 + 360.0 * f / nframes;
        vs_image img = {0, 0, NULL};
        vs_status st = vs_render(ctx, vol, &o->s, &img, &stats);
        if (st != VS_OK) {
            rc = report(ctx, st, o->scene ? o->scene : o->input);
            vs_image_free(&img);
            break;
        }
        ms_all += stats.ms_total;
        if (is_gif) {
            frames[f] = img;
        } else if (sequence) {
            cli_frame_name(o->output, f, name, sizeof name);
            st = vs_image_write(ctx, name, &img, o->bits);
            vs_image_free(&img);
            if (st != VS_OK) rc = report(ctx, st, name);
            else written++;
        } else {
            frames = malloc(sizeof *frames);
            if (!frames) {
                vs_image_free(&img);
                fprintf(stderr, "vsplat: %s: out of memory\n", o->output);
                rc = EXIT_INTERNAL;
                break;
            }
            frames[0] = img;
        }
    }
    end_progress(&prog);
    o->s.progress = NULL;
    if (sequence && rc) remove_frames(o, written);
    if (!rc && trace) {
        vs_status st = vs_trace_write(ctx, trace, o->trace_path);
        if (st != VS_OK) rc = report(ctx, st, o->trace_path);
    }
    o->s.trace = NULL;
    vs_trace_release(trace);

    /* --stats -: the JSON goes to stdout once everything is written */
    const int stats_file = o->stats_path && strcmp(o->stats_path, "-") != 0;
    char stats_tmp[4200] = "";
    if (!rc && stats_file) {
        rc = write_stats_tmp(&stats, o->stats_path, stats_tmp, sizeof stats_tmp);
        if (rc && sequence) remove_frames(o, written);
    }
    if (!rc && !sequence) {
        vs_status st = is_gif ? vs_image_write_frames(ctx, o->output, frames, nframes, o->fps)
                              : vs_image_write(ctx, o->output, &frames[0], o->bits);
        if (st != VS_OK) {
            rc = report(ctx, st, o->output);
            if (stats_file) remove(stats_tmp);
        }
    }
    if (frames)
        for (int f = 0; f < (is_gif ? nframes : 1); f++) vs_image_free(&frames[f]);
    free(frames);
    if (rc) return rc;
    if (stats_file && rename(stats_tmp, o->stats_path) != 0) {
        fprintf(stderr, "vsplat: %s: cannot write: %s\n", o->stats_path, strerror(errno));
        remove(stats_tmp);
        if (sequence) remove_frames(o, nframes);
        else remove(o->output); /* no half-finished results */
        return EXIT_USAGE;
    }

    if (o->stats_path && !stats_file && print_stats_json(&stats) != 0) return EXIT_INTERNAL;
    if (o->print_stats) print_stats_table(&stats);
    if (!o->quiet) {
        const char *pipe = stats.pipeline ? stats.pipeline : vs_pipeline_name(o->s.pipeline);
        if (sequence) {
            char last[4200];
            cli_frame_name(o->output, 0, name, sizeof name);
            cli_frame_name(o->output, nframes - 1, last, sizeof last);
            fprintf(stderr, "vsplat: wrote %s ... %s (%d frames, %dx%d, %s, %.1f ms)\n", name, last, nframes,
                    stats.width, stats.height, pipe, ms_all);
        } else if (nframes > 1) {
            fprintf(stderr, "vsplat: wrote %s (%d frames, %dx%d, %s, %.1f ms)\n", o->output, nframes, stats.width,
                    stats.height, pipe, ms_all);
        } else {
            fprintf(stderr, "vsplat: wrote %s (%dx%d, %s, %.1f ms)\n", o->output, stats.width, stats.height, pipe,
                    stats.ms_total);
        }
    }
    return 0;
}

/* ---- subcommands ---- */

static int cmd_render(int argc, char **argv)
{
    cli_opts o;
    char err[1024];
    if (cli_parse_render(argc, argv, &o, err, sizeof err)) return usage_error(err);
    if (o.help) {
        cli_render_usage(stdout);
        return 0;
    }
    if (check_writable_dir(o.output, err, sizeof err)) return usage_error(err);
    if (o.stats_path && check_writable_dir(o.stats_path, err, sizeof err)) return usage_error(err);
    if (o.trace_path && check_writable_dir(o.trace_path, err, sizeof err)) return usage_error(err);

    vs_context *ctx = NULL;
    vs_status st = vs_context_create(&ctx);
    if (st != VS_OK) {
        fprintf(stderr, "vsplat: cannot create a context: %s\n", vs_status_string(st));
        return exit_code_for(st);
    }
    vs_volume *vol = NULL;
    int rc = load_input(ctx, &o, &vol);
    if (rc) {
        vs_context_release(ctx);
        return rc;
    }

    if (!o.quiet) geometry_notes(&o, vol);
    /* the default view, fixed before a turntable turns the azimuth from it */
    cli_settle_view(&o, vol);

    /* --tf: the .1dt format needs the volume's value range, so load it now. */
    vs_tf_point *tf = NULL;
    if ((st = cli_load_tf(ctx, &o, vol, &tf)) != VS_OK) {
        rc = report(ctx, st, o.tf_path);
        vs_volume_release(vol);
        vs_context_release(ctx);
        return rc;
    }

    /* Non-finite voxels (NaN, Inf) are accepted and rendered as 0 (README
     * "Stiff cases"), but say so. */
    if (!o.quiet && vs_volume_type(vol) == VS_F32) {
        int d[3];
        vs_volume_dims(vol, d);
        const float *p = vs_volume_data(vol);
        size_t n = (size_t)d[0] * d[1] * d[2], bad = 0;
        for (size_t i = 0; i < n; i++) bad += !isfinite(p[i]);
        if (bad)
            fprintf(stderr, "vsplat: note: %s: %zu non-finite voxels (NaN or Inf) are rendered as 0\n",
                    o.scene ? o.scene : o.input, bad);
    }

    /* An iso-range outside the data is allowed (the image is blank), but say so. */
    if (o.s.has_iso && o.s.tf_count == 0 && !o.quiet) {
        double lo, hi;
        vs_volume_range(vol, &lo, &hi);
        double w = o.s.ramp >= 0 ? o.s.ramp : 0.02 * (hi - lo);
        if (o.s.iso_lo - w > hi || o.s.iso_hi + w < lo)
            fprintf(stderr, "vsplat: note: iso-range %g:%g lies outside the data range %g..%g; the image will be blank\n",
                    o.s.iso_lo, o.s.iso_hi, lo, hi);
        else if (o.s.iso_lo + w <= lo && o.s.iso_hi - w >= hi)
            fprintf(stderr,
                    "vsplat: note: iso-range %g:%g (ramp %g) takes in the whole data range %g..%g; every voxel is "
                    "opaque and the image shows the volume's box\n",
                    o.s.iso_lo, o.s.iso_hi, w, lo, hi);
    }

    rc = render_and_write(ctx, vol, &o);
    vs_volume_release(vol);
    vs_tf_free(tf);
    vs_context_release(ctx);
    return rc;
}

static int cmd_info(int argc, char **argv)
{
    cli_opts o;
    char err[1024];
    if (cli_parse_info(argc, argv, &o, err, sizeof err)) return usage_error(err);
    if (o.help) {
        cli_info_usage(stdout);
        return 0;
    }
    vs_context *ctx = NULL;
    vs_status st = vs_context_create(&ctx);
    if (st != VS_OK) {
        fprintf(stderr, "vsplat: cannot create a context: %s\n", vs_status_string(st));
        return exit_code_for(st);
    }
    vs_volume *vol = NULL;
    int rc = load_input(ctx, &o, &vol);
    if (rc) {
        vs_context_release(ctx);
        return rc;
    }
    int d[3];
    double sp[3], lo, hi;
    vs_volume_dims(vol, d);
    vs_volume_spacing(vol, sp);
    vs_volume_range(vol, &lo, &hi);
    printf("input: %s\n", o.scene ? o.scene : o.input);
    printf("dims: %d %d %d\n", d[0], d[1], d[2]);
    printf("type: %s\n", vs_type_name(vs_volume_type(vol)));
    printf("spacing: %.9g %.9g %.9g\n", sp[0], sp[1], sp[2]);
    printf("range: %.9g %.9g\n", lo, hi);
    printf("voxels: %llu\n", (unsigned long long)d[0] * (unsigned long long)d[1] * (unsigned long long)d[2]);
    printf("default_iso: %.9g\n", vs_volume_default_iso(vol));
    printf("analytic: %s\n", vs_volume_has_analytic(vol) ? "yes" : "no");
    double m[12];
    if (vs_volume_affine(vol, m)) {
        char code[4];
        int oblique, sheared;
        orientation_code(m, code, &oblique, &sheared);
        printf("orientation: %s%s%s\n", code, oblique ? " (oblique: nearest axes)" : "",
               sheared ? " (sheared: rendered as the transform says)" : "");
    } else {
        printf("orientation: none (assumed RAS: x right, y anterior, z superior)\n");
    }
    printf("transform:");
    for (int r = 0; r < 3; r++)
        printf(" %.9g %.9g %.9g %.9g%s", m[4 * r] + 0.0, m[4 * r + 1] + 0.0, m[4 * r + 2] + 0.0, m[4 * r + 3] + 0.0,
               r < 2 ? ";" : "\n");
    fflush(stdout);
    geometry_notes(&o, vol);
    vs_volume_release(vol);
    vs_context_release(ctx);
    return 0;
}

static int cmd_compare(int argc, char **argv)
{
    if (argc == 1 && (!strcmp(argv[0], "--help") || !strcmp(argv[0], "-h"))) {
        printf("usage: vsplat compare A B\n"
               "prints rmse=… psnr=… ssim=… max=… over all four channels (psnr inf if identical)\n");
        return 0;
    }
    if (argc != 2) return usage_error("compare: expected two images: vsplat compare A B");
    for (int i = 0; i < 2; i++)
        if (argv[i][0] == '-' && argv[i][1] != '\0') {
            fprintf(stderr, "vsplat: %s: unknown option for 'compare'\n", argv[i]);
            return EXIT_USAGE;
        }
    vs_context *ctx = NULL;
    vs_status st = vs_context_create(&ctx);
    if (st != VS_OK) {
        fprintf(stderr, "vsplat: cannot create a context: %s\n", vs_status_string(st));
        return exit_code_for(st);
    }
    vs_image a = {0, 0, NULL}, b = {0, 0, NULL};
    int rc = 0;
    st = vs_image_read(ctx, argv[0], &a);
    if (st != VS_OK) {
        rc = report(ctx, st, argv[0]);
        goto done;
    }
    st = vs_image_read(ctx, argv[1], &b);
    if (st != VS_OK) {
        rc = report(ctx, st, argv[1]);
        goto done;
    }
    if (a.width != b.width || a.height != b.height) {
        fprintf(stderr, "vsplat: %s: size %dx%d differs from %s (%dx%d)\n", argv[1], b.width, b.height, argv[0],
                a.width, a.height);
        rc = EXIT_USAGE;
        goto done;
    }
    vs_image_diff d;
    st = vs_image_compare(ctx, &a, &b, &d);
    if (st != VS_OK) {
        rc = report(ctx, st, argv[1]);
        goto done;
    }
    printf("rmse=%.6g psnr=%.6g ssim=%.6g max=%.6g\n", d.rmse, d.psnr, d.ssim, d.max_abs);
done:
    vs_image_free(&a);
    vs_image_free(&b);
    vs_context_release(ctx);
    return rc;
}

int main(int argc, char **argv)
{
    if (argc < 2) return usage_error("no command: vsplat render|info|compare ... (see vsplat --help)");
    const char *cmd = argv[1];
    if (!strcmp(cmd, "--version") || !strcmp(cmd, "-V") || !strcmp(cmd, "version")) {
        printf("vsplat %s\n", vs_version());
        return 0;
    }
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
        cli_usage(stdout);
        return 0;
    }
    if (!strcmp(cmd, "render")) return cmd_render(argc - 2, argv + 2);
    if (!strcmp(cmd, "info")) return cmd_info(argc - 2, argv + 2);
    if (!strcmp(cmd, "compare")) return cmd_compare(argc - 2, argv + 2);
    fprintf(stderr, "vsplat: %s: unknown command (render, info, compare; see vsplat --help)\n", cmd);
    return EXIT_USAGE;
}
