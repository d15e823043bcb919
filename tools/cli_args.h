/* Command-line parsing for the vsplat tool: render / info options into
 * vs_settings and vs_load_options.  Strict: every malformed, unknown,
 * incomplete or out-of-range argument is an error with a one-line message. */
#ifndef VSPLAT_CLI_ARGS_H
#define VSPLAT_CLI_ARGS_H

#include "vsplat.h"

#include <stddef.h>
#include <stdio.h>

/* Everything `vsplat render` (and, for the input part, `vsplat info`) takes. */
typedef struct cli_opts {
    vs_settings s;
    vs_load_options load;
    const char *input;      /* volume file, or NULL with scene            */
    const char *scene;      /* --scene NAME[:N]                           */
    const char *output;     /* -o OUT                                     */
    const char *stats_path; /* --stats FILE.json                          */
    int print_stats;        /* --print-stats                              */
    const char *trace_path; /* --trace FILE.json: a timeline of the frames */
    int quiet;              /* -q                                         */
    int bits;               /* --bits 8|16 (PNG depth)                    */
    int help;               /* --help seen: print usage, exit 0           */
    const char *tf_path;    /* --tf FILE (loaded once the volume is known) */
    int turntable;          /* --turntable N: N frames, 0 = one image      */
    double fps;             /* --fps F for animated GIF output            */
} cli_opts;

/* Parse `vsplat render` arguments (argv[0] is the first argument after
 * "render").  Environment defaults: VSPLAT_THREADS, VSPLAT_ISA.
 * Returns 0 on success, 1 on a usage error (message, without the "vsplat: "
 * prefix and without a newline, in err). */
int cli_parse_render(int argc, char **argv, cli_opts *o, char *err, size_t errcap);

/* Parse `vsplat info` arguments: INPUT or --scene, plus the raw-input
 * options (--dims, --type, --spacing, --endian).  Same return convention. */
int cli_parse_info(int argc, char **argv, cli_opts *o, char *err, size_t errcap);

/* Turntable frame name: OUT "dir/out.png", frame 3 -> "dir/out_0003.png".
 * Returns 0, or 1 if it does not fit in cap. */
int cli_frame_name(const char *out, int frame, char *buf, size_t cap);

/* The default view (VS_VIEW_AUTO) made explicit for this volume: the
 * front when it has an orientation, else the angles.  Tools that turn the
 * azimuth from it (turntables, vsplat-bench frame) settle it once first, so
 * that frame 1 turns from frame 0's view, not from the back. */
void cli_settle_view(cli_opts *o, const vs_volume *vol);

/* --tf, once the volume is known (a .1dt spreads over its range): the
 * transfer function into o->s (tf, tf_count), *tf set to what the caller
 * frees with vs_tf_free.  VS_OK and *tf NULL without --tf. */
vs_status cli_load_tf(vs_context *ctx, cli_opts *o, const vs_volume *vol, vs_tf_point **tf);

/* Output format from the extension (.png, .exr, .tif, .tiff, .gif; any
 * case): returns a short name ("png", "exr", "tiff", "gif") or NULL. */
const char *cli_output_format(const char *path);

void cli_usage(FILE *f);        /* whole tool                      */
void cli_render_usage(FILE *f); /* every render option             */
void cli_info_usage(FILE *f);

#endif
