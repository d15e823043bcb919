/* vsplat-mpi — sort-last rendering over MPI (docs/DISTRIBUTED.md):
 *     mpirun -np N vsplat-mpi render INPUT [vsplat render options] -o OUT
 * The volume is split into N bricks (k-d, balanced by relevant voxels),
 * each with the ghost layers its kernel and gradients need.  Raw and NIfTI
 * files are read in parts: every rank reads a z-slab (for the value range,
 * the default iso's histogram and the split's weights), then its brick, so
 * no rank holds the whole volume; other formats and scenes are read by rank
 * 0, which sends the bricks.  Every rank renders its brick with the ordinary
 * pipelines, cropped to the voxels it owns; the partial images are
 * composited in visibility order (rank 0 receiving them in turn; with
 * --composite reduce an MPI reduction with a non-commutative "over"; with
 * --composite swap binary swap) and rank 0 writes.  N = 1 is `vsplat render` itself.
 *
 * Errors: every step that can fail ends in a status exchange (the lowest
 * failing rank's message goes to all), so all ranks exit with the same code
 * and rank 0 prints one line.  Exit codes as vsplat: 0, 1 usage or input,
 * 2 internal. */
#include "cli_args.h"
#include "mpi_composite.h"
#include "mpi_decompose.h"
#include "vsplat.h"

#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { EXIT_USAGE = 1, EXIT_INTERNAL = 2, MSG_CAP = 1024 };

/* What a rank reports after a step. */
typedef struct step {
    int rc; /* 0, EXIT_USAGE or EXIT_INTERNAL */
    char msg[MSG_CAP];
} step;

static int fail(step *s, int rc, const char *fmt, const char *a, const char *b)
{
    s->rc = rc;
    snprintf(s->msg, sizeof s->msg, fmt, a, b ? b : "");
    return rc;
}

static int lib_fail(step *s, vs_context *ctx, vs_status st, const char *what)
{
    const char *m = ctx ? vs_last_error(ctx) : "";
    if (!m || !*m) m = vs_status_string(st);
    int rc = st == VS_ERR_INTERNAL || st == VS_ERR_OUT_OF_MEMORY ? EXIT_INTERNAL : EXIT_USAGE;
    if (what && !strstr(m, what)) return fail(s, rc, "%s: %s", what, m);
    return fail(s, rc, "%s%s", m, NULL);
}

/* The status exchange: returns the agreed exit code (0 if every rank
 * succeeded); rank 0 prints the lowest failing rank's message. */
static int agree(step *s, int rank, int n)
{
    int who = s->rc ? rank : n, first;
    MPI_Allreduce(&who, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (first == n) return 0;
    step g = *s;
    MPI_Bcast(&g, (int)sizeof g, MPI_BYTE, first, MPI_COMM_WORLD);
    if (rank == 0) {
        if (first == 0)
            fprintf(stderr, "vsplat-mpi: %s\n", g.msg);
        else
            fprintf(stderr, "vsplat-mpi: rank %d of %d: %s\n", first, n, g.msg);
    }
    return g.rc;
}

/* Test hook: VSPLAT_MPI_FAIL_RANK=R makes rank R fail to take its brick,
 * as a rank that runs out of memory or cannot read its part would. */
static int injected_failure(int rank)
{
    const char *e = getenv("VSPLAT_MPI_FAIL_RANK");
    return e && *e && atoi(e) == rank;
}

static MPI_Datatype mpi_type_of(vs_type t)
{
    switch (t) {
    case VS_U8: return MPI_UNSIGNED_CHAR;
    case VS_I16: return MPI_SHORT;
    case VS_U16: return MPI_UNSIGNED_SHORT;
    default: return MPI_FLOAT;
    }
}

/* The classification the whole volume gets, made explicit so that bricks
 * (with other histograms and ranges) classify the same: iso-range and ramp
 * as vs_render resolves them (its stats say), or the transfer function's
 * span of non-zero opacity.  Rank 0, on the whole volume. */
static int resolve_classification(vs_context *ctx, const vs_volume *vol, vs_settings *s, double *alo, double *ahi,
                                  step *sp)
{
    if (s->tf_count > 0) {
        *alo = INFINITY;
        *ahi = -INFINITY;
        for (int i = 0; i < s->tf_count; i++)
            if (s->tf[i].a > 0.0f) {
                double lo = i > 0 ? s->tf[i - 1].value : -INFINITY;
                double hi = i + 1 < s->tf_count ? s->tf[i + 1].value : INFINITY;
                if (lo < *alo) *alo = lo;
                if (hi > *ahi) *ahi = hi;
            }
        return 0;
    }
    if (!s->has_iso || s->ramp < 0) {
        vs_settings t = *s;
        t.width = t.height = 1;
        t.pipeline = VS_PIPELINE_PRE;
        vs_image img = {0, 0, NULL};
        vs_stats st;
        vs_status rc = vs_render(ctx, vol, &t, &img, &st);
        vs_image_free(&img);
        if (rc != VS_OK) return lib_fail(sp, ctx, rc, NULL);
        s->has_iso = 1;
        s->iso_lo = st.iso_lo;
        s->iso_hi = st.iso_hi;
        s->ramp = st.ramp;
    }
    *alo = s->iso_lo - s->ramp;
    *ahi = s->iso_hi + s->ramp;
    return 0;
}

/* What rank 0 tells every rank before the bricks move. */
typedef struct plan {
    vs_type type;
    int dims[3];
    double spacing[3];
    double vmin, vmax;
    int has_iso;
    double iso_lo, iso_hi, ramp;
    int tf_count;
    double affine[12]; /* index -> world of the whole volume          */
    int oriented;      /* the file gave it (vs_volume_affine)          */
    vs_view view;      /* the view, settled as vsplat settles it       */
    double alo, ahi;   /* values that can be non-transparent (the split's weights) */
} plan;

/* Per-rank figures, gathered on rank 0 for --print-stats and --stats. */
typedef struct rank_stats {
    int lo[3], hi[3];
    double ms_render, ms_composite, ms_scatter;
    double ms_load, ms_prepare; /* rank 0: reading, classification + split */
    double voxels_held, voxels_relevant, voxels_splatted;
    double voxels_read; /* from the file: slab and brick, or the whole volume */
    double voxels_peak; /* the most held at once: the larger of the two   */
    double voxels_total; /* the whole volume's */
    int parts;          /* every rank read its parts (else rank 0 read it all) */
    double bytes_sent, bytes_scatter;
} rank_stats;

static void print_table(FILE *f, const rank_stats *rs, int n, double ms_total)
{
    fprintf(f, "%-4s %-26s %10s %10s %9s %9s %12s\n", "rank", "owned voxels [lo,hi)", "relevant", "splatted",
            "render ms", "comp. ms", "bytes sent");
    rank_stats t;
    memset(&t, 0, sizeof t);
    for (int r = 0; r < n; r++) {
        const rank_stats *p = &rs[r];
        char box[64];
        snprintf(box, sizeof box, "%d-%d,%d-%d,%d-%d", p->lo[0], p->hi[0], p->lo[1], p->hi[1], p->lo[2], p->hi[2]);
        fprintf(f, "%-4d %-26s %10.0f %10.0f %9.2f %9.2f %12.0f\n", r, box, p->voxels_relevant, p->voxels_splatted,
                p->ms_render, p->ms_composite, p->bytes_sent + p->bytes_scatter);
        t.voxels_relevant += p->voxels_relevant;
        t.voxels_splatted += p->voxels_splatted;
        t.bytes_sent += p->bytes_sent + p->bytes_scatter;
        if (p->ms_render > t.ms_render) t.ms_render = p->ms_render;
        if (p->ms_composite > t.ms_composite) t.ms_composite = p->ms_composite;
    }
    fprintf(f, "%-4s %-26s %10.0f %10.0f %9.2f %9.2f %12.0f\n", "all", "(render, comp.: slowest)", t.voxels_relevant,
            t.voxels_splatted, t.ms_render, t.ms_composite, t.bytes_sent);
    if (rs[0].parts) {
        double most = 0, slowest = 0;
        for (int r = 0; r < n; r++) {
            if (rs[r].voxels_peak > most) most = rs[r].voxels_peak;
            if (rs[r].ms_load > slowest) slowest = rs[r].ms_load;
        }
        fprintf(f, "each rank read its slab, then its brick: at most %.0f of the %.0f voxels held at once, %.2f ms (slowest)\n", most,
                rs[0].voxels_total, slowest);
    } else
        fprintf(f, "rank 0 read the whole volume: %.0f voxels, %.2f ms\n", rs[0].voxels_total, rs[0].ms_load);
    fprintf(f, "rank 0: classification and split %.2f ms, scatter %.2f ms; wall clock %.2f ms\n", rs[0].ms_prepare,
            rs[0].ms_scatter, ms_total);
}

static int write_stats_json(const char *path, const rank_stats *rs, int n, double ms_total, step *sp)
{
    FILE *f = !strcmp(path, "-") ? stdout : fopen(path, "w");
    if (!f) return fail(sp, EXIT_USAGE, "%s: cannot write%s", path, NULL);
    fprintf(f,
            "{\"ranks\": %d, \"reads\": \"%s\", \"voxels\": %.0f, \"ms_total\": %.3f, \"ms_load\": %.3f, "
            "\"ms_prepare\": %.3f, \"ms_scatter\": %.3f, \"per_rank\": [\n",
            n, rs[0].parts ? "per rank" : "rank 0", rs[0].voxels_total, ms_total, rs[0].ms_load, rs[0].ms_prepare,
            rs[0].ms_scatter);
    for (int r = 0; r < n; r++) {
        const rank_stats *p = &rs[r];
        fprintf(f,
                "  {\"rank\": %d, \"lo\": [%d, %d, %d], \"hi\": [%d, %d, %d], \"voxels_held\": %.0f, "
                "\"voxels_relevant\": %.0f, \"voxels_splatted\": %.0f, \"ms_render\": %.3f, "
                "\"ms_composite\": %.3f, \"bytes_composite\": %.0f, \"bytes_scatter\": %.0f, "
                "\"voxels_read\": %.0f, \"voxels_peak\": %.0f, \"ms_load\": %.3f}%s\n",
                r, p->lo[0], p->lo[1], p->lo[2], p->hi[0], p->hi[1], p->hi[2], p->voxels_held, p->voxels_relevant,
                p->voxels_splatted, p->ms_render, p->ms_composite, p->bytes_sent, p->bytes_scatter, p->voxels_read,
                p->voxels_peak, p->ms_load,
                r + 1 < n ? "," : "");
    }
    fprintf(f, "]}\n");
    int ok = f == stdout ? fflush(f) == 0 : fclose(f) == 0;
    if (!ok) return fail(sp, EXIT_USAGE, "%s: cannot write%s", path, NULL);
    return 0;
}

/* N = 1: exactly `vsplat render` (the same library call on the same volume). */
static int render_single(vs_context *ctx, const vs_volume *vol, const cli_opts *o, double t_start, double ms_load,
                         step *sp)
{
    vs_image img = {0, 0, NULL};
    vs_stats st;
    vs_status rc = vs_render(ctx, vol, &o->s, &img, &st);
    if (rc != VS_OK) return lib_fail(sp, ctx, rc, o->scene ? o->scene : o->input);
    rc = vs_image_write(ctx, o->output, &img, o->bits);
    vs_image_free(&img);
    if (rc != VS_OK) return lib_fail(sp, ctx, rc, o->output);
    rank_stats rs;
    memset(&rs, 0, sizeof rs);
    vs_volume_dims(vol, rs.hi);
    rs.ms_render = st.ms_total;
    rs.ms_load = ms_load;
    rs.voxels_relevant = (double)st.voxels_relevant;
    rs.voxels_splatted = (double)st.voxels_splatted;
    rs.voxels_held = rs.voxels_read = rs.voxels_peak = rs.voxels_total = (double)st.voxels_total;
    const double ms_total = 1e3 * (MPI_Wtime() - t_start);
    if (o->print_stats) print_table(stdout, &rs, 1, ms_total);
    if (o->stats_path && write_stats_json(o->stats_path, &rs, 1, ms_total, sp)) return sp->rc;
    if (!o->quiet)
        fprintf(stderr, "vsplat-mpi: wrote %s (%dx%d, %s, 1 rank, %.1f ms)\n", o->output, o->s.width, o->s.height,
                vs_pipeline_name(o->s.pipeline), st.ms_total);
    return 0;
}

/* Voxels a brick needs beyond the ones it owns, so that every sheet point
 * it composites, and the neighbours its gradient reads (one pixel in the
 * sheet, two where post-cd takes its four-point stencil; one sheet
 * across, two where it takes the stencil across sheets), see all the
 * voxels whose kernel reaches them,
 * and those voxels the neighbours their own gradient reads (two voxels:
 * pre-shaded pipelines, src/voxel_gradient.h).
 * A pixel spans more than a voxel when zoomed out; perspective doubles the
 * margin for the far side. */
static int ghost_layers(const vs_settings *s, const int d[3], const double sp[3])
{
    double extent = 0.0, unit = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (d[a] * sp[a] > extent) extent = d[a] * sp[a];
        if (sp[a] < unit) unit = sp[a];
    }
    double px_mm = extent / (s->zoom * s->width);
    const double px0 = px_mm; /* the rules' pixel, before the in-sheet stencil widens the reach */
    /* post-cd's four-point stencil (src/footprint.c vs_cd_wide): below 1.5
     * pixels a voxel, anywhere on a perspective view's far side */
    const int wide = s->pipeline == VS_PIPELINE_POST_CD &&
                     (s->cd_stencil == 4 || (s->cd_stencil == 0 && (unit < 1.5 * px_mm || s->perspective_fov > 0)));
    if (wide) px_mm *= 2.0;
    /* and across sheets (vs_cd_wide_z): from 0.7 pixel a voxel times the
     * slab, anywhere in perspective; erring wide where pre-integration
     * turns it off */
    const int wide_z = s->pipeline == VS_PIPELINE_POST_CD &&
                       (s->cd_stencil == 4 || (s->cd_stencil == 0 && (s->slab * unit >= 0.7 * px0 ||
                                                                      s->perspective_fov > 0)));
    const double across = (wide_z ? 2.0 : 1.0) * s->slab * unit;
    const double step_mm = px_mm > across ? px_mm : across;
    double reach = ceil(step_mm / unit) * (s->perspective_fov > 0 ? 2 : 1);
    return (int)ceil(s->kernel_radius) + 2 + (int)(reach < 64 ? reach : 64);
}

static int run(int rank, int n, int argc, char **argv)
{
    step sp;
    memset(&sp, 0, sizeof sp);
    cli_opts o;
    char err[MSG_CAP];
    /* every rank parses the same arguments, so all fail alike */
    if (argc < 2 || strcmp(argv[1], "render") != 0) {
        if (rank == 0)
            fprintf(stderr, "vsplat-mpi: usage: mpirun -np N vsplat-mpi render INPUT|--scene NAME "
                            "[vsplat render options] [--composite gather|reduce|swap] [--read parts|root] -o OUT\n");
        return EXIT_USAGE;
    }
    /* vsplat-mpi's own options, taken out before the render options are
     * parsed: --composite gather|reduce|swap (default gather, the cheaper
     * at the rank counts measured: docs/DISTRIBUTED.md); --read parts|root
     * (default parts: every rank reads its part where the format allows;
     * root: rank 0 reads the whole volume and sends the bricks) */
    int (*compositor)(MPI_Comm, const vs_image *, const int *, const float *, vs_image *, uint64_t *) =
        mpi_composite_gather;
    int read_parts = 1, na = 0;
    char **args = malloc(sizeof *args * (size_t)(argc > 2 ? argc - 2 : 1));
    if (!args) return EXIT_INTERNAL;
    for (int i = 2; i < argc; i++) {
        const int composite = !strcmp(argv[i], "--composite");
        if (!composite && strcmp(argv[i], "--read") != 0) {
            args[na++] = argv[i];
            continue;
        }
        const char *opt = argv[i], *m = i + 1 < argc ? argv[++i] : "";
        const char *a = composite ? "gather" : "parts", *b = composite ? "reduce" : "root";
        const int swap = composite && !strcmp(m, "swap");
        if (strcmp(m, a) != 0 && strcmp(m, b) != 0 && !swap) {
            if (rank == 0)
                fprintf(stderr, "vsplat-mpi: %s: expected %s, got '%s'\n", opt,
                        composite ? "gather, reduce or swap" : "parts or root", m);
            free(args);
            return EXIT_USAGE;
        }
        if (composite) compositor = swap ? mpi_composite_swap : !strcmp(m, a) ? mpi_composite_gather : mpi_composite_reduce;
        else read_parts = !strcmp(m, a);
    }
    const int bad_args = cli_parse_render(na, args, &o, err, sizeof err);
    free(args);
    if (bad_args) {
        if (rank == 0) fprintf(stderr, "vsplat-mpi: %s\n", err);
        return EXIT_USAGE;
    }
    if (o.help) {
        if (rank == 0) cli_render_usage(stdout);
        return 0;
    }
    /* bricks render at full resolution and anisotropic grids as stored
     * (docs/DISTRIBUTED.md), one rank too */
    o.s.lod_pixels = 0.0;
    const char *unsupported = o.turntable > 0                        ? "--turntable"
                              : o.s.resample > 0                     ? "--resample on"
                              : o.trace_path                         ? "--trace"
                              : o.s.pipeline == VS_PIPELINE_RAYCAST  ? "--pipeline raycast"
                              : !strcmp(cli_output_format(o.output), "gif") ? "GIF output"
                                                                     : NULL;
    if (unsupported) {
        if (rank == 0) fprintf(stderr, "vsplat-mpi: %s is not supported by vsplat-mpi (use vsplat)\n", unsupported);
        return EXIT_USAGE;
    }
    o.s.resample = 0;
    const double t_start = MPI_Wtime();
    vs_context *ctx = NULL;
    vs_status st = vs_context_create(&ctx);
    if (st != VS_OK) lib_fail(&sp, NULL, st, "cannot create a context");
    int rc = agree(&sp, rank, n);
    if (rc) return rc;

    /* Raw and NIfTI files are read in parts: every rank reads a z-slab for
     * the value range, the histogram and the split's weights, then its
     * brick, and no rank holds the whole volume.  Other formats (and
     * scenes): rank 0 reads the whole volume and sends the bricks. */
    int dims[3] = {0, 0, 0},
        parts = n > 1 && read_parts && !o.scene && vs_volume_file_dims(ctx, o.input, &o.load, dims) == VS_OK;
    MPI_Allreduce(MPI_IN_PLACE, &parts, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    vs_volume *full = NULL, *brick = NULL; /* full: the whole volume (rank 0) or this rank's slab */
    vs_tf_point *tf = NULL;
    mpi_weights W;
    memset(&W, 0, sizeof W);
    plan P;
    memset(&P, 0, sizeof P);
    double ms_load = 0, ms_prepare = 0;
    double voxels_first = 0; /* read first: this rank's slab, or the whole volume */
    int z0 = 0;
    if (parts) {
        if (mpi_weights_init(&W, dims)) fail(&sp, EXIT_INTERNAL, "out of memory%s", "", NULL);
        const int gz = W.g[2], c = W.cell;
        const int a = (int)((long)rank * gz / n), b = (int)((long)(rank + 1) * gz / n);
        z0 = a * c < dims[2] ? a * c : dims[2];
        const int z1 = b * c < dims[2] ? b * c : dims[2];
        const double t_load = MPI_Wtime();
        if (!sp.rc && z1 > z0) {
            const int lo[3] = {0, 0, z0}, hi[3] = {dims[0], dims[1], z1};
            st = vs_volume_load_box(ctx, o.input, &o.load, lo, hi, &full);
            if (st != VS_OK) lib_fail(&sp, ctx, st, o.input);
            voxels_first = (double)dims[0] * dims[1] * (z1 - z0);
        }
        ms_load = 1e3 * (MPI_Wtime() - t_load);
    } else if (rank == 0) {
        const double t_load = MPI_Wtime();
        st = o.scene ? vs_volume_scene(ctx, o.scene, &full) : vs_volume_load(ctx, o.input, &o.load, &full);
        ms_load = 1e3 * (MPI_Wtime() - t_load);
        if (st != VS_OK) lib_fail(&sp, ctx, st, o.scene ? "--scene" : o.input);
        if (!sp.rc) {
            vs_volume_dims(full, dims);
            voxels_first = (double)dims[0] * dims[1] * dims[2];
        }
    }
    rc = agree(&sp, rank, n);
    if (rc) goto done;
    const double t_prep = MPI_Wtime();
    if (parts) {
        /* the whole volume's range and, for the default iso, its histogram */
        double r[2] = {INFINITY, INFINITY};
        if (full) {
            vs_volume_range(full, &r[0], &r[1]);
            r[1] = -r[1];
        }
        MPI_Allreduce(MPI_IN_PLACE, r, 2, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
        if (full) vs_volume_set_range(full, r[0], -r[1]);
        if (!o.tf_path && !o.s.has_iso) {
            double hist[VS_HISTOGRAM_BINS] = {0};
            if (full) vs_volume_histogram(full, hist);
            MPI_Allreduce(MPI_IN_PLACE, hist, VS_HISTOGRAM_BINS, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
            o.s.has_iso = 1; /* what vs_render takes without an iso */
            o.s.iso_lo = vs_histogram_iso(hist, r[0], -r[1]);
            o.s.iso_hi = INFINITY;
        }
    }
    if (rank == 0 && o.tf_path) { /* the whole volume, or rank 0's slab with the whole range */
        st = cli_load_tf(ctx, &o, full, &tf);
        if (st != VS_OK) lib_fail(&sp, ctx, st, o.tf_path);
    }
    if (rank == 0 && n > 1) {
        if (!sp.rc) resolve_classification(ctx, full, &o.s, &P.alo, &P.ahi, &sp);
        if (!sp.rc) {
            P.type = vs_volume_type(full);
            memcpy(P.dims, dims, sizeof P.dims);
            vs_volume_spacing(full, P.spacing);
            vs_volume_range(full, &P.vmin, &P.vmax);
            P.has_iso = o.s.has_iso;
            P.iso_lo = o.s.iso_lo;
            P.iso_hi = o.s.iso_hi;
            P.ramp = o.s.ramp;
            P.tf_count = o.s.tf_count;
            P.oriented = vs_volume_affine(full, P.affine); /* rank 0's slab starts at z = 0 */
            cli_settle_view(&o, full);
            P.view = o.s.view;
        }
    } else if (rank == 0 && !sp.rc) {
        render_single(ctx, full, &o, t_start, ms_load, &sp);
    }
    rc = agree(&sp, rank, n);
    if (rc || n == 1) goto done;

    /* the plan, the transfer function */
    MPI_Bcast(&P, (int)sizeof P, MPI_BYTE, 0, MPI_COMM_WORLD);
    o.s.has_iso = P.has_iso;
    o.s.iso_lo = P.iso_lo;
    o.s.iso_hi = P.iso_hi;
    o.s.ramp = P.ramp;
    o.s.view = P.view;
    if (P.tf_count > 0) {
        if (rank != 0 && !(tf = malloc(sizeof *tf * (size_t)P.tf_count))) MPI_Abort(MPI_COMM_WORLD, EXIT_INTERNAL);
        MPI_Bcast(tf, (int)(sizeof *tf * (size_t)P.tf_count), MPI_BYTE, 0, MPI_COMM_WORLD);
        o.s.tf = tf;
        o.s.tf_count = P.tf_count;
    }

    /* the split's weights: every rank's slab, summed on rank 0; or rank 0's
     * whole volume */
    if (parts) {
        if (full) mpi_weights_add(&W, full, z0, P.alo, P.ahi);
        MPI_Reduce(rank == 0 ? MPI_IN_PLACE : W.count, W.count, W.g[0] * W.g[1] * W.g[2], MPI_UINT32_T, MPI_SUM, 0,
                   MPI_COMM_WORLD);
        vs_volume_release(full); /* the slab: each rank reads its brick next */
        full = NULL;
    } else if (rank == 0) {
        if (mpi_weights_init(&W, dims)) fail(&sp, EXIT_INTERNAL, "out of memory%s", "", NULL);
        else mpi_weights_add(&W, full, 0, P.alo, P.ahi);
    }
    mpi_decomp *D = calloc(1, sizeof *D);
    if (!D) fail(&sp, EXIT_INTERNAL, "out of memory%s", "", NULL);
    if (!sp.rc && rank == 0 && mpi_decompose(&W, P.spacing, n, ghost_layers(&o.s, P.dims, P.spacing), D))
        fail(&sp, EXIT_USAGE, "%s: the volume is too small to split into this many bricks%s",
             o.scene ? o.scene : o.input, NULL);
    mpi_weights_free(&W);
    ms_prepare = 1e3 * (MPI_Wtime() - t_prep);
    rc = agree(&sp, rank, n);
    if (rc) goto done_d;
    MPI_Bcast(D, (int)sizeof *D, MPI_BYTE, 0, MPI_COMM_WORLD);

    /* every rank reads its brick, or makes room for it and rank 0 sends them */
    const mpi_brick *B = &D->brick[rank];
    const int gd[3] = {B->ghi[0] - B->glo[0], B->ghi[1] - B->glo[1], B->ghi[2] - B->glo[2]};
    const double t_brick = MPI_Wtime();
    if (injected_failure(rank))
        fail(&sp, EXIT_INTERNAL, "cannot take its brick (failure injected by VSPLAT_MPI_FAIL_RANK)%s", "", NULL);
    else if (parts) {
        if ((st = vs_volume_load_box(ctx, o.input, &o.load, B->glo, B->ghi, &brick)) != VS_OK)
            lib_fail(&sp, ctx, st, o.input);
        else
            vs_volume_set_range(brick, P.vmin, P.vmax);
    } else if ((st = vs_volume_create(ctx, P.type, gd, P.spacing, &brick)) != VS_OK)
        lib_fail(&sp, ctx, st, "its brick");
    else {
        vs_volume_set_range(brick, P.vmin, P.vmax);
        /* the brick lies where it lies in the whole volume: the same
         * directions, the translation moved to its first voxel */
        double m[12];
        memcpy(m, P.affine, sizeof m);
        for (int r = 0; r < 3; r++)
            for (int a = 0; a < 3; a++) m[4 * r + 3] += P.affine[4 * r + a] * B->glo[a];
        if (P.oriented && (st = vs_volume_set_transform(ctx, brick, m)) != VS_OK) lib_fail(&sp, ctx, st, "its brick");
    }
    if (parts) ms_load += 1e3 * (MPI_Wtime() - t_brick);
    rc = agree(&sp, rank, n);
    if (rc) goto done_d;
    const double t_scatter = MPI_Wtime();
    double bytes_scatter = 0;
    const MPI_Datatype et = mpi_type_of(P.type);
    int esize;
    MPI_Type_size(et, &esize);
    if (parts) {
        /* nothing to send */
    } else if (rank == 0) {
        /* a subarray type per brick: no copy of the volume is made */
        const int sizes[3] = {P.dims[2], P.dims[1], P.dims[0]};
        for (int r = 0; r < n; r++) {
            const mpi_brick *b = &D->brick[r];
            const int sub[3] = {b->ghi[2] - b->glo[2], b->ghi[1] - b->glo[1], b->ghi[0] - b->glo[0]};
            const int start[3] = {b->glo[2], b->glo[1], b->glo[0]};
            MPI_Datatype box;
            MPI_Type_create_subarray(3, sizes, sub, start, MPI_ORDER_C, et, &box);
            MPI_Type_commit(&box);
            if (r == 0) {
                int pos = 0;
                MPI_Pack(vs_volume_data(full), 1, box, vs_volume_data(brick),
                         (int)((size_t)gd[0] * gd[1] * gd[2] * (size_t)esize), &pos, MPI_COMM_WORLD);
            } else {
                MPI_Send(vs_volume_data(full), 1, box, r, 0, MPI_COMM_WORLD);
                bytes_scatter += (double)sub[0] * sub[1] * sub[2] * esize;
            }
            MPI_Type_free(&box);
        }
        vs_volume_release(full); /* rank 0 keeps only its brick from here on */
        full = NULL;
    } else {
        MPI_Recv(vs_volume_data(brick), (int)((size_t)gd[0] * gd[1] * gd[2]), et, 0, 0, MPI_COMM_WORLD,
                 MPI_STATUS_IGNORE);
    }
    const double ms_scatter = 1e3 * (MPI_Wtime() - t_scatter);

    /* render the brick: same pixels per mm as the whole volume, centred on
     * the whole volume's centre, compositing only the owned voxels' points */
    vs_settings s = o.s;
    double ext_full = 0, ext_brick = 0;
    for (int a = 0; a < 3; a++) {
        if (P.dims[a] * P.spacing[a] > ext_full) ext_full = P.dims[a] * P.spacing[a];
        if (gd[a] * P.spacing[a] > ext_brick) ext_brick = gd[a] * P.spacing[a];
        double c = o.s.has_center ? o.s.center[a] : 0.5 * (P.dims[a] - 1);
        s.center[a] = c - B->glo[a];
        s.crop_lo[a] = B->lo[a] - B->glo[a];
        s.crop_hi[a] = B->hi[a] - B->glo[a];
    }
    s.zoom = o.s.zoom * ext_brick / ext_full;
    s.has_center = 1;
    s.has_crop = 1; /* which also means full resolution: no levels of detail */
    for (int c = 0; c < 4; c++) s.background[c] = 0.0f;
    vs_image part = {0, 0, NULL};
    vs_stats stats;
    memset(&stats, 0, sizeof stats);
    st = vs_render(ctx, brick, &s, &part, &stats);
    if (st != VS_OK) lib_fail(&sp, ctx, st, o.scene ? o.scene : o.input);
    rc = agree(&sp, rank, n);
    if (rc) goto done_img;

    /* composite in visibility order */
    int *order = malloc(sizeof *order * (size_t)n);
    if (!order) MPI_Abort(MPI_COMM_WORLD, EXIT_INTERNAL);
    double eye[3], dir[3];
    /* the brick's camera in its own index space: the same direction as the
     * whole volume's, the eye moved by the brick's origin */
    if (vs_view_in_index(ctx, brick, &s, dir, eye) != VS_OK) MPI_Abort(MPI_COMM_WORLD, EXIT_INTERNAL);
    for (int a = 0; a < 3; a++) eye[a] += B->glo[a];
    mpi_visibility_order(D, o.s.perspective_fov > 0 ? eye : NULL, dir, order);
    const double t_comp = MPI_Wtime();
    vs_image img = {0, 0, NULL};
    uint64_t bytes_sent = 0;
    if (compositor(MPI_COMM_WORLD, &part, order, o.s.background, &img, &bytes_sent))
        fail(&sp, EXIT_INTERNAL, "compositing: out of memory%s", "", NULL);
    const double ms_comp = 1e3 * (MPI_Wtime() - t_comp);
    free(order);
    if (!sp.rc && rank == 0 && (st = vs_image_write(ctx, o.output, &img, o.bits)) != VS_OK)
        lib_fail(&sp, ctx, st, o.output);
    vs_image_free(&img);
    rc = agree(&sp, rank, n);
    if (rc) goto done_img;

    /* stats */
    rank_stats mine, *all = rank == 0 ? calloc((size_t)n, sizeof *all) : NULL;
    memset(&mine, 0, sizeof mine);
    memcpy(mine.lo, B->lo, sizeof mine.lo);
    memcpy(mine.hi, B->hi, sizeof mine.hi);
    mine.ms_render = stats.ms_total;
    mine.ms_composite = ms_comp;
    mine.ms_scatter = ms_scatter;
    mine.ms_load = ms_load;
    mine.ms_prepare = ms_prepare;
    mine.voxels_held = (double)gd[0] * gd[1] * gd[2];
    mine.voxels_read = voxels_first + (parts ? mine.voxels_held : 0.0); /* the brick came from the file too */
    mine.voxels_peak = voxels_first > mine.voxels_held ? voxels_first : mine.voxels_held;
    mine.voxels_total = (double)P.dims[0] * P.dims[1] * P.dims[2];
    mine.parts = parts;
    mine.voxels_relevant = (double)stats.voxels_relevant;
    mine.voxels_splatted = (double)stats.voxels_splatted;
    mine.bytes_sent = (double)bytes_sent;
    mine.bytes_scatter = bytes_scatter;
    MPI_Gather(&mine, (int)sizeof mine, MPI_BYTE, all, (int)sizeof mine, MPI_BYTE, 0, MPI_COMM_WORLD);
    if (rank == 0 && all) {
        const double ms_total = 1e3 * (MPI_Wtime() - t_start);
        if (o.print_stats) print_table(stdout, all, n, ms_total);
        if (o.stats_path) write_stats_json(o.stats_path, all, n, ms_total, &sp);
        if (!o.quiet && !sp.rc)
            fprintf(stderr, "vsplat-mpi: wrote %s (%dx%d, %s, %d ranks, %.1f ms)\n", o.output, o.s.width,
                    o.s.height, vs_pipeline_name(o.s.pipeline), n, ms_total);
    }
    free(all);
    rc = agree(&sp, rank, n);
done_img:
    vs_image_free(&part);
done_d:
    free(D);
done:
    vs_volume_release(brick);
    vs_volume_release(full);
    if (rank == 0) vs_tf_free(tf);
    else free(tf);
    vs_context_release(ctx);
    return rc;
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    int rank, n;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &n);
    int rc = n > MPI_MAX_RANKS ? EXIT_USAGE : run(rank, n, argc, argv);
    if (n > MPI_MAX_RANKS && rank == 0) fprintf(stderr, "vsplat-mpi: at most %d ranks\n", MPI_MAX_RANKS);
    MPI_Finalize();
    return rc;
}
