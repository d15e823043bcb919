#!/usr/bin/env bash
# vsplat-mpi scaling on one machine: per-rank render time, compositing time
# and bytes sent for N ranks (docs/DISTRIBUTED.md).  On a machine with fewer
# cores than ranks the runs are oversubscribed (the header says how many
# cores): render times then measure the load balance and the work per rank,
# not a speed-up.
# The three compositors (--composite gather, the default, reduce and swap) and both
# ways of reading (--read parts, every rank its own part of a raw or NIfTI
# file, the default, and root, rank 0 reading it all) run in each round,
# interleaved with the rank counts.
# Usage: bench/mpi.sh [BUILD_DIR] [OUT_DIR]   (env: RANKS="1 2 4 8", RUNS=3,
#        SIZE=256x256, INPUT="path --iso 45 --ramp 10 --view 180,0",
#        COMPOSITE="gather reduce swap", READS="parts root")
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
COMPOSITE=${COMPOSITE:-gather reduce swap}
READS=${READS:-parts root}
SIZE=${SIZE:-256x256}
mkdir -p "$OUT"
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
CSV=$OUT/mpi.csv
{
    echo "# vsplat-mpi $INPUT --size $SIZE --threads 1 --no-pin; $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg)"
    echo "# $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //')"
    echo "composite,read,ranks,run,rank,ms_render,ms_composite,bytes_composite,bytes_scatter,voxels_held,voxels_relevant,ms_scatter,ms_total,ms_load,ms_prepare,voxels_peak"
} >"$CSV"
# shellcheck disable=SC2086
for run in $(seq 1 "$RUNS"); do
    for n in $RANKS; do # interleaved: each round runs every N and compositor once
        for c in $COMPOSITE; do for rd in $READS; do
            timeout 600 mpirun --oversubscribe -np "$n" "$MPI" render $INPUT --size "$SIZE" --threads 1 --no-pin -q \
                --composite "$c" --read "$rd" -o "$T/img.exr" --stats "$T/s.json"
            jq -r --arg c "$c" --arg rd "$rd" --arg n "$n" --arg run "$run" '.ms_scatter as $sc | .ms_total as $t |
                .ms_prepare as $p | .per_rank[] | [$c, $rd, ($n | tonumber), ($run | tonumber), .rank, .ms_render,
                .ms_composite, .bytes_composite, .bytes_scatter, .voxels_held, .voxels_relevant, $sc, $t, .ms_load, $p,
                .voxels_peak] | @csv' "$T/s.json" | tr -d '"' >>"$CSV"
        done; done
    done
done
# per N, medians over the runs: slowest rank's render, root's compositing,
# bytes into the root, scatter bytes, wall clock
SUM=$OUT/mpi_summary.csv
echo "composite,read,ranks,render_ms_slowest,render_ms_fastest,composite_ms_root,bytes_composite,bytes_scatter,max_voxels_held,ms_scatter,ms_total,ms_load_slowest,ms_prepare,max_voxels_peak,max_bytes_one_rank" >"$SUM"
for c in $COMPOSITE; do for rd in $READS; do for n in $RANKS; do
    awk -F, -v c="$c" -v rd="$rd" -v n="$n" '
        $1 == c && $2 == rd && $3 == n { r = $4; if (!(r in rmax) || $6 > rmax[r]) rmax[r] = $6; if (!(r in rmin) || $6 < rmin[r]) rmin[r] = $6
                  if ($5 == 0) comp[r] = $7; bytes[r] += $8; scat[r] += $9; if ($10 > held[r]) held[r] = $10
                  sc[r] = $12; tot[r] = $13; if ($14 > ld[r]) ld[r] = $14; pr[r] = $15; if ($16 > peak[r]) peak[r] = $16; if ($8 > bmax[r]) bmax[r] = $8 }
        function med(a,   k, v, m, i, j, t) { m = 0; for (k in a) v[++m] = a[k]
            for (i = 1; i <= m; i++) for (j = i + 1; j <= m; j++) if (v[j] < v[i]) { t = v[i]; v[i] = v[j]; v[j] = t }
            return m % 2 ? v[(m + 1) / 2] : (v[m / 2] + v[m / 2 + 1]) / 2 }
        END { printf "%s,%s,%d,%.1f,%.1f,%.2f,%.0f,%.0f,%.0f,%.1f,%.1f,%.1f,%.1f,%.0f,%.0f\n", c, rd, n, med(rmax), med(rmin), med(comp),
              med(bytes), med(scat), med(held), med(sc), med(tot), med(ld), med(pr), med(peak), med(bmax) }' "$CSV" >>"$SUM"
done; done; done
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
plot '< grep ^reduce,parts $SUM' using 3:4 with linespoints title 'render, slowest rank', \
     '< grep ^reduce,parts $SUM' using 3:6 with linespoints title 'compositing at rank 0 (reduce)', \
     '< grep ^gather,parts $SUM' using 3:6 with linespoints title 'compositing at rank 0 (gather)', \
     '< grep ^swap,parts $SUM' using 3:6 with linespoints title 'compositing at rank 0 (swap)', \
     '< grep ^swap,parts $SUM' using 3:(\$7/1024) axes x1y2 with linespoints title 'KiB sent (swap)', \
     '< grep ^reduce,parts $SUM' using 3:(\$7/1024) axes x1y2 with linespoints title 'KiB sent (reduce)', \
     '< grep ^gather,parts $SUM' using 3:(\$7/1024) axes x1y2 with linespoints title 'KiB sent (gather)'
EOF
    echo "wrote $CSV, $SUM, $OUT/mpi.png"
fi
