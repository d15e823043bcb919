/* vsplat-bench frame INPUT [vsplat render options] [--frames K]
 *
 * Interactive-use figures: load, render once (builds the relevant-voxel
 * list), then K frames turning the azimuth by 360/K degrees from --view;
 * then one render with iso_lo moved (the list is rebuilt): iso_change_ms is
 * that render's whole wall clock (rebuild + frame, what a user waits for;
 * stderr splits it); peak_mb is getrusage's ru_maxrss.  Every `vsplat render`
 * option works (the CLI's parser, tools/cli_args.c, linked as the
 * vsplat_cli_args library); -o OUT, if given, receives the first frame;
 * --trace FILE.json receives the timeline of the timed frames.
 * stdout gets exactly one line:
 *   median_ms=... min_ms=... max_ms=... iso_change_ms=... peak_mb=... */
#include "bench.h"
#include "cli_args.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

int bench_frame(const bench_opts *bo, int argc, char **argv)
{
    (void)bo;
    int frames = 36;
    char **args = calloc((size_t)argc + 3, sizeof *args);
    if (!args) return 2;
    int n = 0, have_out = 0;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        const char *v = NULL;
        if (!strcmp(a, "--frames")) {
            if (i + 1 >= argc) {
                fprintf(stderr, "vsplat-bench: --frames: missing value\n");
                free(args);
                return 1;
            }
            v = argv[++i];
        } else if (!strncmp(a, "--frames=", 9)) {
            v = a + 9;
        }
        if (v) {
            char *end = NULL;
            errno = 0;
            long k = strtol(v, &end, 10);
            if (!*v || *end || errno || k < 1 || k > 100000) {
                fprintf(stderr, "vsplat-bench: --frames: expected an integer in 1..100000, got '%s'\n", v);
                free(args);
                return 1;
            }
            frames = (int)k;
            continue;
        }
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            printf("usage: vsplat-bench frame INPUT|--scene NAME [vsplat render options] [--frames K]\n"
                   "prints: median_ms=... min_ms=... max_ms=... iso_change_ms=... peak_mb=...\n\n");
            cli_render_usage(stdout);
            free(args);
            return 0;
        }
        if (!strcmp(a, "-o") || !strcmp(a, "--output") || !strncmp(a, "--output=", 9)) have_out = 1;
        args[n++] = argv[i];
    }
    static char dash_o[] = "-o", dummy[] = "unused.png";
    if (!have_out) {
        args[n++] = dash_o;
        args[n++] = dummy;
    }
    cli_opts o;
    char err[1024];
    if (cli_parse_render(n, args, &o, err, sizeof err)) {
        fprintf(stderr, "vsplat-bench: frame: %s\n", err);
        free(args);
        return 1;
    }
    free(args);

    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return 2;
    vs_volume *vol = NULL;
    vs_status st = o.scene ? vs_volume_scene(ctx, o.scene, &vol) : vs_volume_load(ctx, o.input, &o.load, &vol);
    if (st != VS_OK) {
        fprintf(stderr, "vsplat-bench: %s: %s\n", o.scene ? o.scene : o.input, vs_last_error(ctx));
        vs_context_release(ctx);
        return st == VS_ERR_OUT_OF_MEMORY || st == VS_ERR_INTERNAL ? 2 : 1;
    }

    cli_settle_view(&o, vol); /* the frames turn from the first one's view */
    vs_tf_point *tf = NULL;
    if ((st = cli_load_tf(ctx, &o, vol, &tf)) != VS_OK) {
        fprintf(stderr, "vsplat-bench: %s\n", vs_last_error(ctx));
        vs_volume_release(vol);
        vs_context_release(ctx);
        return 1;
    }
    vs_settings s = o.s;
    vs_image img = {0, 0, NULL};
    vs_stats first;
    st = vs_render(ctx, vol, &s, &img, &first);
    if (st == VS_OK && have_out) st = vs_image_write(ctx, o.output, &img, o.bits);
    vs_image_free(&img);
    if (st != VS_OK) {
        fprintf(stderr, "vsplat-bench: frame: %s\n", vs_last_error(ctx));
        vs_tf_free(tf);
        vs_volume_release(vol);
        vs_context_release(ctx);
        return 2;
    }
    fprintf(stderr, "frame: first render %.1f ms (relevant-voxel list %.1f ms, %llu relevant voxels), %d threads\n",
            first.ms_total, first.ms_relevant, (unsigned long long)first.voxels_relevant, first.threads);

    /* --trace FILE.json: the timed frames (and the iso change) as a timeline */
    vs_trace *trace = NULL;
    if (o.trace_path) {
        if (vs_trace_create(&trace) != VS_OK) return 2;
        s.trace = trace;
    }
    double *ms = malloc((size_t)frames * sizeof *ms);
    if (!ms) return 2;
    int rebuilt = 0;
    for (int i = 0; i < frames; i++) {
        vs_settings f = s;
        f.azimuth = s.azimuth + 360.0 * i / frames;
        vs_stats fs;
        bench_progress("frame", i, frames, "");
        st = vs_render(ctx, vol, &f, &img, &fs);
        vs_image_free(&img);
        if (st != VS_OK) {
            fprintf(stderr, "vsplat-bench: frame %d: %s\n", i, vs_last_error(ctx));
            free(ms);
            vs_tf_free(tf);
            vs_volume_release(vol);
            vs_context_release(ctx);
            return 2;
        }
        if (fs.ms_relevant > 0) rebuilt++;
        ms[i] = fs.ms_total;
    }
    bench_progress_end();
    if (rebuilt) fprintf(stderr, "frame: note: %d frames rebuilt the relevant-voxel list\n", rebuilt);

    /* iso change: move iso_lo by 2 % of the value range (keep the ramp and the upper end) */
    double lo, hi;
    vs_volume_range(vol, &lo, &hi);
    vs_settings c = s;
    double iso_change = NAN;
    if (s.tf_count == 0) {
        c.has_iso = 1;
        c.iso_lo = first.iso_lo + 0.02 * (hi - lo);
        c.iso_hi = first.iso_hi;
        c.ramp = first.ramp;
        if (c.iso_hi < c.iso_lo) c.iso_hi = INFINITY;
        vs_stats cs;
        st = vs_render(ctx, vol, &c, &img, &cs);
        vs_image_free(&img);
        if (st != VS_OK) {
            fprintf(stderr, "vsplat-bench: iso change: %s\n", vs_last_error(ctx));
        } else {
            iso_change = cs.ms_total;
            fprintf(stderr, "frame: iso %g -> %g: render %.1f ms, of which the relevant-voxel rebuild %.1f ms\n",
                    first.iso_lo, c.iso_lo, cs.ms_total, cs.ms_relevant);
        }
    }

    double med = bench_median(ms, frames); /* sorts */
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    double peak_mb = ru.ru_maxrss / 1024.0; /* kilobytes on Linux */
    printf("median_ms=%.2f min_ms=%.2f max_ms=%.2f iso_change_ms=%.2f peak_mb=%.1f\n", med, ms[0], ms[frames - 1],
           iso_change, peak_mb);
    if (trace) {
        if (vs_trace_write(ctx, trace, o.trace_path) != VS_OK) {
            fprintf(stderr, "vsplat-bench: %s\n", vs_last_error(ctx));
            st = VS_ERR_IO;
        } else {
            fprintf(stderr, "frame: wrote %s (%zu spans)\n", o.trace_path, vs_trace_spans(trace));
        }
        vs_trace_release(trace);
    }
    free(ms);
    vs_tf_free(tf);
    vs_volume_release(vol);
    vs_context_release(ctx);
    return st == VS_OK ? 0 : 2;
}
