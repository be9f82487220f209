#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The long fuzzing run of msii's input, for a person (the test suite runs 60 mutants per
# format): N mutants per format (default 1000) of the seeds in tests/fuzz/seeds, computed by
# build/tools/msii two at a time; failing mutants are kept, each with a report, in
# fuzz-failures/ (or $FUZZ_FAILURES). Other seeds of the mutations: FUZZ_SEED (default 1).
# Two runs at a time on two cores: 1000 per format (6000 mutants) take about 8 minutes.
# Usage: tools/fuzz.sh [N]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${MSII_BUILD_DIR:-$here/build}"
python=/usr/bin/python3
[ -x "$python" ] || python=python3
exec "$python" "$here/tests/fuzz/fuzz.py" --msii "$build_dir/tools/msii" --count "${1:-1000}" \
  --seed "${FUZZ_SEED:-1}" --jobs "${FUZZ_JOBS:-2}" --keep "${FUZZ_FAILURES:-$here/fuzz-failures}"
