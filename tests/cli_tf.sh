#!/usr/bin/env bash
# CLI --tf (every shipped preset format, malformed files) and --turntable
# (PNG sequence, animated GIF with N subimages).
# Usage: bash tests/cli_tf.sh PATH_TO_VSPLAT   (VSPLAT_SOURCE_DIR: the source tree)
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/testutil.sh"
tu_setup "${1:?usage: cli_tf.sh PATH_TO_VSPLAT}"
SRC=${VSPLAT_SOURCE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}
TF=$SRC/tools/tf
mkdir "$T/work"
cd "$T/work"

expect_fail() { # desc, stderr regex, args...
    local desc=$1 re=$2
    shift 2
    run "$@"
    if [[ $rc -eq 1 ]]; then ok; else bad "$desc: exit $rc (expected 1)"; fi
    expect_err "$re" "$desc"
    if [[ $(wc -l <"$T/err") -eq 1 ]]; then ok; else bad "$desc: more than one line on stderr"; fi
}
not_blank() { # image, desc: differs from a transparent image of the same size
    run compare "$1" "$2"
    local max
    max=$(sed -n 's/.*max=\([^ ]*\)$/\1/p' "$T/out")
    if [[ $rc -eq 0 ]] && awk -v m="$max" 'BEGIN { exit !(m > 0.05) }'; then ok; else bad "$3: image is blank (max=$max)"; fi
}

S=(--scene sphere:24 --size 48x48 -q)
expect_ok "blank reference" render "${S[@]}" --iso 1e9 -o blank.png

# --- shipped presets: every format, on a small scene ---
# sphere values are 0..1; the .vtf and .json presets are in data units of their
# volumes, so write scene-sized files in each format too.
cat >sphere.vtf <<'V'
# shell semi-transparent, core opaque
iso 0.2 0.4 0.9 0.6 0.5 0.1 0.05
iso 0.6 inf 1 1 1 1 0.05
V
cat >sphere.json <<'J'
[{"Name": "sphere", "ColorSpace": "RGB",
  "RGBPoints": [0, 0, 0, 1,  1, 1, 0.5, 0],
  "Points": [0, 0, 0.5, 0,  0.4, 0, 0.5, 0,  0.6, 1, 0.5, 0,  1, 1, 0.5, 0]}]
J
printf '4\n0 0 0 0\n0.2 0.2 1 0.05\n1 0.5 0 0.9\n1 1 1 1\n' >sphere.1dt
for f in sphere.vtf sphere.json sphere.1dt; do
    expect_ok "--tf $f" render "${S[@]}" --tf "$f" -o "tf-${f%.*}-${f##*.}.png"
    expect_file "tf-${f%.*}-${f##*.}.png" "--tf $f"
    not_blank blank.png "tf-${f%.*}-${f##*.}.png" "--tf $f"
done
# --tf really changes the image (a green material vs the default white)
expect_ok "iso render" render "${S[@]}" --iso 0.5 -o iso.png
run compare iso.png tf-sphere-vtf.png
max=$(sed -n 's/.*max=\([^ ]*\)$/\1/p' "$T/out")
if awk -v m="$max" 'BEGIN { exit !(m > 0.05) }'; then ok; else bad "--tf image equals the iso image"; fi
# the shipped presets load and render (on the small scene, values outside
# their range: the image may be blank, but the file must be accepted)
for f in "$TF"/*; do
    expect_ok "preset $(basename "$f")" render "${S[@]}" --tf "$f" -o "preset-$(basename "$f").png"
done
# the Colin27 preset on the real head, if the data is here (small image)
DATA=${VSPLAT_DATA:-$SRC/../shared/data}
C=$DATA/colin27_ch2_mri_t1_head_181x217x181_u8.nii.gz
if [[ -f $C ]]; then
    expect_ok "colin27 preset" render "$C" --tf "$TF/colin27-skin-brain.vtf" --size 64x64 --view 120,15 -q -o colin.png
    expect_ok "colin27 blank" render "$C" --iso 1e9 --size 64x64 -q -o colin-blank.png
    not_blank colin-blank.png colin.png "colin27 preset"
else
    echo "note: $C not found; real-data preset render skipped"
fi

# --- malformed transfer functions: exit 1, one line naming the file ---
printf '{"RGBPoints": [0, 0, 0' >trunc.json
expect_fail "truncated json" "trunc.json: line 1" render "${S[@]}" --tf trunc.json -o x.png
printf '{"RGBPoints": [0, 0, 2, 0]}' >range.json
expect_fail "colour out of range" "range.json: .*outside \[0,1\]" render "${S[@]}" --tf range.json -o x.png
printf '1e12\n0 0 0 0\n' >huge.1dt
expect_fail "huge .1dt" "huge.1dt: line 1: entry count" render "${S[@]}" --tf huge.1dt -o x.png
printf '3\n0 0 0 0\n' >short.1dt
expect_fail "short .1dt" "short.1dt: .*promises 3" render "${S[@]}" --tf short.1dt -o x.png
printf 'iso 1 2 3\n' >bad.vtf
expect_fail "bad .vtf" "bad.vtf: line 1" render "${S[@]}" --tf bad.vtf -o x.png
expect_fail "missing tf" "nope.vtf: cannot open" render "${S[@]}" --tf nope.vtf -o x.png
expect_fail "--tf with --iso" "replaces --iso" render "${S[@]}" --tf sphere.vtf --iso 0.5 -o x.png
expect_fail "--tf empty" "--tf: expected a file name" render "${S[@]}" --tf "" -o x.png
if [[ ! -e x.png ]]; then ok; else bad "a failed render left x.png"; fi

# --- turntable: PNG sequence ---
expect_ok "turntable png" render --scene cube --size 40x32 --pipeline raycast -q --turntable 5 --view 10,20 \
    --stats tt.json -o spin.png
n=$(ls spin_*.png 2>/dev/null | wc -l)
if [[ $n -eq 5 ]]; then ok; else bad "turntable png: $n frames, expected 5: $(ls)"; fi
for f in 0000 0001 0002 0003 0004; do
    if [[ -s spin_$f.png ]]; then ok; else bad "spin_$f.png missing"; fi
done
if [[ ! -e spin.png && ! -e spin_0005.png ]]; then ok; else bad "turntable wrote extra files: $(ls)"; fi
expect_file tt.json "turntable --stats"
if command -v oiiotool >/dev/null; then
    for f in spin_*.png; do
        info=$(oiiotool --info "$f")
        if grep -q '40 x *32' <<<"$info"; then ok; else bad "$f: not 40x32: $info"; fi
    done
fi
# frame 0 of --turntable equals a plain render at --view; frames differ from each other
expect_ok "plain view" render --scene cube --size 40x32 --pipeline raycast -q --view 10,20 -o plain.png
expect_ok "frame 0 vs plain" compare spin_0000.png plain.png
if grep -q 'max=0$' "$T/out"; then ok; else bad "frame 0 differs from --view 10,20: $(cat "$T/out")"; fi
expect_ok "frame 2 is at azimuth 10+144" render --scene cube --size 40x32 --pipeline raycast -q --view 154,20 -o az.png
expect_ok "frame 2 vs az" compare spin_0002.png az.png
if grep -q 'max=0$' "$T/out"; then ok; else bad "frame 2 is not at azimuth 154: $(cat "$T/out")"; fi
expect_ok "frame 0 vs 1" compare spin_0000.png spin_0001.png
if grep -q 'max=0$' "$T/out"; then bad "turntable frames 0 and 1 are identical"; else ok; fi
# other formats keep their extension
expect_ok "turntable exr" render "${S[@]}" --turntable 2 -o e.exr
if [[ -s e_0000.exr && -s e_0001.exr ]]; then ok; else bad "turntable exr: $(ls e_* 2>&1)"; fi

# --- turntable: animated GIF ---
expect_ok "turntable gif" render --scene cube --size 40x32 --pipeline raycast --turntable 6 --fps 12 -o spin.gif
expect_file spin.gif "turntable gif"
if grep -q "6 frames" "$T/err"; then ok; else bad "gif summary: $(cat "$T/err")"; fi
if command -v oiiotool >/dev/null; then
    info=$(oiiotool --info -v spin.gif)
    if grep -Eq '(^|[^0-9])6 subimages' <<<"$info"; then ok; else bad "spin.gif: not 6 subimages: $info"; fi
    if grep -q '40 x *32' <<<"$info"; then ok; else bad "spin.gif: not 40x32: $info"; fi
    if grep -q 'FramesPerSecond' <<<"$info"; then ok; else bad "spin.gif: no FramesPerSecond: $info"; fi
else
    echo "note: oiiotool not found; GIF subimage count not checked"
fi
expect_ok "single gif" render "${S[@]}" -o one.gif
expect_file one.gif "single gif"
expect_fail "--bits 16 gif" "GIF output is 8-bit" render "${S[@]}" --bits 16 -o x.gif
expect_fail "--fps without gif" "--fps applies" render "${S[@]}" --fps 10 -o x.png
expect_fail "--turntable 0" "--turntable: 0 is out of range" render "${S[@]}" --turntable 0 -o x.png
expect_fail "--turntable word" "--turntable: 'many' is not an integer" render "${S[@]}" --turntable many -o x.png
# --- vsplat-bench frame renders what vsplat renders, --tf included ---
BENCH=$(dirname "$VSPLAT")/bench/vsplat-bench
if [[ -x $BENCH ]]; then
    expect_ok "tf render" render "${S[@]}" --tf sphere.vtf -o tf-cli.png
    if "$BENCH" frame "${S[@]}" --tf sphere.vtf --frames 1 -o tf-bench.png >"$T/out" 2>"$T/err"; then ok; else
        bad "vsplat-bench frame --tf: $(cat "$T/err")"
    fi
    run compare tf-cli.png tf-bench.png
    if grep -q 'max=0$' "$T/out"; then ok; else bad "vsplat-bench frame --tf differs from vsplat render: $(cat "$T/out")"; fi
    if "$BENCH" frame "${S[@]}" --tf missing.vtf --frames 1 >"$T/out" 2>"$T/err"; then
        bad "vsplat-bench frame with a missing --tf succeeded"
    elif [[ $(wc -l <"$T/err") -eq 1 ]] && grep -q "missing.vtf" "$T/err"; then ok; else
        bad "vsplat-bench frame, missing --tf: $(cat "$T/err")"
    fi
else
    echo "note: $BENCH not built; vsplat-bench frame not checked"
fi

run render --help
for opt in --tf --turntable --fps; do
    if grep -q -- "$opt\b" "$T/out"; then ok; else bad "render --help does not list $opt"; fi
done

tu_done
