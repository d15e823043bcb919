/* vsplat-bench: timings of the vsplat library (bench/README.md).
 *
 *   vsplat-bench table1|error|scaling|growth|kernels|limits|peers|oracle|lod|all [--quick] [--out DIR] [--data DIR]
 *                [--runs N] [--threads N] [--no-plot]
 *   vsplat-bench frame INPUT [vsplat render options] [--frames K]
 *
 * Exit codes: 0 success, 1 usage error, 2 a case failed. */
#include "bench.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *f)
{
    fprintf(f,
            "usage: vsplat-bench MODE [options]\n"
            "modes:\n"
            "  table1    the paper's Table 1 (stage times per image and pipeline) and speedups over it\n"
            "  error     error (RMSE, PSNR, SSIM, edge width) against run time, Pareto front marked *\n"
            "  scaling   frame time for 1..N threads (and 2N), pinned and not, speedups\n"
            "  growth    frame time against voxels and image size, with and without levels of detail\n"
            "  kernels   one SIMD kernel at a time per ISA, peak FMA rate, rasterize stage per ISA\n"
            "  limits    this machine's bandwidths (L1..DRAM) and peak add/FMA rates per ISA, and each\n"
            "            stage of the head's frames as a share of its limit (roofline plot, counters)\n"
            "  peers     vsplat against VolPack's octree renderer on the same volumes, views and image\n"
            "            size: frame-time medians, ratios, PSNR against the ray caster (needs VolPack)\n"
            "  oracle    post-cd on every voxel against only the voxels that can show (the hidden ones\n"
            "            made air from a ray march): the ceiling of visibility culling, same views as peers\n"
            "  lod       levels of detail: a generated 2.16 G-voxel ball seen at 256^2 against the same\n"
            "            ball 4x coarser and against full resolution (peak memory too); real volumes\n"
            "            at 128^2 and 256^2 with and without, against a 4x supersampled reference\n"
            "  all       table1, error, scaling, growth, kernels, limits, peers, oracle, lod\n"
            "  frame INPUT [vsplat render options] [--frames K]\n"
            "            K frames turning the azimuth by 360/K, the iso-change time and peak memory:\n"
            "            prints one line median_ms=... min_ms=... max_ms=... iso_change_ms=... peak_mb=...\n"
            "options (all modes but frame):\n"
            "  --quick         small images, fewer runs and rows (all --quick stays under two minutes)\n"
            "  --out DIR       results folder for CSV, plot data and PNG plots (default bench/results,\n"
            "                  with --quick bench/results/quick)\n"
            "  --data DIR      folder of the real volumes (default $VSPLAT_DATA, else the source tree's\n"
            "                  ../shared/data); cases whose file is absent are skipped\n"
            "  --runs N        timed runs per configuration (default 3, scaling 5; --quick 1, scaling 2)\n"
            "  --threads N     thread count of the N-thread rows (default 0 = one per core)\n"
            "  --no-plot       write the gnuplot scripts but do not run gnuplot\n");
}

static int to_int(const char *s, int lo, int hi, int *out)
{
    char *end = NULL;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (!*s || *end || errno || v < lo || v > hi) return 0;
    *out = (int)v;
    return 1;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 1;
    }
    const char *mode = argv[1];
    if (!strcmp(mode, "--help") || !strcmp(mode, "-h") || !strcmp(mode, "help")) {
        usage(stdout);
        return 0;
    }
    bench_opts o;
    memset(&o, 0, sizeof o);
    o.out_dir = "bench/results";
    o.plot = 1;
    const char *data = NULL;
    int out_given = 0;

    if (!strcmp(mode, "frame")) {
        /* frame parses the render options itself; --data is not used (INPUT is a path) */
        o.data_dir = bench_data_dir(NULL);
        return bench_frame(&o, argc - 2, argv + 2);
    }

    for (int i = 2; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--quick")) {
            o.quick = 1;
        } else if (!strcmp(a, "--no-plot")) {
            o.plot = 0;
        } else if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--out") || !strcmp(a, "--data") || !strcmp(a, "--runs") || !strcmp(a, "--threads")) {
            if (!v) {
                fprintf(stderr, "vsplat-bench: %s: missing value\n", a);
                return 1;
            }
            i++;
            if (!strcmp(a, "--out")) {
                if (!*v) {
                    fprintf(stderr, "vsplat-bench: --out: empty folder name\n");
                    return 1;
                }
                o.out_dir = v;
                out_given = 1;
            } else if (!strcmp(a, "--data")) {
                data = v;
            } else if (!strcmp(a, "--runs")) {
                if (!to_int(v, 1, 1000, &o.runs)) {
                    fprintf(stderr, "vsplat-bench: --runs: expected an integer in 1..1000, got '%s'\n", v);
                    return 1;
                }
            } else if (!to_int(v, 0, 256, &o.threads)) {
                fprintf(stderr, "vsplat-bench: --threads: expected an integer in 0..256, got '%s'\n", v);
                return 1;
            }
        } else {
            fprintf(stderr, "vsplat-bench: %s: unknown option (see vsplat-bench --help)\n", a);
            return 1;
        }
    }
    o.data_dir = bench_data_dir(data);
    /* quick results never overwrite the full ones committed in bench/results */
    if (o.quick && !out_given) o.out_dir = "bench/results/quick";

    int (*run[])(const bench_opts *) = {bench_table1,  bench_error,  bench_scaling, bench_growth,
                                        bench_kernels, bench_limits, bench_peers, bench_oracle,
                                        bench_lod};
    const char *names[] = {"table1", "error", "scaling", "growth", "kernels", "limits", "peers", "oracle", "lod"};
    const int nmodes = (int)(sizeof names / sizeof names[0]);
    int rc = 0, known = 0;
    double t0 = bench_now_ms();
    for (int m = 0; m < nmodes; m++) {
        if (strcmp(mode, "all") && strcmp(mode, names[m])) continue;
        known = 1;
        if (!strcmp(mode, "all")) printf("\n==== vsplat-bench %s%s ====\n", names[m], o.quick ? " --quick" : "");
        fflush(stdout);
        int r = run[m](&o);
        fflush(stdout);
        if (r > rc) rc = r;
    }
    if (!known) {
        fprintf(stderr, "vsplat-bench: %s: unknown mode (table1, error, scaling, growth, kernels, limits, peers, oracle, lod, frame, all)\n", mode);
        return 1;
    }
    if (!strcmp(mode, "all")) printf("\nall: %.1f s\n", (bench_now_ms() - t0) / 1000.0);
    return rc;
}
