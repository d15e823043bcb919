#!/usr/bin/env bash
# Install round trip: `cmake --install` of this build into a temporary prefix,
# then build tools/example_embed.c against the installed package three ways
# and run each: CMake find_package(vsplat) with vsplat::vsplat (shared) and
# vsplat::vsplat_static, pkg-config (shared), pkg-config --static (static).
# Also checks the installed CLI, man page, presets and pkg-config metadata.
# Usage: bash tests/cli_install.sh PATH_TO_VSPLAT   (the build folder is its folder)
set -euo pipefail

VSPLAT=${1:?usage: cli_install.sh PATH_TO_VSPLAT}
# the module search is what this tests: a caller's override would hide it
unset VSPLAT_OIIO_MODULE
BUILD=$(cd "$(dirname "$VSPLAT")" && pwd)
if [[ ! -f $BUILD/CMakeCache.txt ]]; then
    echo "SKIP: $BUILD is not a CMake build folder"
    exit 0
fi
if grep -Eq '^VSPLAT_SANITIZE:[A-Z]+=.+' "$BUILD/CMakeCache.txt"; then
    echo "SKIP: sanitizer build (an installed sanitized library needs sanitized consumers)"
    exit 0
fi
for tool in cmake gcc pkg-config; do
    if ! command -v $tool >/dev/null; then
        echo "SKIP: $tool not found"
        exit 0
    fi
done
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
P=$T/prefix

source "$(dirname "${BASH_SOURCE[0]}")/testutil.sh"
step() { # desc, command...
    local desc=$1
    shift
    if "$@" >"$T/log" 2>&1; then ok; else bad "$desc: $(tail -c 1500 "$T/log")"; return 1; fi
}
LINE='^example_embed: vsplat [0-9]+\.[0-9]+\.[0-9]+ rendered 64x64, centre alpha 1\.00, [0-9]+ voxels splatted'
check_run() { # desc, exe, args...
    local desc=$1
    shift
    if "$@" >"$T/run" 2>&1 && grep -Eq "$LINE" "$T/run"; then ok; else bad "$desc: $(head -c 600 "$T/run")"; fi
}

step "cmake --install" cmake --install "$BUILD" --prefix "$P" || { tu_done; exit 1; }
LIBDIR=$(ls -d "$P"/lib*/libvsplat.so 2>/dev/null | head -1 | xargs -r dirname)
if [[ -n $LIBDIR ]]; then ok; else bad "no libvsplat.so under $P/lib*"; LIBDIR=$P/lib; fi
for f in "$P/include/vsplat.h" "$P/bin/vsplat" "$LIBDIR/libvsplat.a" "$LIBDIR/pkgconfig/vsplat.pc" \
    "$LIBDIR/cmake/vsplat/vsplatConfig.cmake" "$LIBDIR/cmake/vsplat/vsplatConfigVersion.cmake" \
    "$LIBDIR/cmake/vsplat/vsplatTargets.cmake" "$P/share/man/man1/vsplat.1" \
    "$P/share/vsplat/tf/colin27-skin-brain.vtf" "$P/share/vsplat/tf/ct-head-bone-soft.json" \
    "$P/share/vsplat/tf/engine.1dt" "$P/share/doc/vsplat/examples/example_embed.c"; do
    if [[ -e $f ]]; then ok; else bad "not installed: ${f#"$P"/}"; fi
done
# versioned soname: libvsplat.so -> libvsplat.so.SOVERSION -> libvsplat.so.X.Y.Z,
# SOVERSION MAJOR.MINOR while the major is 0, else MAJOR (docs/ABI.md)
VER=$("$VSPLAT" --version | awk '{print $2}')
SOV=${VER%%.*}
[[ $SOV == 0 ]] && SOV=${VER%.*}
if [[ -e $LIBDIR/libvsplat.so.$VER && -L $LIBDIR/libvsplat.so.$SOV ]]; then ok; else bad "no versioned libvsplat.so.$VER"; fi
objdump -p "$LIBDIR/libvsplat.so" >"$T/objdump" 2>&1 || true
if grep -q "SONAME *libvsplat.so.$SOV$" "$T/objdump"; then ok; else
    bad "soname is not libvsplat.so.$SOV"; fi
# the installed CLI and man page; the CLI finds the image module under ../LIBDIR
if [[ $("$P/bin/vsplat" --version) == "vsplat $VER" ]]; then ok; else bad "installed vsplat --version"; fi
if [[ -f $LIBDIR/vsplat-modules/vsplat-oiio.so ]]; then ok; else bad "not installed: vsplat-modules/vsplat-oiio.so"; fi
if "$P/bin/vsplat" render --scene sphere --size 32x32 -o "$T/cli.png" >"$T/run" 2>&1 && [[ -s $T/cli.png ]]; then ok; else
    bad "installed vsplat render -o PNG: $(head -c 600 "$T/run")"; fi
if command -v man >/dev/null && MANPAGER=cat MANWIDTH=100 man -l "$P/share/man/man1/vsplat.1" >"$T/man" 2>/dev/null; then
    for w in render info compare --tf --turntable VSPLAT_THREADS VSPLAT_ISA VSPLAT_DATA EXIT; do
        if grep -q -- "$w" "$T/man"; then ok; else bad "man page lacks $w"; fi
    done
elif grep -q '^\.TH VSPLAT 1' "$P/share/man/man1/vsplat.1"; then ok; else bad "man page has no .TH"; fi
# the Python package: installed beside the library, it finds the installed
# libvsplat.so (relative to itself) and renders
PY3=$(command -v /usr/bin/python3 || command -v python3 || true)
if [[ -n $PY3 ]] && "$PY3" -c 'import numpy' 2>/dev/null; then
    if PYTHONPATH=$P/lib/python3/dist-packages env -u VSPLAT_LIBRARY "$PY3" -c '
import os, sys, numpy, vsplat
lib = os.path.realpath(vsplat.library_path())
assert lib.startswith(os.path.realpath(sys.argv[1])), lib
img = vsplat.render(vsplat.Volume(numpy.zeros((16, 16, 16), numpy.float32)), iso=0.5, size=8)
assert img.shape == (8, 8, 4), img.shape
vsplat.save(img, sys.argv[1] + "/py.png")
' "$P" >"$T/run" 2>&1 && [[ -s $P/py.png ]]; then ok; else bad "installed Python package: $(tail -c 600 "$T/run")"; fi
    if [[ -x $P/share/doc/vsplat/examples/render_colin27.py ]]; then ok; else bad "not installed: render_colin27.py"; fi
else
    echo "note: python3 with NumPy not found; the installed Python package is not tried"
fi
EX=$P/share/doc/vsplat/examples/example_embed.c
ENGINE=$P/share/vsplat/tf/engine.1dt

# --- CMake: find_package(vsplat) ---
mkdir "$T/cm"
cat >"$T/cm/CMakeLists.txt" <<CM
cmake_minimum_required(VERSION 3.18)
project(embed LANGUAGES C)
find_package(vsplat $VER REQUIRED)
add_executable(embed_shared "$EX")
target_link_libraries(embed_shared PRIVATE vsplat::vsplat)
add_executable(embed_static "$EX")
target_link_libraries(embed_static PRIVATE vsplat::vsplat_static)
CM
if step "find_package configure" cmake -S "$T/cm" -B "$T/cm/b" -DCMAKE_PREFIX_PATH="$P" -DCMAKE_BUILD_TYPE=Release &&
    step "find_package build" cmake --build "$T/cm/b"; then
    check_run "find_package shared" "$T/cm/b/embed_shared"
    # image I/O is a module: the shared library finds it beside itself...
    check_run "find_package shared + image" "$T/cm/b/embed_shared" "$ENGINE" "$T/cm/out_shared.png"
    if [[ -s $T/cm/out_shared.png ]]; then ok; else bad "the shared example wrote no image"; fi
    # ...and so does a program linked statically through the package,
    # wherever it lives: the package gives it the prefix it was found in
    # (an install with --prefix, not the configured /usr/local)
    check_run "find_package static + image, no VSPLAT_OIIO_MODULE" "$T/cm/b/embed_static" "$ENGINE" "$T/cm/out_static.png"
    if [[ -s $T/cm/out_static.png ]]; then ok; else bad "the static example wrote no image without VSPLAT_OIIO_MODULE"; fi
    # moved away from its module, it says where it looked and takes the variable
    mv "$LIBDIR/vsplat-modules" "$LIBDIR/vsplat-modules.away"
    if "$T/cm/b/embed_static" "$ENGINE" "$T/cm/out.png" >"$T/run" 2>&1; then
        bad "static example wrote an image with its module moved away"
    elif grep -q "cannot load the OpenImageIO module.*$LIBDIR/vsplat-modules.*VSPLAT_OIIO_MODULE" "$T/run"; then ok; else
        bad "static example without the module: $(head -c 600 "$T/run")"; fi
    mv "$LIBDIR/vsplat-modules.away" "$LIBDIR/vsplat-modules"
    check_run "find_package static + .1dt preset" env VSPLAT_OIIO_MODULE="$LIBDIR/vsplat-modules/vsplat-oiio.so" \
        "$T/cm/b/embed_static" "$ENGINE" "$T/cm/out.png"
    if [[ -s $T/cm/out.png ]]; then ok; else bad "the static example wrote no image"; fi
    ldd "$T/cm/b/embed_shared" >"$T/ldd" 2>&1 || true
    if grep -q "$LIBDIR/libvsplat.so" "$T/ldd"; then ok; else bad "embed_shared does not use the installed libvsplat.so: $(cat "$T/ldd")"; fi
    ldd "$T/cm/b/embed_static" >"$T/ldd" 2>&1 || true
    if grep -q libvsplat "$T/ldd"; then bad "embed_static links libvsplat dynamically"; else ok; fi
fi
# a version the package does not offer is refused
mkdir "$T/cm2"
cat >"$T/cm2/CMakeLists.txt" <<CM
cmake_minimum_required(VERSION 3.18)
project(embed2 LANGUAGES C)
find_package(vsplat 99.0 QUIET)
if(vsplat_FOUND)
  message(FATAL_ERROR "vsplat 99.0 found")
endif()
CM
step "find_package refuses version 99" cmake -S "$T/cm2" -B "$T/cm2/b" -DCMAKE_PREFIX_PATH="$P" || true

# --- pkg-config ---
export PKG_CONFIG_PATH=$LIBDIR/pkgconfig
if [[ $(pkg-config --modversion vsplat) == "$VER" ]]; then ok; else bad "pkg-config --modversion: $(pkg-config --modversion vsplat 2>&1)"; fi
# relocatable: the paths point into the temporary prefix
CFLAGS_PC=$(pkg-config --cflags vsplat)
if grep -q -- "-I$P/lib[^ ]*/\.\./\.\./include\|-I$P/include" <<<"$CFLAGS_PC"; then ok; else
    bad "pkg-config --cflags: $(pkg-config --cflags vsplat)"; fi
# shellcheck disable=SC2046
if step "pkg-config shared build" gcc -std=c11 -Wall -Wextra -Werror "$EX" $(pkg-config --cflags --libs vsplat) \
    -Wl,-rpath,"$LIBDIR" -o "$T/pc_shared"; then
    check_run "pkg-config shared" "$T/pc_shared"
fi
# static: the archive, then Libs.private and Requires.private
STATIC_LIBS=$(pkg-config --static --libs vsplat | sed 's/-lvsplat\b//')
# shellcheck disable=SC2046,SC2086
if step "pkg-config static build" gcc -std=c11 -Wall -Wextra -Werror "$EX" $(pkg-config --cflags vsplat) \
    "$LIBDIR/libvsplat.a" $STATIC_LIBS -o "$T/pc_static"; then
    check_run "pkg-config static + .1dt preset" "$T/pc_static" "$ENGINE"
    ldd "$T/pc_static" >"$T/ldd" 2>&1 || true
    if grep -q libvsplat "$T/ldd"; then bad "pc_static links libvsplat dynamically"; else ok; fi
fi

tu_done
