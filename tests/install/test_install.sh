#!/usr/bin/env bash
# msii as a library, as an outside project uses it: `cmake --install` into a temporary
# prefix, then examples/ configured on its own with find_package(msii REQUIRED) against that
# prefix, built, and run on a generated mesh; its CSV must equal the in-tree example's. The
# installed programs and the installed Python module must run from the prefix as well.
# Usage: test_install.sh BUILD_DIR SOURCE_DIR MSII_SAMPLES IN_TREE_VOLUME_CSV PYTHON
set -euo pipefail
build="$1" src="$2" samples="$3" intree="$4" python="$5"
fail() { echo "FAIL: $*" >&2; exit 1; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"
cmake --install "$build" --prefix "$prefix" > "$work/install.log" || { cat "$work/install.log"; fail "cmake --install"; }
config="$(find "$prefix" -name msiiConfig.cmake | head -n 1)"
[ -n "$config" ] || fail "no msiiConfig.cmake installed"
[ -f "$prefix/include/msii/msii.h" ] || fail "no umbrella header installed"
cmake -S "$src/examples" -B "$work/examples" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
  > "$work/configure.log" 2>&1 || { cat "$work/configure.log"; fail "configuring examples/ against the prefix"; }
cmake --build "$work/examples" -j 2 > "$work/build.log" 2>&1 || { cat "$work/build.log"; fail "building examples/"; }
"$samples" tablet --width 4 --height 3 --spacing 0.1 -q -o "$work/tablet.ply"
"$work/examples/volume_csv" "$work/tablet.ply" 0.6 "$work/outside.csv" 2> /dev/null
"$intree" "$work/tablet.ply" 0.6 "$work/inside.csv" 2> /dev/null
[ "$(wc -l < "$work/outside.csv")" -gt 100 ] || fail "the example's CSV is too short"
cmp -s "$work/outside.csv" "$work/inside.csv" || fail "the installed library's example differs from the in-tree one"
"$prefix/bin/msii" --version > /dev/null || fail "the installed msii does not run"
# msii view finds its page where it is installed (share/msii/view beside bin/).
"$prefix/bin/msii" compute "$work/tablet.ply" -r 0.5 -q -o "$work/tablet.msii.ply" || fail "the installed msii compute"
"$prefix/bin/msii" view "$work/tablet.msii.ply" --no-serve -q || fail "the installed msii view"
[ -f "$work/tablet.msii.view/three/three.module.js" ] || fail "the installed msii view wrote no three.js"
# The QGIS plugin, with the file that names the installed program.
plugin="$prefix/share/msii/qgis/msii_processing"
[ -f "$plugin/metadata.txt" ] && [ -f "$plugin/program.py" ] || fail "no QGIS plugin in $plugin"
[ "$(cat "$plugin/msii_program.txt")" = "$prefix/bin/msii" ] || fail "msii_program.txt does not name $prefix/bin/msii"
PYTHONPATH="$prefix/lib/python3/dist-packages" "$python" -c "import msii, sys; sys.exit(0 if msii.__version__ else 1)" \
  || fail "the installed Python module does not import"
echo "ok: installed, built examples/ against it, same CSV ($(wc -l < "$work/outside.csv") lines)"
