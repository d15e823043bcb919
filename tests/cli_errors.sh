#!/usr/bin/env bash
# CLI error handling: exit codes, one-line messages, no files left behind.
# Usage: bash tests/cli_errors.sh PATH_TO_VSPLAT
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/testutil.sh"
tu_setup "${1:?usage: cli_errors.sh PATH_TO_VSPLAT}"
mkdir "$T/work"
cd "$T/work" # outputs here; logs in $T

# expect_fail CODE DESC ARGS...: exit code CODE, exactly one "vsplat: " line on stderr
expect_fail() {
    local code=$1 desc=$2
    shift 2
    run "$@"
    local lines
    lines=$(grep -c '^vsplat: ' "$T/err" || true)
    if [[ $rc -eq $code && $lines -ge 1 ]]; then
        ok
    else
        bad "$desc: expected exit $code with a message, got exit $rc; stderr: $(head -c 300 "$T/err")"
    fi
}

SCENE=(--scene sphere:24 --size 64x64 --pipeline raycast -q)

# usage
expect_fail 1 "no arguments"
expect_fail 1 "unknown command" frobnicate
expect_err "frobnicate" "unknown command named"
expect_fail 1 "unknown option" render "${SCENE[@]}" --frobnicate -o a.png
expect_err "--frobnicate" "unknown option named"
expect_fail 1 "missing value" render "${SCENE[@]}" -o a.png --zoom
expect_err "--zoom" "missing value names the option"
expect_fail 1 "no output" render "${SCENE[@]}"
expect_fail 1 "no input" render --size 64x64 -o a.png
expect_fail 1 "two inputs" render a.nii b.nii -o a.png
expect_fail 1 "file and scene" render a.nii "${SCENE[@]}" -o a.png

# input files
expect_fail 1 "missing input file" render "$T/no-such-volume.nii" -o a.png
expect_err "no-such-volume.nii" "missing input names the file"
expect_fail 1 "info on a missing file" info "$T/no-such-volume.nii"
expect_err "no-such-volume.nii" "info on a missing file names the file"
printf '\x01\x02\x03' >short.raw
expect_fail 1 "truncated raw" render short.raw --dims 4,4,4 --type u8 -o a.png
expect_err "short.raw" "truncated raw names the file"
expect_fail 1 "--dims without --type" info short.raw --dims 4,4,4
expect_fail 1 "bad --type" info short.raw --dims 1,1,3 --type u12
expect_fail 1 "bad --dims" info short.raw --dims 1,0,3 --type u8
expect_fail 1 "bad --endian" info short.raw --dims 1,1,3 --type u8 --endian middle

# option values
for v in abc 0x10 64x 64x0 99999x64 64x64x2 -64x64 64.5x64 "" ; do
    expect_fail 1 "bad --size '$v'" render "${SCENE[@]}" --size "$v" -o a.png
done
expect_err "--size" "bad --size names the option"
expect_fail 1 "bad --pipeline" render "${SCENE[@]}" --pipeline fancy -o a.png
expect_err "--pipeline" "bad --pipeline names the option"
expect_fail 1 "--iso 5:3" render "${SCENE[@]}" --iso 5:3 -o a.png
expect_err "--iso" "empty iso-range names the option"
expect_fail 1 "--iso abc" render "${SCENE[@]}" --iso abc -o a.png
expect_fail 1 "--iso nan" render "${SCENE[@]}" --iso nan -o a.png
expect_fail 1 "--zoom abc" render "${SCENE[@]}" --zoom abc -o a.png
expect_fail 1 "--zoom 0" render "${SCENE[@]}" --zoom 0 -o a.png
expect_fail 1 "--zoom 1e999" render "${SCENE[@]}" --zoom 1e999 -o a.png
expect_fail 1 "--perspective 180" render "${SCENE[@]}" --perspective 180 -o a.png
expect_fail 1 "--perspective -5" render "${SCENE[@]}" --perspective -5 -o a.png
expect_fail 1 "--perspective nan" render "${SCENE[@]}" --perspective nan -o a.png
expect_fail 1 "--ramp -1" render "${SCENE[@]}" --ramp -1 -o a.png
expect_fail 1 "--opacity 2" render "${SCENE[@]}" --opacity 2 -o a.png
expect_fail 1 "--threads -1" render "${SCENE[@]}" --threads -1 -o a.png
expect_fail 1 "--threads 2.5" render "${SCENE[@]}" --threads 2.5 -o a.png
expect_fail 1 "--threads 1000" render "${SCENE[@]}" --threads 1000 -o a.png
expect_err "--threads" "too many threads names the option"
expect_fail 1 "--tile-size 4" render "${SCENE[@]}" --tile-size 4 -o a.png
expect_err "--tile-size" "a tile size below 8 names the option"
expect_fail 1 "--trace = output" render "${SCENE[@]}" --trace a.png -o a.png
expect_err "--trace" "a trace over the output image names the option"
expect_fail 1 "--isa mmx" render "${SCENE[@]}" --isa mmx -o a.png
expect_fail 1 "--resample sometimes" render "${SCENE[@]}" --resample sometimes -o a.png
expect_err "--resample" "a bad --resample names the option"
expect_fail 1 "--cd-stencil 3" render "${SCENE[@]}" --cd-stencil 3 -o a.png
expect_err "--cd-stencil" "a bad --cd-stencil names the option"
expect_fail 1 "--view 1" render "${SCENE[@]}" --view 1 -o a.png
expect_fail 1 "--view 0,1e7" render "${SCENE[@]}" --view 0,1e7 -o a.png
expect_fail 1 "--material 1,1" render "${SCENE[@]}" --material 1,1 -o a.png
expect_fail 1 "--background 0,0,0,2" render "${SCENE[@]}" --background 0,0,0,2 -o a.png
expect_fail 1 "--light 0,0,0" render "${SCENE[@]}" --light 0,0,0 -o a.png
expect_fail 1 "--slab 0" render "${SCENE[@]}" --slab 0 -o a.png
expect_fail 1 "--bits 12" render "${SCENE[@]}" --bits 12 -o a.png
expect_fail 1 "--no-pin=1" render "${SCENE[@]}" --no-pin=1 -o a.png
expect_fail 1 "--tf" render "${SCENE[@]}" --tf tf.txt -o a.png
expect_err "tf.txt: cannot open" "--tf on a missing file names it"
VSPLAT_THREADS=lots expect_fail 1 "bad VSPLAT_THREADS" render "${SCENE[@]}" -o a.png
expect_err "VSPLAT_THREADS" "bad VSPLAT_THREADS names the variable"
VSPLAT_ISA=mmx expect_fail 1 "bad VSPLAT_ISA" render "${SCENE[@]}" -o a.png

# outputs
expect_fail 1 "unknown output extension" render "${SCENE[@]}" -o a.bmp
expect_err "a.bmp" "unknown extension names the file"
expect_fail 1 "no output extension" render "${SCENE[@]}" -o a
expect_fail 1 "unwritable output" render "${SCENE[@]}" -o /nonexistent/x.png
expect_err "/nonexistent/x.png" "unwritable output names the file"
if [[ -e /nonexistent/x.png ]]; then bad "unwritable output left a file"; else ok; fi
expect_fail 1 "unwritable stats" render "${SCENE[@]}" --stats /nonexistent/s.json -o b.png
if [[ -e b.png ]]; then bad "failed render (stats) left b.png"; else ok; fi

# compare
run render "${SCENE[@]}" -o small.png
if [[ $rc -eq 0 ]]; then ok; else bad "render small.png: exit $rc: $(cat "$T/err")"; fi
run render --scene sphere:24 --size 32x48 --pipeline raycast -q -o other.png
if [[ $rc -eq 0 ]]; then ok; else bad "render other.png: exit $rc: $(cat "$T/err")"; fi
expect_fail 1 "compare different sizes" compare small.png other.png
expect_fail 1 "compare missing image" compare small.png missing.png
expect_err "missing.png" "compare names the missing image"
echo "not an image" >junk.png
expect_fail 1 "compare junk image" compare small.png junk.png
expect_fail 1 "compare one argument" compare small.png

# nothing but our own files may be in the work folder
left=
shopt -s nullglob dotglob
for f in *; do
    case $f in short.raw | small.png | other.png | junk.png) ;; *) left="$left $f" ;; esac
done
shopt -u nullglob dotglob
if [[ -z $left ]]; then ok; else bad "files left behind: $left"; fi

tu_done
