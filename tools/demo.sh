#!/usr/bin/env bash
# Sets up (installs missing Debian packages, builds Release), generates the bundled default
# sample (a tablet-like surface with wedge impressions) and runs msii compute on it.
# Results go to demo-output/ (or $1).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$here/tools/setup.sh" --no-tests
build_dir="${MSII_BUILD_DIR:-$here/build}"
out="${1:-$here/demo-output}"
mkdir -p "$out"
"$build_dir/samples/msii-samples" tablet --width 20 --height 15 --spacing 0.05 --seed 1 \
  --output "$out/tablet.ply"
"$build_dir/tools/msii" compute "$out/tablet.ply" --radius 1.0 --scales 16 --overwrite \
  --output "$out/tablet.msii.ply"
echo "msii demo: results in $out (tablet.msii.ply: V_01..V_16, S_01..S_16, P_01..P_16, L_01..L_16, quality; tablet.msii.json)"
