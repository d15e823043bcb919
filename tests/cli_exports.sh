#!/usr/bin/env bash
# The library boundary: libvsplat.so exports exactly the functions that
# include/vsplat.h declares (no internal symbol leaks, no declared function is
# missing), and the adapter modules vsplat-oiio.so and vsplat-dicom.so (when
# built) export only the entry point the library looks up with dlsym.
# Usage: bash tests/cli_exports.sh PATH_TO_VSPLAT   (the build folder is its folder)
set -euo pipefail

VSPLAT=${1:?usage: cli_exports.sh PATH_TO_VSPLAT}
BUILD=$(cd "$(dirname "$VSPLAT")" && pwd)
SRC=${VSPLAT_SOURCE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}
LIB=$BUILD/libvsplat.so
MOD=$BUILD/vsplat-modules/vsplat-oiio.so
if ! command -v nm >/dev/null; then
    echo "SKIP: nm not found"
    exit 0
fi
for f in "$LIB" "$MOD" "$SRC/include/vsplat.h"; do
    [[ -f $f ]] || { echo "FAIL: $f not found"; exit 1; }
done
CC=$(sed -n 's/^CMAKE_C_COMPILER:[A-Z]*=//p' "$BUILD/CMakeCache.txt" 2>/dev/null || true)
CC=${CC:-cc}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

# Symbols the static linker defines in every shared object, not the library's.
LINKER='^(_init|_fini|_edata|_end|__bss_start)$'
# defined dynamic symbols, version suffixes dropped
exports() { nm -D --defined-only "$1" | awk 'NF >= 3 {sub(/@.*/, "", $3); print $3}' | grep -Ev "$LINKER" | sort -u; }

# The declared functions: every `vs_NAME (` of the preprocessed header
# (comments and macros gone; a function-pointer typedef reads `vs_NAME)(`).
"$CC" -E -P -x c "$SRC/include/vsplat.h" >"$T/header.i"
grep -oE '\bvs_[A-Za-z0-9_]+[[:space:]]*\(' "$T/header.i" | sed -E 's/[[:space:]]*\($//' | sort -u >"$T/declared"
exports "$LIB" >"$T/exported"

failed=0
n_decl=$(wc -l <"$T/declared")
if [[ $n_decl -lt 30 ]]; then
    echo "FAIL: parsed only $n_decl declarations from include/vsplat.h"
    failed=1
fi
extra=$(comm -13 "$T/declared" "$T/exported")
missing=$(comm -23 "$T/declared" "$T/exported")
if [[ -n $extra ]]; then
    echo "FAIL: libvsplat.so exports $(wc -l <<<"$extra") symbols include/vsplat.h does not declare:"
    sed 's/^/  /' <<<"$extra"
    failed=1
fi
if [[ -n $missing ]]; then
    echo "FAIL: declared in include/vsplat.h but not exported by libvsplat.so (VS_API missing?):"
    sed 's/^/  /' <<<"$missing"
    failed=1
fi
mod=$(exports "$MOD" | tr '\n' ' ')
if [[ $mod != "vs_oiio_module_api " ]]; then
    echo "FAIL: vsplat-oiio.so should export vs_oiio_module_api only, exports: $mod"
    failed=1
fi
DCM=$BUILD/vsplat-modules/vsplat-dicom.so
if [[ -f $DCM ]]; then
    dcm=$(exports "$DCM" | tr '\n' ' ')
    if [[ $dcm != "vs_dicom_module_api " ]]; then
        echo "FAIL: vsplat-dicom.so should export vs_dicom_module_api only, exports: $dcm"
        failed=1
    fi
fi
if [[ $failed -eq 0 ]]; then
    echo "libvsplat.so exports the $n_decl functions include/vsplat.h declares and nothing else;" \
        "the modules export their entry points only"
fi
exit $failed
