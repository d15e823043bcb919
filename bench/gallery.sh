#!/usr/bin/env bash
# Render the README gallery with the project's own CLI:
#   bench/gallery.sh [BUILD_DIR]   (data from $VSPLAT_DATA or ../shared/data)
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
V=${1:-$ROOT/build}/vsplat
DATA=${VSPLAT_DATA:-$ROOT/../shared/data}
OUT=$ROOT/bench/gallery
mkdir -p "$OUT"
S=(--size 320x320)
# the paper's claim: the 8^3 cube, pre-shaded (blurred) vs post-shaded (crisp)
for p in pre post-cd post-gs post-alpha; do
    "$V" render --scene cube --pipeline $p --view 30,25 "${S[@]}" -q -o "$OUT/cube-$p.png"
done
"$V" render --scene sphere --pipeline post-cd --view 30,25 "${S[@]}" -q -o "$OUT/sphere-post-cd.png"
"$V" render --scene ml --pipeline post-cd --view 20,15 "${S[@]}" -q -o "$OUT/ml-post-cd.png"
if [[ -d $DATA ]]; then
    C=$DATA/colin27_ch2_mri_t1_head_181x217x181_u8.nii.gz
    "$V" render "$C" --iso 45 --ramp 10 --view 200,10 --pipeline pre "${S[@]}" -q -o "$OUT/head-skin-pre.png"
    "$V" render "$C" --iso 45 --ramp 10 --view 200,10 --pipeline post-cd "${S[@]}" -q -o "$OUT/head-skin-post-cd.png"
    # translucent: skin over cortical folds, every pipeline next to the ray caster
    for p in pre post-cd post-gs post-alpha raycast; do
        "$V" render "$C" --tf "$ROOT/tools/tf/colin27-skin-brain.vtf" --view 120,15 --pipeline $p "${S[@]}" -q \
            -o "$OUT/head-tf-$p.png"
    done
    # perspective (45 degrees): the near side looms larger than the far one
    "$V" render "$C" --iso 45 --ramp 10 --view 235,-5 --zoom 0.7 --perspective 45 --pipeline post-cd "${S[@]}" -q \
        -o "$OUT/head-perspective-post-cd.png"
    "$V" render "$DATA/unc_mrbrain_volpack_brainsmall_128x128x84_u8.den" --spacing 1,1,1.3 --iso 70 --ramp 8 \
        --view 200,20 --pipeline post-gs "${S[@]}" -q -o "$OUT/mrbrain-post-gs.png"
    "$V" render "$DATA/invesalius_cranium_ct_head_256x256x108_i16le.raw.gz" --dims 256,256,108 --type i16 \
        --spacing 0.9570312,0.9570312,1.5 --iso 300 --ramp 60 --view 180,10 --pipeline post-cd "${S[@]}" -q \
        -o "$OUT/ct-bone-post-cd.png"
    "$V" render "$DATA/openscivis_engine_ct_256x256x128_u8.nii.gz" --iso 110 --ramp 10 --view 30,30 \
        --pipeline post-cd "${S[@]}" -q -o "$OUT/engine-post-cd.png"
    "$V" render "$DATA/openscivis_bonsai_ct_256x256x256_u8.nii.gz" --iso 40 --ramp 8 --view 20,10 \
        --pipeline post-cd "${S[@]}" -q -o "$OUT/bonsai-post-cd.png"
    # EM: dark membranes, semi-transparent; value 0 is inside the range, so
    # every voxel is relevant.  Full resolution: a level averages the thin
    # dark membranes with the bright cytoplasm around them, out of the range
    "$V" render "$DATA/isbi2012_sstem_drosophila_vnc_512x512x30_u8_png.tar" --spacing 4,4,50 --iso 0:60 --ramp 15 \
        --opacity 0.3 --view 20,40 --no-lod --pipeline post-cd "${S[@]}" -q -o "$OUT/em-stack-post-cd.png"
else
    echo "gallery: $DATA not found; real-data pictures skipped" >&2
fi
echo "gallery: written to $OUT"
