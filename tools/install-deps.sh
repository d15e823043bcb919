#!/usr/bin/env bash
# Install the Debian packages vsplat needs, if any are missing.
# Quiet when everything is there.  Set VSPLAT_SKIP_DEPS=1 to skip entirely.
set -euo pipefail

if [[ ${VSPLAT_SKIP_DEPS:-0} == 1 ]]; then
    exit 0
fi

PACKAGES=(
    build-essential gcc g++ make cmake pkg-config
    libopenimageio-dev openimageio-tools
    libhwloc-dev libteem-dev libnifti2-dev zlib1g-dev libbz2-dev
    libcjson-dev  # ParaView colour-map presets (--tf FILE.json)
    libgdcm-dev python3-pydicom  # DICOM series (the module); tests write series with pydicom
    mricron-data  # the Colin27 demo head (ch2.nii.gz)
    libvolpack1-dev  # vsplat-bench peers: VolPack's octree renderer
    gnuplot-nox jq  # plots; tools/trace-png.sh reads traces with jq
    python3 python3-numpy  # the Python package (tools/python) and its tests
    clang libclang-rt-14-dev valgrind  # sanitizers, fuzzers, memcheck
    libopenmpi-dev openmpi-bin  # vsplat-mpi (optional: the rest builds without it)
)

missing=()
for p in "${PACKAGES[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
        missing+=("$p")
    fi
done
if [[ ${#missing[@]} -eq 0 ]]; then
    exit 0
fi

if ! command -v apt-get >/dev/null; then
    echo "install-deps: missing packages (${missing[*]}) and no apt-get; install them by hand" >&2
    exit 1
fi
SUDO=()
if [[ $(id -u) -ne 0 ]]; then
    if ! command -v sudo >/dev/null; then
        echo "install-deps: missing packages (${missing[*]}); run as root or install sudo" >&2
        exit 1
    fi
    SUDO=(sudo)
fi

echo "install-deps: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
"${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq >/dev/null
"${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
