#!/usr/bin/env bash
# What the sanitizers cannot see inside Teem and OpenImageIO (issue 24),
# under valgrind memcheck: `vsplat info` on every NRRD fuzz reproducer
# (Teem's header parser leaked on several), on truncated deflate TIFFs as
# a file and as a tar member (OIIO inflated the cut strips from
# uninitialised memory), on TIFFs OIIO returned partly undecoded (unknown
# predictor or compression, a deflate strip too short for its rows) and on
# the valid TIFF seed.  Each must exit as
# expected with no memcheck error and no definitely lost block.  Skipped
# without valgrind and in sanitizer builds (VSPLAT_SANITIZED=1).
# Usage: bash tests/cli_valgrind.sh PATH_TO_VSPLAT
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/testutil.sh"
tu_setup "${1:?usage: cli_valgrind.sh PATH_TO_VSPLAT}"
SRC=${VSPLAT_SOURCE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}
if ! command -v valgrind >/dev/null; then
    echo "SKIP: valgrind is not installed (tools/install-deps.sh installs it)"
    exit 0
fi
if [[ ${VSPLAT_SANITIZED:-0} == 1 ]]; then
    echo "SKIP: sanitizer build (valgrind cannot run it; LSan checks the same inputs there)"
    exit 0
fi

# vg WANT_RC FILE: vsplat info FILE under memcheck exits WANT_RC, no errors
vg() {
    local want=$1 f=$2
    set +e
    valgrind -q --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite \
        --show-leak-kinds=definite "$VSPLAT" info "$f" >"$T/out" 2>"$T/err"
    rc=$?
    set -e
    if [[ $rc -eq 99 ]] || grep -q '^==[0-9]*== ' "$T/err"; then
        bad "$(basename "$f"): memcheck: $(grep -m12 '^==' "$T/err" | tr '\n' '|' | head -c 1200)"
    elif [[ $rc -ne $want ]]; then
        bad "$(basename "$f"): exit $rc, expected $want: $(head -c 300 "$T/err")"
    else
        ok
    fi
}

# NRRD reproducers: a .nrrd suffix for the loader to dispatch on
for f in "$SRC"/tests/fuzz/regressions/nrrd/*; do
    cp "$f" "$T/in.nrrd"
    set +e
    "$VSPLAT" info "$T/in.nrrd" >/dev/null 2>&1
    want=$?
    set -e
    vg "$want" "$T/in.nrrd"
done
# OpenImageIO loads Highway, whose initialiser reads the time-stamp counter
# with RDTSCP.  Where the CPU runs RDTSCP but its CPUID does not list it
# (some virtual machines), valgrind refuses the instruction: SIGILL in
# libhwy before any of vsplat's code runs.  The TIFF cases cannot run
# under memcheck there; the ASan+UBSan suite still reads these files.
set +e
valgrind -q "$VSPLAT" info "$SRC/tests/fuzz/seeds/stack/u16_2pages.tif" >/dev/null 2>"$T/probe"
set -e
if grep -q 'Illegal opcode' "$T/probe" && grep -q 'libhwy' "$T/probe"; then
    echo "SKIP (TIFF cases only): valgrind cannot execute libhwy's RDTSCP on this CPU (CPUID hides it)"
else
    vg 1 "$SRC/tests/fuzz/regressions/stack/truncated-deflate-strips.tif"
    for f in "$SRC"/tests/fuzz/regressions/stack/uninit-*.tif; do vg 1 "$f"; done
    vg 1 "$SRC/tests/fuzz/regressions/tar/truncated-deflate-strips.tar"
    vg 0 "$SRC/tests/fuzz/seeds/stack/u16_2pages.tif"
fi
tu_done
