#!/usr/bin/env bash
# Build vsplat (Release, warnings as errors): tools/build.sh [build-dir]
# The build folder defaults to build/ in the repository root; extra CMake
# options can be passed in VSPLAT_CMAKE_ARGS.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${1:-$ROOT/build}

"$ROOT/tools/install-deps.sh"
# shellcheck disable=SC2086
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DVSPLAT_WERROR=ON ${VSPLAT_CMAKE_ARGS:-} >/dev/null
cmake --build "$BUILD" -j"$(nproc)"
