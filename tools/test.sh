#!/usr/bin/env bash
# Sets up (installs missing Debian packages, builds Release) and runs the whole test suite.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$here/tools/setup.sh"
build_dir="${MSII_BUILD_DIR:-$here/build}"
cd "$build_dir"
ctest --output-on-failure -j "${MSII_JOBS:-2}" --timeout 1800
