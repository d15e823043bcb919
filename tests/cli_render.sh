#!/usr/bin/env bash
# CLI end to end: render, --stats, --print-stats, info, compare, --version, --help.
# Usage: bash tests/cli_render.sh PATH_TO_VSPLAT
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/testutil.sh"
tu_setup "${1:?usage: cli_render.sh PATH_TO_VSPLAT}"
mkdir "$T/work"
cd "$T/work" # outputs here; logs in $T

SCENE=(--scene sphere:24 --size 64x64 --pipeline raycast)

# version and help
expect_ok "--version" --version
expect_out '^vsplat [0-9]+\.[0-9]+\.[0-9]+$' "--version"
expect_ok "--help" --help
expect_out "render" "--help mentions render"
expect_ok "render --help" render --help
for opt in --scene --pipeline --iso --ramp --opacity --material --background --tf --size --view \
    --zoom --perspective --center --slab --kernel-radius --footprint-res --seam --threads --isa --no-pin \
    --no-occlusion --occlusion-threshold --no-tiles --tile-size --exact-normals --normal-lut --no-preintegration \
    --lod --no-lod --resample \
    --ray-step --trilinear --no-analytic --ray-normalize --light --ambient --diffuse --specular --shininess \
    --dims --type --spacing --endian --bits --stats --print-stats -q; do
    if grep -q -- "$opt\b" "$T/out"; then ok; else bad "render --help does not list $opt"; fi
done

# a small render, with stats
expect_ok "render png" render "${SCENE[@]}" --stats s.json -o a.png
expect_file a.png "render png"
expect_file s.json "--stats"
expect_err "a.png" "summary names the output"
KEYS=(pipeline isa threads width height voxels_total voxels_relevant voxels_splatted voxels_culled
    sheets tiles_total tiles_shaded ms_total ms_stage setup rasterize gradient shade composite
    ms_relevant iso_lo iso_hi ramp pin_warning version)
if command -v python3 >/dev/null; then
    if python3 - s.json "${KEYS[@]}" <<'PY'; then ok; else bad "--stats JSON is invalid or lacks keys: $(cat s.json)"; fi
import json, sys
d = json.load(open(sys.argv[1]))
stage = ("setup", "rasterize", "gradient", "shade", "composite")
missing = [k for k in sys.argv[2:] if k not in stage and k not in d]
missing += [k for k in stage if k not in d.get("ms_stage", {})]
assert not missing, missing
assert d["width"] == 64 and d["height"] == 64, (d["width"], d["height"])
assert d["pipeline"] == "raycast", d["pipeline"]
PY
else
    for k in "${KEYS[@]}"; do
        if grep -q "\"$k\":" s.json; then ok; else bad "--stats JSON lacks \"$k\""; fi
    done
fi

# --stats -: the same JSON on stdout, no file named "-"
expect_ok "render --stats -" render "${SCENE[@]}" -q --stats - -o c.png
if [[ ! -e - ]]; then ok; else bad "--stats - wrote a file named '-'"; fi
if command -v python3 >/dev/null; then
    if python3 -c 'import json, sys; d = json.load(open(sys.argv[1])); assert d["width"] == 64, d' "$T/out"; then
        ok
    else
        bad "--stats - did not print the JSON on stdout: $(cat "$T/out")"
    fi
else
    expect_out '"ms_stage"' "--stats - prints the JSON"
fi

# -q and --print-stats
expect_ok "render -q --print-stats" render "${SCENE[@]}" -q --print-stats -o b.png
if [[ ! -s $T/err ]]; then ok; else bad "-q still printed: $(cat "$T/err")"; fi
for s in setup rasterize gradient shade composite total; do expect_out "$s" "--print-stats row $s"; done

# other formats and options
expect_ok "render exr" render "${SCENE[@]}" -q -o a.exr
expect_file a.exr "render exr"
expect_ok "render tiff" render "${SCENE[@]}" -q -o a.tiff
expect_file a.tiff "render tiff"
expect_ok "render 16-bit png" render "${SCENE[@]}" -q --bits 16 -o a16.png
expect_file a16.png "render 16-bit png"
expect_ok "render with many options" render "${SCENE[@]}" -q --view 30,20 --zoom 0.7 --iso 0.5 --ramp 0.1 \
    --opacity 0.9 --material 1,0.8,0.6 --background 0,0,0.2,1 --light 1,1,1 --ambient 0.1 --diffuse 0.8 \
    --specular 0.2 --shininess 30 --threads 2 --isa scalar --no-pin --ray-step 0.2 --trilinear -o opts.png
expect_file opts.png "render with many options"
for p in post-cd raycast; do
    expect_ok "perspective $p" render "${SCENE[@]}" -q --perspective 45 --pipeline $p -o persp-$p.png
    expect_file persp-$p.png "perspective $p"
done
VSPLAT_THREADS=1 VSPLAT_ISA=scalar expect_ok "env defaults" render "${SCENE[@]}" -q --stats env.json -o env.png
if grep -Eq '"threads": *1\b' env.json; then ok; else bad "VSPLAT_THREADS=1 not used: $(grep threads env.json)"; fi

# iso-range outside the data: still an image, exit 0, and a note
expect_ok "--iso 1e9" render "${SCENE[@]}" --iso 1e9 -o blank.png
expect_file blank.png "--iso 1e9"
expect_err "note" "--iso 1e9 prints a note"

# every pipeline renders something (not the blank image) and names itself in the stats
for p in pre post-cd post-gs post-alpha raycast; do
    expect_ok "render --pipeline $p" render --scene sphere:24 --size 64x64 --pipeline "$p" -q --stats "$p.json" -o "$p.png"
    expect_file "$p.png" "render --pipeline $p"
    if grep -Eq "\"pipeline\": *\"$p\"" "$p.json"; then ok; else bad "$p: stats name another pipeline"; fi
    run compare blank.png "$p.png"
    max=$(sed -n 's/.*max=\([^ ]*\)$/\1/p' "$T/out")
    if [[ $rc -eq 0 ]] && awk -v m="$max" 'BEGIN { exit !(m > 0.1) }'; then ok; else bad "$p: image is blank (max=$max)"; fi
done

# compare
expect_ok "compare identical" compare a.png a.png
expect_out '^rmse=[^ ]+ psnr=[^ ]+ ssim=[^ ]+ max=[^ ]+$' "compare format"
expect_out 'max=0$' "compare identical: max=0"
expect_out 'psnr=inf ' "compare identical: psnr=inf"
if [[ $(wc -l <"$T/out") -eq 1 ]]; then ok; else bad "compare prints more than one line"; fi
expect_ok "render red background" render "${SCENE[@]}" -q --background 1,0,0,1 -o red.png
expect_ok "compare different" compare a.png red.png
max=$(sed -n 's/.*max=\([^ ]*\)$/\1/p' "$T/out")
if awk -v m="$max" 'BEGIN { exit !(m > 0) }'; then ok; else bad "compare different: max=$max"; fi

# info on a raw file written here: 4x3x2 u8
printf '\x00\x01\x02\x03\x04\x05\x06\x07\x08\x09\x0a\x0b\x0c\x0d\x0e\x0f\x10\x11\x12\x13\x14\x15\x16\x64' >v.raw
expect_ok "info raw" info v.raw --dims 4,3,2 --type u8 --spacing 1,1,2.5
expect_out '^dims: 4 3 2$' "info dims"
expect_out '^type: u8$' "info type"
expect_out '^spacing: 1 1 2.5$' "info spacing"
expect_out '^range: 0 100$' "info range"
expect_out '^voxels: 24$' "info voxels"
expect_out '^default_iso: ' "info default_iso"
# 16-bit big-endian: values 1 and 258
printf '\x00\x01\x01\x02' >w.raw
expect_ok "info raw u16 big-endian" info w.raw --dims 2,1,1 --type u16 --endian big
expect_out '^range: 1 258$' "info big-endian range"
expect_ok "render raw" render v.raw --dims 4,3,2 --type u8 --iso 50 --size 32x32 --pipeline raycast -q -o raw.png
expect_file raw.png "render raw"

tu_done
