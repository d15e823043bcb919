/* vsplat-bench error: image error against run time.  Every splatting
 * pipeline x sheet thickness x exact/LUT normals x footprint-table resolution
 * is timed (interleaved runs, median) and compared with a reference ray
 * caster: the scene's analytic function for sphere, ml and cube (ray step
 * 0.05, iso crossing refined; the sphere also in perspective), and for Colin27 (an opaque
 * iso-surface, and translucent with tools/tf/colin27-skin-brain.vtf) the same samples
 * reconstructed with the exact Gaussian (ray step 0.05), and also with the
 * Gaussian's weights normalised (ray_normalize: psnr_n).  RMSE, PSNR and SSIM
 * come from vs_image_compare (all four channels); for the cube also the
 * silhouette edge width (10-90 % of alpha, as tests/test_splat.c).  A row is
 * on the Pareto front (*) if no other row of its scene is both faster and
 * more accurate (higher PSNR). */
#include "bench.h"

#ifndef VSPLAT_SOURCE_DIR
#define VSPLAT_SOURCE_DIR "."
#endif

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct err_scene {
    const char *name;  /* printed and in the CSV */
    const char *input; /* bench_load key        */
    int analytic;      /* reference: analytic function (1) or exact Gaussian (0) */
    int size_full, size_quick;
    double az, el;
    int has_iso;
    double iso, ramp;
    int edge; /* measure the cube's silhouette edge width */
    double fov; /* perspective field of view (0: orthographic) */
    const char *tf; /* transfer-function file under the source tree, or NULL */
} err_scene;

static const err_scene scenes[] = {
    {"sphere", "scene:sphere", 1, 256, 128, 20, 15, 0, 0, 0, 0, 0.0, NULL},
    {"ml", "scene:ml", 1, 256, 128, 20, 15, 0, 0, 0, 0, 0.0, NULL},
    /* view 0,0 as tests/test_splat.c: the right silhouette crosses the middle row */
    {"cube", "scene:cube", 1, 256, 128, 0, 0, 0, 0, 0, 1, 0.0, NULL},
    {"colin27", "colin27", 0, 128, 64, 180, 0, 1, 45, 10, 0, 0.0, NULL},
    /* perspective, against the ray caster casting from the eye */
    {"sphere-persp30", "scene:sphere", 1, 256, 128, 20, 15, 0, 0, 0, 0, 30.0, NULL},
    /* translucent: skin over cortical folds (pre-integration on by default) */
    {"colin27-tf", "colin27", 0, 128, 64, 120, 15, 0, 0, 0, 0, 0.0, "tools/tf/colin27-skin-brain.vtf"},
};
#define NSCENES ((int)(sizeof scenes / sizeof scenes[0]))

/* Silhouette edge width (10-90 % of alpha) across the cube's right edge,
 * along the middle row: tests/test_splat.c's measure. */
static double edge_width(const vs_image *img)
{
    int y = img->height / 2, W = img->width;
    const float *row = img->rgba + 4 * (size_t)y * W;
    int x90 = -1, x10 = -1;
    double p90 = 0, p10 = 0;
    for (int x = W / 2; x < W - 1; x++) {
        double a0 = row[4 * x + 3], a1 = row[4 * (x + 1) + 3];
        if (x90 < 0 && a0 >= 0.9 && a1 < 0.9) {
            x90 = x;
            p90 = x + (a0 - 0.9) / (a0 - a1);
        }
        if (x10 < 0 && a0 >= 0.1 && a1 < 0.1) {
            x10 = x;
            p10 = x + (a0 - 0.1) / (a0 - a1);
        }
    }
    if (x90 < 0 || x10 < 0) return NAN;
    return p10 - p90;
}

typedef struct err_row {
    vs_pipeline pipeline;
    double slab;
    int exact;
    int fpres;
    bench_summary ms;
    vs_image_diff d;
    double psnr_n; /* against the normalised Gaussian ray caster (NAN for analytic references) */
    double edge;
    int pareto;
    int ok;
} err_row;

static void mark_pareto(err_row *rows, int n)
{
    for (int i = 0; i < n; i++) {
        rows[i].pareto = rows[i].ok;
        for (int j = 0; j < n && rows[i].pareto; j++)
            if (j != i && rows[j].ok && rows[j].ms.median < rows[i].ms.median && rows[j].d.psnr > rows[i].d.psnr)
                rows[i].pareto = 0;
    }
}

static void print_row(const char *scene, const err_row *r, int edge)
{
    char e[16] = "-";
    if (edge && !isnan(r->edge)) snprintf(e, sizeof e, "%.2f", r->edge);
    if (!r->ok) {
        printf("%-8s %-10s %5.2f %-5s %5d  failed\n", scene, vs_pipeline_name(r->pipeline), r->slab,
               r->exact ? "exact" : "lut", r->fpres);
        return;
    }
    char pn[16] = "-";
    if (!isnan(r->psnr_n)) snprintf(pn, sizeof pn, "%.2f", r->psnr_n);
    printf("%-8s %-10s %5.2f %-5s %5d %9.1f %8.1f-%-8.1f %9.5f %7.2f %7.4f %7s %7s %s\n", scene,
           vs_pipeline_name(r->pipeline), r->slab, r->exact ? "exact" : "lut", r->fpres, r->ms.median, r->ms.min,
           r->ms.max, r->d.rmse, r->d.psnr, r->d.ssim, pn, e, r->pareto ? "*" : "");
}

int bench_error(const bench_opts *o)
{
    double t0 = bench_now_ms();
    const int runs = bench_runs(o, 3, 1);
    static const double slabs_full[] = {0.25, 0.5, 1, 2}, slabs_quick[] = {0.5, 1, 2};
    static const int fpres_list[] = {256, 32};
    const double *slabs = o->quick ? slabs_quick : slabs_full;
    const int nslab = o->quick ? 3 : 4;
    const int nexact = o->quick ? 1 : 2; /* quick: LUT normals only */
    const int nfp = o->quick ? 1 : 2; /* quick: footprint table 256 only */
    int failed = 0;

    if (bench_results_dir(o)) return 2;
    FILE *csv = bench_result_open(o, "error.csv");
    if (!csv) return 2;
    fprintf(csv, "scene,reference,size,pipeline,slab,normals,footprint_res,median_ms,min_ms,max_ms,rmse,psnr,ssim,"
                 "edge_px,pareto,threads,runs,psnr_normalized\n");
    printf("\nError against run time: median ms over %d interleaved run%s, threads %d (0 = one per core); machine: %s; load average "
           "%s\n",
           runs, runs == 1 ? "" : "s", o->threads, bench_machine(), bench_loadavg());
    printf("%-8s %-10s %5s %-5s %5s %9s %17s %9s %7s %7s %7s %7s %s\n", "scene", "pipeline", "slab", "norm", "fpres",
           "ms", "min-max", "rmse", "psnr", "ssim", "psnr_n", "edge", "pareto");

    int scenes_done = 0, done[NSCENES] = {0};
    for (int si = 0; si < NSCENES; si++) {
        const err_scene *sc = &scenes[si];
        vs_volume *vol = NULL;
        int ls = bench_load(o, sc->input, &vol);
        if (ls != 0) {
            if (ls < 0) failed++;
            continue;
        }
        const int size = o->quick ? sc->size_quick : sc->size_full;
        vs_settings base;
        vs_settings_init(&base);
        base.width = base.height = size;
        base.azimuth = sc->az;
        base.elevation = sc->el;
        base.perspective_fov = sc->fov;
        base.threads = o->threads;
        if (sc->has_iso) {
            base.has_iso = 1;
            base.iso_lo = sc->iso;
            base.iso_hi = INFINITY;
            base.ramp = sc->ramp;
        }
        vs_tf_point *tfp = NULL;
        if (sc->tf) {
            char path[4096];
            snprintf(path, sizeof path, "%s/%s", VSPLAT_SOURCE_DIR, sc->tf);
            vs_context *tctx = NULL;
            int n = 0;
            if (vs_context_create(&tctx) != VS_OK || vs_tf_load_for_volume(tctx, path, vol, &tfp, &n) != VS_OK) {
                fprintf(stderr, "error: %s: %s\n", path, tctx ? vs_last_error(tctx) : "no context");
                if (tctx) vs_context_release(tctx);
                failed++;
                vs_volume_release(vol);
                continue;
            }
            vs_context_release(tctx);
            base.tf = tfp;
            base.tf_count = n;
        }
        /* the reference */
        vs_settings rs = base;
        rs.pipeline = VS_PIPELINE_RAYCAST;
        rs.ray_step = 0.05;
        rs.ray_analytic = sc->analytic;
        rs.ray_trilinear = 0;
        bench_case ref;
        bench_case_set(&ref, "reference", vol, &rs);
        ref.keep_image = 1;
        char label[64];
        snprintf(label, sizeof label, "error %s reference", sc->name);
        if (bench_run(label, &ref, 1, 1)) {
            failed++;
            bench_cases_free(&ref, 1);
            vs_tf_free(tfp);
            vs_volume_release(vol);
            continue;
        }
        bench_summary rms = bench_summarize(&ref, bench_m_total);
        /* a Gaussian reference also without the kernel's lattice ripple
         * (ray_normalize), the field post-gs reconstructs (gs_normalize) */
        bench_case nref;
        int have_nref = 0;
        if (!sc->analytic) {
            rs.ray_normalize = 1;
            bench_case_set(&nref, "normalised reference", vol, &rs);
            nref.keep_image = 1;
            snprintf(label, sizeof label, "error %s normalised reference", sc->name);
            have_nref = !bench_run(label, &nref, 1, 1);
            if (!have_nref) {
                failed++;
                bench_cases_free(&nref, 1);
            }
        }
        double ref_edge = sc->edge ? edge_width(&ref.img) : NAN;
        const char *refname = sc->analytic ? "analytic ray caster" : "exact-Gaussian ray caster";

        int n = 4 * nslab * nexact * nfp, k = 0;
        bench_case *cases = calloc((size_t)n, sizeof *cases);
        err_row *rows = calloc((size_t)n, sizeof *rows);
        if (!cases || !rows) {
            free(cases);
            free(rows);
            bench_cases_free(&ref, 1);
            if (have_nref) bench_cases_free(&nref, 1);
            vs_tf_free(tfp);
            vs_volume_release(vol);
            return 2;
        }
        /* post-alpha first: its relevant-voxel list (with voxel gradients) serves post-cd and post-gs too */
        static const vs_pipeline order[4] = {VS_PIPELINE_POST_ALPHA, VS_PIPELINE_PRE, VS_PIPELINE_POST_CD,
                                             VS_PIPELINE_POST_GS};
        for (int p = 0; p < 4; p++)
            for (int a = 0; a < nslab; a++)
                for (int e = 0; e < nexact; e++)
                    for (int f = 0; f < nfp; f++) {
                        vs_settings s = base;
                        s.pipeline = order[p];
                        s.slab = slabs[a];
                        s.exact_normals = e;
                        s.footprint_resolution = fpres_list[f];
                        char name[96];
                        snprintf(name, sizeof name, "%s %s ds %.2f %s fp %d", sc->name, vs_pipeline_name(s.pipeline),
                                 s.slab, e ? "exact" : "lut", s.footprint_resolution);
                        bench_case_set(&cases[k], name, vol, &s);
                        cases[k].keep_image = 1;
                        rows[k].pipeline = s.pipeline;
                        rows[k].slab = s.slab;
                        rows[k].exact = e;
                        rows[k].fpres = s.footprint_resolution;
                        k++;
                    }
        snprintf(label, sizeof label, "error %s", sc->name);
        failed += bench_run(label, cases, n, runs);
        vs_context *cctx = NULL;
        vs_context_create(&cctx);
        for (int i = 0; i < n; i++) rows[i].psnr_n = NAN;
        for (int i = 0; i < n; i++) {
            if (cases[i].failed || !cctx) continue;
            rows[i].ms = bench_summarize(&cases[i], bench_m_total);
            rows[i].edge = sc->edge ? edge_width(&cases[i].img) : NAN;
            if (vs_image_compare(cctx, &ref.img, &cases[i].img, &rows[i].d) == VS_OK) rows[i].ok = 1;
            else failed++;
            vs_image_diff dn;
            rows[i].psnr_n =
                have_nref && vs_image_compare(cctx, &nref.img, &cases[i].img, &dn) == VS_OK ? dn.psnr : NAN;
        }
        if (cctx) vs_context_release(cctx);
        mark_pareto(rows, n);

        printf("-- %s %dx%d against the %s (ray step 0.05): %.1f ms", sc->name, size, size, refname, rms.median);
        if (sc->edge) printf(", reference edge %.2f px", ref_edge);
        printf(" --\n");
        /* print in pipeline order pre, post-cd, post-gs, post-alpha */
        for (int pp = 0; pp < 4; pp++)
            for (int i = 0; i < n; i++)
                if ((int)rows[i].pipeline == pp) print_row(sc->name, &rows[i], sc->edge);
        for (int pp = 0; pp < 4; pp++)
            for (int i = 0; i < n; i++) {
                const err_row *r = &rows[i];
                if ((int)r->pipeline != pp) continue;
                fprintf(csv, "%s,%s,%d,%s,%.2f,%s,%d,%.3f,%.3f,%.3f,%.6g,%.4f,%.5f,%.3f,%s,%d,%d,%.4f\n", sc->name,
                        sc->analytic ? "analytic" : "exact-gaussian", size, vs_pipeline_name(r->pipeline), r->slab,
                        r->exact ? "exact" : "lut", r->fpres, r->ms.median, r->ms.min, r->ms.max, r->d.rmse,
                        r->d.psnr, r->d.ssim, r->edge, r->pareto ? "*" : "", cases[i].warm.threads, runs, r->psnr_n);
            }
        fprintf(csv, "%s,%s,%d,%s,%.2f,%s,%d,%.3f,%.3f,%.3f,0,inf,1,%.3f,,%d,1,nan\n", sc->name,
                sc->analytic ? "analytic" : "exact-gaussian", size, "reference", 0.05, "exact", 0, rms.median,
                rms.min, rms.max, ref_edge, ref.warm.threads);
        fflush(csv);
        scenes_done++;
        done[si] = 1;
        bench_cases_free(cases, n);
        bench_cases_free(&ref, 1);
        if (have_nref) bench_cases_free(&nref, 1);
        free(cases);
        free(rows);
        bench_contexts_release();
        vs_tf_free(tfp);
        vs_volume_release(vol);
    }
    fclose(csv);

    if (scenes_done) {
        char script[8192];
        int len = snprintf(script, sizeof script,
                           "%s"
                           "set output 'error_vs_time.png'\n"
                           "set datafile separator ','\n"
                           "set multiplot layout 2,3 title \"vsplat: PSNR against the reference ray caster vs "
                           "frame time (* = Pareto front)\"\n"
                           "set logscale x\n"
                           "set xlabel 'ms (log)'\n"
                           "set ylabel 'PSNR dB'\n"
                           "set grid\n"
                           "set key bottom right font ',8'\n",
                           bench_plot_terminal(1500, 800));
        static const char *pl[4] = {"pre", "post-cd", "post-gs", "post-alpha"};
        static const int pt[4] = {5, 7, 9, 13};
        for (int si = 0; si < NSCENES && len < (int)sizeof script; si++) {
            if (!done[si]) continue;
            len += snprintf(script + len, sizeof script - (size_t)len, "set title '%s'\nplot ", scenes[si].name);
            for (int p = 0; p < 4; p++)
                len += snprintf(script + len, sizeof script - (size_t)len,
                                "'error.csv' using (strcol(1) eq '%s' && strcol(4) eq '%s' ? $8 : NaN):12 with "
                                "points pt %d ps 0.8 title '%s', ",
                                scenes[si].name, pl[p], pt[p], pl[p]);
            len += snprintf(script + len, sizeof script - (size_t)len,
                            "'error.csv' using (strcol(1) eq '%s' && strcol(15) eq '*' ? $8 : NaN):12 with "
                            "points pt 6 ps 1.8 lc rgb 'black' title 'Pareto'\n",
                            scenes[si].name);
        }
        if (len < (int)sizeof script) snprintf(script + len, sizeof script - (size_t)len, "unset multiplot\n");
        if (bench_plot(o, "error_vs_time", script)) failed++;
    }
    printf("error: %.1f s, results in %s\n", (bench_now_ms() - t0) / 1000.0, o->out_dir);
    return failed ? 2 : 0;
}
