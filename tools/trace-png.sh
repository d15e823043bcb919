#!/usr/bin/env bash
# A picture of a vsplat trace (vsplat render --trace T.json): one band per
# thread, the tiles as grey bars and, inside them, each stage of each sheet
# in its colour; the frame's serial parts above thread 0.  For a closer
# look open the JSON in ui.perfetto.dev or chrome://tracing.
#   tools/trace-png.sh T.json OUT.png [FROM_MS TO_MS]
# Needs jq and gnuplot (tools/install-deps.sh installs both).
set -euo pipefail
in=$1 out=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# tid, start and end in ms, name
jq -r '.traceEvents[] | select(.ph == "X") | [.tid, .ts / 1000, (.ts + .dur) / 1000, .name] | @tsv' "$in" >"$tmp/spans"
[ -s "$tmp/spans" ] || { echo "trace-png: $in has no spans" >&2; exit 1; }
stages=("projection" "splatting" "classification" "shading" "compositing" "occlusion map")
colours=("#8c564b" "#1f77b4" "#2ca02c" "#ff7f0e" "#d62728" "#9467bd")
frame_parts=("setup" "relevant voxels" "binning" "tiles" "ray casting")
threads=$(awk -F'\t' '$1 > m { m = $1 } END { print m + 1 }' "$tmp/spans")
# y of a thread's band: thread t spans [t, t + 0.8]; frame parts at -0.6
awk -F'\t' -v OFS='\t' '$4 == "tile" { print $2, $3, $1, $1 + 0.8 > "'"$tmp"'/tile" }' "$tmp/spans"
for i in "${!stages[@]}"; do
    awk -F'\t' -v OFS='\t' -v n="${stages[$i]}" '$4 == n { print $2, $3, $1 + 0.1, $1 + 0.7 }' "$tmp/spans" >"$tmp/s$i"
done
for i in "${!frame_parts[@]}"; do
    awk -F'\t' -v OFS='\t' -v n="${frame_parts[$i]}" '$4 == n { print $2, $3, -0.7, -0.2 }' "$tmp/spans" >"$tmp/f$i"
done
range=""
[ $# -ge 4 ] && range="set xrange [$3:$4]"
{
    echo "set terminal pngcairo size 1400,$((180 + 90 * threads)) font 'sans,10'"
    echo "set output '$out'"
    echo "set xlabel 'ms'"
    echo "set yrange [-0.9:$threads]"
    echo "set ytics ('serial' -0.45$(for ((t = 0; t < threads; t++)); do printf ", 'thread %d' %s" "$t" "$t.4"; done))"
    echo "set key outside top center horizontal"
    echo "set style fill solid 1.0 noborder"
    echo "$range"
    printf "plot '%s/tile' using (\$1+\$2)/2:(\$3+\$4)/2:(\$1):(\$2):(\$3):(\$4) with boxxyerror lc rgb '#dddddd' title 'tile'" "$tmp"
    for i in "${!stages[@]}"; do
        [ -s "$tmp/s$i" ] && printf ", '%s/s%d' using (\$1+\$2)/2:(\$3+\$4)/2:(\$1):(\$2):(\$3):(\$4) with boxxyerror lc rgb '%s' title '%s'" "$tmp" "$i" "${colours[$i]}" "${stages[$i]}"
    done
    for i in "${!frame_parts[@]}"; do
        [ -s "$tmp/f$i" ] && printf ", '%s/f%d' using (\$1+\$2)/2:(\$3+\$4)/2:(\$1):(\$2):(\$3):(\$4) with boxxyerror lc rgb '%s' title '%s'" "$tmp" "$i" "$([ $((i % 2)) = 0 ] && echo '#555555' || echo '#999999')" "${frame_parts[$i]}"
    done
    echo
} >"$tmp/plot.gp"
gnuplot "$tmp/plot.gp"
echo "trace-png: wrote $out ($(wc -l <"$tmp/spans") spans, $threads threads)"
