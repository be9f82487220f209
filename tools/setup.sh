#!/usr/bin/env bash
# Installs what msii needs from Debian's packages (only what is missing), then configures
# and builds it (Release, two jobs). Used by tools/demo.sh and tools/test.sh.
#   tools/setup.sh [--no-tests]
# Environment: MSII_BUILD_DIR (default: build), MSII_JOBS (default: 2).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${MSII_BUILD_DIR:-$here/build}"
jobs="${MSII_JOBS:-2}"
with_tests=ON
if [ "${1:-}" = "--no-tests" ]; then
  with_tests=OFF
  # A build folder that already builds the tests (a developer's) keeps building them.
  if grep -qs '^MSII_BUILD_TESTS:BOOL=ON$' "$build_dir/CMakeCache.txt"; then with_tests=ON; fi
fi

packages=(
  build-essential cmake pkg-config
  libopenvdb-dev libboost-iostreams-dev libblosc-dev
  libopenmesh-dev libopenexr-dev libtbb-dev libpng-dev
  libfreetype-dev libfontconfig-dev fonts-dejavu-core
  pybind11-dev python3-dev python3-numpy
  libcgal-dev libeigen3-dev
  libgdal-dev
  libcli11-dev nlohmann-json3-dev
  libgtest-dev
  libcpp-httplib-dev
)
# msii view's page takes three.js from npm (npm ci below): node and npm, from Debian where missing.
command -v node >/dev/null 2>&1 || packages+=(nodejs)
command -v npm >/dev/null 2>&1 || packages+=(npm)
# The tests also run the Snakemake workflow of samples/snakemake, and check GeoTIFFs with gdalinfo.
[ "$with_tests" = ON ] && packages+=(snakemake gdal-bin python3-gdal)
# ... and the Python module's tests and its documented example (plots with matplotlib),
# pip install . into a virtual environment (docs/python.md), and the QGIS plugin run headless
# (docs/terrain.md).
[ "$with_tests" = ON ] && packages+=(python3-pytest python3-matplotlib
  python3-venv python3-pip python3-setuptools python3-wheel
  qgis python3-qgis qgis-providers)
# ... and msii view's page in a real browser (tests/view, driven by playwright-core from npm).
[ "$with_tests" = ON ] && packages+=(chromium)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -gt 0 ]; then
  echo "msii setup: installing ${missing[*]}"
  if [ "$(id -u)" -eq 0 ]; then
    sudo=()
  elif command -v sudo >/dev/null 2>&1; then
    sudo=(sudo)
  else
    echo "msii setup: error: need root or sudo to install: ${missing[*]}" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# three.js (and, for the tests, playwright-core), as package-lock.json pins them; again when
# the lock file changed or the tests need what an earlier install left out.
modules="$here/node_modules"
if [ ! -f "$modules/.package-lock.json" ] || [ "$here/package-lock.json" -nt "$modules/.package-lock.json" ] ||
   { [ "$with_tests" = ON ] && [ ! -d "$modules/playwright-core" ]; }; then
  (cd "$here" && npm ci --no-audit --no-fund $([ "$with_tests" = ON ] || echo --omit=dev))
fi

cmake -S "$here" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DMSII_BUILD_TESTS="$with_tests" \
  -DMSII_WARNINGS_AS_ERRORS="$([ "${CI:-}" = true ] && echo ON || echo OFF)" >/dev/null
cmake --build "$build_dir" -j "$jobs"
