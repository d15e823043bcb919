#!/usr/bin/env bash
# Make `import vsplat` work in python3 from this build: tools/python-user-site.sh [build-dir]
# Writes vsplat.pth, naming BUILD/python (the package CMake copies there,
# which finds BUILD's libvsplat.so), into the user site of Debian's python3
# (the one that sees python3-numpy; other Python 3 of the same minor version
# read the same user site).  tools/demo.sh and tools/test.sh run it.
# Quiet when nothing changes.  No python3: a note, exit 0.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=$(cd "${1:-$ROOT/build}" && pwd)
PY=
for p in /usr/bin/python3 "$(command -v python3 || true)"; do
    if [[ -n $p && -x $p ]]; then PY=$p; break; fi
done
if [[ -z $PY ]]; then
    echo "python-user-site: no python3; the Python package (tools/python) is not set up" >&2
    exit 0
fi
if [[ ! -f $BUILD/python/vsplat/_paths.py ]]; then
    echo "python-user-site: $BUILD/python/vsplat is not built (run tools/build.sh $BUILD)" >&2
    exit 1
fi
SITE=$("$PY" -c 'import site; print(site.getusersitepackages())')
PTH=$SITE/vsplat.pth
if [[ -f $PTH && $(cat "$PTH") == "$BUILD/python" ]]; then
    exit 0
fi
mkdir -p "$SITE"
echo "$BUILD/python" >"$PTH"
echo "python-user-site: python3 imports vsplat from $BUILD/python ($PTH)" >&2
