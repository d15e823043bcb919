#!/usr/bin/env bash
# Orientation and views on the command line: `info` says which way a volume
# lies, named views equal their angles, --up/--roll, the default view, the
# notes for what a file does not say, option errors, slice folders that are
# not one series, and progress on a terminal.
# Usage: bash tests/cli_orient.sh PATH_TO_VSPLAT
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/testutil.sh"
tu_setup "${1:?usage: cli_orient.sh PATH_TO_VSPLAT}"
DATA=${VSPLAT_DATA:-$(cd "${VSPLAT_SOURCE_DIR:-$(dirname "${BASH_SOURCE[0]}")/..}" && pwd)/../shared/data}
mkdir "$T/work"
cd "$T/work"

# same PATH_A PATH_B DESC: the two images are identical
same() {
    run compare "$1" "$2"
    if [[ $rc -eq 0 ]] && grep -q 'max=0$' "$T/out"; then ok; else bad "$3: $(cat "$T/out" "$T/err")"; fi
}
# differ PATH_A PATH_B DESC: the two images differ
differ() {
    run compare "$1" "$2"
    if [[ $rc -eq 0 ]] && ! grep -q 'max=0$' "$T/out"; then ok; else bad "$3: $(cat "$T/out" "$T/err")"; fi
}
# fails DESC REGEX ARGS...: exit 1 and the message matches
fails() {
    local desc=$1 re=$2
    shift 2
    run "$@"
    if [[ $rc -eq 1 ]] && grep -Eq -- "$re" "$T/err"; then ok; else bad "$desc: exit $rc; stderr: $(head -c 300 "$T/err")"; fi
}

# An asymmetric 12x10x8 u8 volume (a bright block near one corner, a dimmer
# bar and a plate), make_volume FX FY writes it with x (FX=1) and y (FY=1)
# reversed.  lps.nrrd: LPS space, index x to the left and y to posterior;
# ras.nrrd: the same anatomy stored the other way round in RAS space.
make_volume() {
    local x y z i j
    for ((z = 0; z < 8; z++)); do
        for ((j = 0; j < 10; j++)); do
            for ((i = 0; i < 12; i++)); do
                x=$(($1 ? 11 - i : i)) y=$(($2 ? 9 - j : j))
                if ((x >= 2 && x <= 5 && y >= 2 && y <= 4 && z >= 2 && z <= 5)); then printf '\310'
                elif ((y >= 5 && y <= 7 && z >= 3 && z <= 4 && x >= 2 && x <= 9)); then printf '\200'
                elif ((x >= 6 && x <= 8 && y >= 2 && y <= 7 && z == 6)); then printf '\144'
                else printf '\000'; fi
            done
        done
    done
}
make_volume 0 0 >vol_12x10x8_u8.raw
make_volume 1 1 >flipped.raw
nrrd() { # NAME SPACE DIRECTIONS ORIGIN DATA
    {
        printf 'NRRD0004\ntype: uchar\ndimension: 3\nspace: %s\nsizes: 12 10 8\n' "$2"
        printf 'space directions: %s\nspace origin: %s\nencoding: raw\n\n' "$3" "$4"
        cat "$5"
    } >"$1"
}
nrrd lps.nrrd left-posterior-superior '(1,0,0) (0,1.5,0) (0,0,2)' '(10,20,-30)' vol_12x10x8_u8.raw
nrrd ras.nrrd right-anterior-superior '(1,0,0) (0,1.5,0) (0,0,2)' '(-21,-33.5,-30)' flipped.raw
nrrd air.nrrd right-anterior-superior '(0,1.5,0) (0,0,-2) (1,0,0)' '(0,0,0)' vol_12x10x8_u8.raw
nrrd scanner.nrrd scanner-xyz '(1,0,0) (0,1.5,0) (0,0,2)' '(0,0,0)' vol_12x10x8_u8.raw

# info: the orientation code and the transform (LPS converted to RAS)
expect_ok "info lps" info lps.nrrd
expect_out '^orientation: LPS$' "LPS directions (1,0,0) (0,1.5,0) are RAS -x, -y"
expect_out '^transform: -1 0 0 -10; 0 -1.5 0 -20; 0 0 2 -30$' "transform in RAS"
expect_ok "info ras" info ras.nrrd
expect_out '^orientation: RAS$' "RAS"
expect_out '^spacing: 1 1.5 2$' "spacing from the directions"
expect_ok "info permuted" info air.nrrd
expect_out '^orientation: AIR$' "permuted axes"
expect_ok "info raw" info vol_12x10x8_u8.raw
expect_out '^orientation: none \(assumed RAS' "raw: no orientation"
expect_err 'note: .*no orientation' "raw: orientation note"
expect_err 'note: .*no voxel spacing.*1,1,1.*--spacing' "raw: spacing note"
expect_ok "info raw with spacing" info vol_12x10x8_u8.raw --spacing 1,1.5,2
if grep -q 'no voxel spacing' "$T/err"; then bad "--spacing given, spacing note anyway"; else ok; fi
expect_ok "info scanner-xyz" info scanner.nrrd
expect_out '^orientation: none' "a scanner-xyz space is no anatomy"

R=(--iso 60 --ramp 20 --size 48x40 -q)
# the same anatomy stored two ways renders the same (ray caster: exact)
for p in post-cd raycast; do
    expect_ok "lps $p" render lps.nrrd "${R[@]}" --pipeline $p --view 30,20 -o lps-$p.png
    expect_ok "ras $p" render ras.nrrd "${R[@]}" --pipeline $p --view 30,20 -o ras-$p.png
    run compare lps-$p.png ras-$p.png
    psnr=$(sed -n 's/.*psnr=\([^ ]*\).*/\1/p' "$T/out")
    if [[ $psnr == inf ]] || awk "BEGIN{exit !($psnr >= 45)}"; then ok; else bad "$p: LPS vs RAS storage $psnr dB"; fi
done
expect_ok "raw as stored" render vol_12x10x8_u8.raw --spacing 1,1.5,2 "${R[@]}" --view 30,20 -o raw.png
differ raw.png lps-post-cd.png "the LPS file renders differently from its voxels without the transform"

# named views are angle pairs; the default view of an oriented volume is anterior
view() { expect_ok "$1" render ras.nrrd "${R[@]}" "${@:2}" -o "$1.png"; }
view default
view anterior --view anterior
view a180 --view 180,0
view left --view left
view l270 --view 270,0
view superior --view superior
view s090 --view 0,90
view inferior --view Inferior
view i180 --view 180,-90
view posterior --view posterior
view p000 --view 0,0
same default.png anterior.png "default view of an oriented volume = anterior"
same anterior.png a180.png "--view anterior = 180,0"
same left.png l270.png "--view left = 270,0"
same superior.png s090.png "--view superior = 0,90"
same inferior.png i180.png "--view inferior = 180,-90"
same posterior.png p000.png "--view posterior = 0,0"
differ anterior.png posterior.png "anterior and posterior differ"
# a turntable without --view turns from the front: frame 1 of 4 is the left view
expect_ok "turntable" render ras.nrrd "${R[@]}" --turntable 4 -o tt.png
same tt_0000.png anterior.png "turntable frame 0 = anterior"
same tt_0001.png left.png "turntable frame 1 of 4 = left"
# upright and upside down: 180,180 is allowed and is 0,0 rolled; --up says the same
view upside --view 180,180
view roll180 --view 0,0 --roll 180
view updown --view 0,0 --up 0,0,-1
same upside.png roll180.png "--view 180,180 = --roll 180"
same updown.png roll180.png "--up 0,0,-1 = --roll 180"
differ upside.png p000.png "--roll 180 turns the picture"
view sup_up_r --view superior --up 1,0,0
view sup_roll --view superior --roll -90
same sup_up_r.png sup_roll.png "superior with +x up = rolled 90 counter-clockwise"
# an unoriented volume keeps 0,0 as its default
expect_ok "raw default" render vol_12x10x8_u8.raw "${R[@]}" -o rawdef.png
expect_ok "raw 0,0" render vol_12x10x8_u8.raw "${R[@]}" --view 0,0 -o raw00.png
same rawdef.png raw00.png "unoriented default = 0,0"

# option errors name the option
fails "bad view name" '--view:.*anterior' render ras.nrrd "${R[@]}" --view sideways -o x.png
fails "bad view angles" '--view' render ras.nrrd "${R[@]}" --view 1,2,3 -o x.png
fails "zero up" '--up:' render ras.nrrd "${R[@]}" --up 0,0,0 -o x.png
fails "bad up" '--up:' render ras.nrrd "${R[@]}" --up 1,x,0 -o x.png
fails "bad roll" '--roll:' render ras.nrrd "${R[@]}" --roll abc -o x.png
fails "up along the view" 'up vector' render ras.nrrd "${R[@]}" --view anterior --up 0,1,0 -o x.png
fails "threads 1000" '^vsplat: --threads: 1000' render ras.nrrd "${R[@]}" --threads 1000 -o x.png
if [[ -e x.png ]]; then bad "an error left x.png"; else ok; fi

# notes: iso below and above the data, geometry of raw input; -q silences them
expect_ok "iso below" render ras.nrrd --iso -50 --ramp 10 --size 16x16 -o x.png
expect_err 'note: iso-range -50:inf .*whole data range' "iso below the data: note"
expect_ok "iso above" render ras.nrrd --iso 300 --ramp 10 --size 16x16 -o x.png
expect_err 'note: iso-range 300:inf lies outside' "iso above the data: note"
expect_ok "raw notes" render vol_12x10x8_u8.raw --size 16x16 -o x.png
expect_err 'note: .*no orientation' "render raw: orientation note"
expect_err 'note: .*no voxel spacing' "render raw: spacing note"
expect_ok "oriented: no notes" render ras.nrrd --size 16x16 -o x.png
if grep -q 'note:' "$T/err"; then bad "oriented NRRD got a note: $(cat "$T/err")"; else ok; fi
expect_ok "quiet" render vol_12x10x8_u8.raw --size 16x16 -q -o x.png
if [[ -s $T/err ]]; then bad "-q printed: $(cat "$T/err")"; else ok; fi

# the raw naming rule is documented in --help
expect_ok "help" render --help
expect_out 'NAME_XxYxZ_TYPE' "render --help gives the raw naming rule"

# a folder that is not one slice series: an error in words
mkdir mixed
expect_ok "slice 8-bit" render --scene sphere:8 --size 16x16 -q -o mixed/a1.png
expect_ok "slice 16-bit" render --scene sphere:8 --size 16x16 -q --bits 16 -o mixed/a2.png
fails "mixed folder" 'not one slice series: slice 2 \(a2.png\) is 16x16 16-bit, but the first slice is 16x16 8-bit' \
    render mixed --size 16x16 -o x.png
stack=$DATA/snt_spotspine_confocal_dendrite_116x157x41_u8.tif
if [[ -f $stack ]]; then
    mkdir pages
    cp "$stack" pages/
    fails "folder with a multi-page TIFF" 'not one slice series: .*several pages' render pages --size 16x16 -o x.png
else
    echo "SKIP: multi-page folder case ($stack absent)"
fi

# progress: on a terminal (script gives one) after a second; not with -q, not in a file
if command -v script >/dev/null; then
    # about 2 s of work on one core (a second more than the threshold)
    slow=(render --scene head:64 --pipeline raycast --no-analytic --ray-step 0.02 --size 256x256 --threads 1)
    set +e
    script -qec "'$VSPLAT' ${slow[*]} -o slow.png" /dev/null >tty.log 2>&1
    set -e
    if grep -Eq 'rendering +[0-9]+%' tty.log; then ok; else bad "no progress on a terminal: $(head -c 300 tty.log)"; fi
    set +e
    script -qec "'$VSPLAT' ${slow[*]} -q -o slow.png" /dev/null >tty-q.log 2>&1
    set -e
    if grep -q 'rendering' tty-q.log; then bad "progress despite -q"; else ok; fi
    run "${slow[@]}" -o slow.png
    if grep -q 'rendering' "$T/err"; then bad "progress into a file"; else ok; fi
else
    echo "SKIP: progress cases (no script command)"
fi

tu_done
