#!/usr/bin/env bash
# vsplat-mpi scaling on one machine: per-rank render time, compositing time
# and bytes sent for N ranks (docs/DISTRIBUTED.md).  On a machine with fewer
# cores than ranks the runs are oversubscribed (the header says how many
# cores): render times then measure the load balance and the work per rank,
# not a speed-up.
# Both compositors run in each round (--composite gather, the default, and
# reduce), interleaved with the rank counts.
# Usage: bench/mpi.sh [BUILD_DIR] [OUT_DIR]   (env: RANKS="1 2 4 8", RUNS=3,
#        SIZE=256x256, INPUT="path --iso 45 --ramp 10 --view 180,0",
#        COMPOSITE="gather reduce")
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${1:-$ROOT/build}
OUT=${2:-$ROOT/bench/results}
MPI=$BUILD/vsplat-mpi
[[ -x $MPI ]] || { echo "mpi.sh: $MPI not built (CMake found no MPI)" >&2; exit 1; }
command -v jq >/dev/null || { echo "mpi.sh: needs jq" >&2; exit 1; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
DATA=${VSPLAT_DATA:-$ROOT/../shared/data}
HEAD=$DATA/colin27_ch2_mri_t1_head_181x217x181_u8.nii.gz
if [[ -z ${INPUT:-} ]]; then
    if [[ -f $HEAD ]]; then INPUT="$HEAD --iso 45 --ramp 10 --view 180,0"; else INPUT="--scene cell:256 --view 30,70"; fi
fi
RANKS=${RANKS:-1 2 4 8}
RUNS=${RUNS:-3}
COMPOSITE=${COMPOSITE:-gather reduce}
SIZE=${SIZE:-256x256}
mkdir -p "$OUT"
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
CSV=$OUT/mpi.csv
{
    echo "# vsplat-mpi $INPUT --size $SIZE --threads 1 --no-pin; $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg)"
    echo "# $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //')"
    echo "composite,ranks,run,rank,ms_render,ms_composite,bytes_composite,bytes_scatter,voxels_held,voxels_relevant,ms_scatter,ms_total,ms_load,ms_prepare"
} >"$CSV"
# shellcheck disable=SC2086
for run in $(seq 1 "$RUNS"); do
    for n in $RANKS; do # interleaved: each round runs every N and compositor once
        for c in $COMPOSITE; do
            timeout 600 mpirun --oversubscribe -np "$n" "$MPI" render $INPUT --size "$SIZE" --threads 1 --no-pin -q \
                --composite "$c" -o "$T/img.exr" --stats "$T/s.json"
            jq -r --arg c "$c" --arg n "$n" --arg run "$run" '.ms_scatter as $sc | .ms_total as $t | .ms_load as $l |
                .ms_prepare as $p | .per_rank[] | [$c, ($n | tonumber), ($run | tonumber), .rank, .ms_render,
                .ms_composite, .bytes_composite, .bytes_scatter, .voxels_held, .voxels_relevant, $sc, $t, $l, $p] |
                @csv' "$T/s.json" | tr -d '"' >>"$CSV"
        done
    done
done
# per N, medians over the runs: slowest rank's render, root's compositing,
# bytes into the root, scatter bytes, wall clock
SUM=$OUT/mpi_summary.csv
echo "composite,ranks,render_ms_slowest,render_ms_fastest,composite_ms_root,bytes_composite,bytes_scatter,max_voxels_held,ms_scatter,ms_total,ms_load,ms_prepare" >"$SUM"
for c in $COMPOSITE; do for n in $RANKS; do
    awk -F, -v c="$c" -v n="$n" '
        $1 == c && $2 == n { r = $3; if (!(r in rmax) || $5 > rmax[r]) rmax[r] = $5; if (!(r in rmin) || $5 < rmin[r]) rmin[r] = $5
                  if ($4 == 0) comp[r] = $6; bytes[r] += $7; scat[r] += $8; if ($9 > held[r]) held[r] = $9
                  sc[r] = $11; tot[r] = $12; ld[r] = $13; pr[r] = $14 }
        function med(a,   k, v, m, i, j, t) { m = 0; for (k in a) v[++m] = a[k]
            for (i = 1; i <= m; i++) for (j = i + 1; j <= m; j++) if (v[j] < v[i]) { t = v[i]; v[i] = v[j]; v[j] = t }
            return m % 2 ? v[(m + 1) / 2] : (v[m / 2] + v[m / 2 + 1]) / 2 }
        END { printf "%s,%d,%.1f,%.1f,%.2f,%.0f,%.0f,%.0f,%.1f,%.1f,%.1f,%.1f\n", c, n, med(rmax), med(rmin), med(comp),
              med(bytes), med(scat), med(held), med(sc), med(tot), med(ld), med(pr) }' "$CSV" >>"$SUM"
done; done
column -s, -t "$SUM"
if command -v gnuplot >/dev/null; then
    gnuplot <<EOF
set terminal pngcairo size 800,420
set output '$OUT/mpi.png'
set datafile separator ','
set key top left
set xlabel 'ranks (oversubscribed on $(nproc) cores)'
set ylabel 'ms'
set y2label 'KiB sent, all ranks'
set y2tics
set logscale x 2
set title 'vsplat-mpi: slowest rank render, rank 0 compositing, bytes (medians of $RUNS)'
plot '< grep ^reduce $SUM' using 2:3 with linespoints title 'render, slowest rank', \
     '< grep ^reduce $SUM' using 2:5 with linespoints title 'compositing at rank 0 (reduce)', \
     '< grep ^gather $SUM' using 2:5 with linespoints title 'compositing at rank 0 (gather)', \
     '< grep ^reduce $SUM' using 2:(\$6/1024) axes x1y2 with linespoints title 'KiB sent (reduce)', \
     '< grep ^gather $SUM' using 2:(\$6/1024) axes x1y2 with linespoints title 'KiB sent (gather)'
EOF
    echo "wrote $CSV, $SUM, $OUT/mpi.png"
fi
