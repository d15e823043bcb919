#!/usr/bin/env bash
# Bit-identity check for refactors: render a fixed set of cases with a
# vsplat binary into a folder as float EXR, or compare two such folders.
#   tools/identity.sh render VSPLAT_BIN OUTDIR   (data from $VSPLAT_DATA or ../shared/data)
#   tools/identity.sh compare VSPLAT_BIN DIR_A DIR_B  (exit 1 on any differing float)
# The cases cover every pipeline, every ISA this CPU has, 1 and 2 threads,
# separable, sheared and general footprints, perspective and small tiles.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
DATA=${VSPLAT_DATA:-$ROOT/../shared/data}

if [ "${1:-}" = compare ]; then
  bin=$2 a=$3 b=$4 n=0 bad=0
  for f in "$a"/*.exr; do
    n=$((n + 1))
    d=$("$bin" compare "$f" "$b/$(basename "$f")" 2>&1 || true)
    case $d in *" max=0") ;; *) echo "differs: $(basename "$f"): $d"; bad=$((bad + 1)) ;; esac
  done
  echo "identity: $n cases, $bad differ"
  [ "$n" -gt 0 ] && [ "$bad" -eq 0 ]
  exit
fi
[ "${1:-}" = render ] || { echo "usage: $0 render VSPLAT_BIN OUTDIR | compare VSPLAT_BIN DIR_A DIR_B" >&2; exit 1; }
BIN=$2 OUT=$3
mkdir -p "$OUT"
head=$DATA/colin27_ch2_mri_t1_head_181x217x181_u8.nii.gz
ct=$DATA/invesalius_cranium_ct_head_256x256x108_i16le.raw.gz
engine=$DATA/openscivis_engine_ct_256x256x128_u8.nii.gz
ctopt=(--dims 256,256,108 --type i16 --spacing 0.9570312,0.9570312,1.5 --iso 300 --ramp 60)
best=$("$BIN" render --scene sphere:16 --size 8x8 --stats - -q -o "$OUT/.probe.exr" | sed -n 's/.*"isa": *"\([a-z0-9]*\)".*/\1/p')
rm -f "$OUT/.probe.exr"
r() { local name=$1; shift; "$BIN" render "$@" -q -o "$OUT/$name.exr"; }
for p in pre post-cd post-gs post-alpha; do
  if [ -f "$head" ]; then
    r head-$p-t2 "$head" --iso 45 --ramp 10 --view 180,0 --size 256x256 --pipeline $p --threads 2
    r head-$p-scalar-t1 "$head" --iso 45 --ramp 10 --view 180,0 --size 256x256 --pipeline $p --threads 1 --isa scalar
    r head-$p-persp "$head" --iso 45 --ramp 10 --view 150,20 --size 192x192 --pipeline $p --perspective 30 --threads 2
    r head-$p-tf "$head" --tf "$ROOT/tools/tf/colin27-skin-brain.vtf" --view 120,15 --size 192x192 --pipeline $p --tile-size 16
  fi
  if [ -f "$ct" ]; then
    r ct-$p "$ct" "${ctopt[@]}" --view 180,10 --size 192x192 --pipeline $p --threads 2
  fi
  if [ -f "$engine" ]; then
    r engine-$p "$engine" --iso 110 --ramp 10 --view 30,30 --size 192x192 --pipeline $p --zoom 1.6
  fi
  for i in sse4 avx2; do
    r cell-$p-$i --scene cell --view 33,21 --size 160x160 --pipeline $p --isa $i
  done
  r cell-$p --scene cell --view 33,21 --size 160x160 --pipeline $p
  r cell-$p-scalar --scene cell --view 33,21 --size 160x160 --pipeline $p --isa scalar --threads 1
  r sphere-$p-noocc --scene sphere --view 10,70 --size 128x128 --pipeline $p --no-occlusion --no-tiles
done
r head-raycast --scene head --size 96x96 --pipeline raycast --threads 2
r cell-raycast --scene cell --size 96x96 --pipeline raycast --threads 1
echo "identity: rendered $(ls "$OUT"/*.exr | wc -l) cases (best ISA $best) into $OUT"
