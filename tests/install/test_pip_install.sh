#!/usr/bin/env bash
# pip install . as docs/python.md shows it: a clone of the repository (its committed state)
# into a fresh virtual environment with Debian's packages (--system-site-packages,
# --no-build-isolation, and --no-index: nothing is downloaded). Then, without PYTHONPATH,
# `import msii` must find the environment's module, and the Python tests that compare it with
# the msii program (compute, metric and smooth, bit for bit) must pass with it.
# Usage: test_pip_install.sh SOURCE_DIR PYTHON MSII MSII_SAMPLES
set -euo pipefail
src="$1" python="$2" msii="$3" samples="$4"
fail() { echo "FAIL: $*" >&2; exit 1; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
unset PYTHONPATH
if git -C "$src" rev-parse --git-dir > /dev/null 2>&1; then
  git clone -q "$src" "$work/src"
else  # a source tree without git: its files, without build folders
  mkdir "$work/src" && tar -C "$src" --exclude='./build*' --exclude=./.pip-build -cf - . | tar -C "$work/src" -xf -
fi
"$python" -m venv --system-site-packages "$work/venv"
CMAKE_BUILD_PARALLEL_LEVEL="${MSII_JOBS:-2}" "$work/venv/bin/pip" install -q --no-build-isolation --no-index "$work/src" \
  > "$work/pip.log" 2>&1 || { tail -n 40 "$work/pip.log"; fail "pip install . in a fresh environment"; }
cd "$work"
where="$("$work/venv/bin/python" -c "import msii; print(msii.__file__)")" || fail "import msii after pip install"
case "$where" in
  "$work/venv/"*) ;;
  *) fail "import msii found $where, not the environment's module" ;;
esac
MSII_EXE="$msii" MSII_SAMPLES_EXE="$samples" "$work/venv/bin/python" -m pytest -q -p no:cacheprovider \
  "$src/python/tests/test_msii.py" -k "equals_the_cli or equal_the_cli" \
  || fail "the pip-installed module differs from the msii program"
echo "ok: pip install . into a fresh environment; import msii finds $where; its values are the program's"
