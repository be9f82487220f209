#!/usr/bin/env bash
# The Python example of docs/python.md runs as written on a generated scan and writes its
# picture. Usage: test_python_example.sh MSII_SAMPLES PYTHON EXAMPLE.py (PYTHONPATH set).
set -euo pipefail
samples="$1" python="$2" example="$3"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$samples" tablet --width 12 --height 9 --spacing 0.06 -q -o "$work/scan.ply"
"$python" "$example" "$work/scan.ply" 0.8 "$work/volume.png"
[ -s "$work/volume.png" ] || { echo "FAIL: no picture written" >&2; exit 1; }
head -c 8 "$work/volume.png" | od -c | grep -q "P   N   G" || { echo "FAIL: not a PNG" >&2; exit 1; }
