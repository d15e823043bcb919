#!/usr/bin/env bash
# Build vsplat and run every test: tools/test.sh
# Exits non-zero if the build or any test fails.
# (build folder: $VSPLAT_BUILD_DIR, default build/)
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${VSPLAT_BUILD_DIR:-$ROOT/build}

"$ROOT/tools/build.sh" "$BUILD"
"$ROOT/tools/python-user-site.sh" "$BUILD" # python3 -c "import vsplat" works from now on
ctest --test-dir "$BUILD" --output-on-failure -j2
