#!/usr/bin/env bash
# Build vsplat, then render the Colin27 MRI head (skin: iso 45, ramp 10, seen
# from the front) with the post-classified central-difference pipeline: tools/demo.sh [OUT.png]
# (build folder: $VSPLAT_BUILD_DIR, default build/)
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
OUT=${1:-$ROOT/demo.png}
HEAD=/usr/share/mricron/templates/ch2.nii.gz

BUILD=${VSPLAT_BUILD_DIR:-$ROOT/build}

"$ROOT/tools/build.sh" "$BUILD"
"$ROOT/tools/python-user-site.sh" "$BUILD" # python3 -c "import vsplat" works from now on
VSPLAT=$BUILD/vsplat

if [[ -f $HEAD ]]; then
    INPUT=("$HEAD" --iso 45 --ramp 10)
    what="the Colin27 MRI head ($HEAD), skin at iso 45"
else
    echo "demo: $HEAD is missing (package mricron-data); rendering the synthetic --scene head instead" >&2
    INPUT=(--scene head)
    what="the synthetic Shepp-Logan head (--scene head)"
fi

"$VSPLAT" render "${INPUT[@]}" --pipeline post-cd --view 180,0 --size 512x512 --print-stats -o "$OUT"
echo "demo: rendered $what"
echo "demo: image written to $OUT"
