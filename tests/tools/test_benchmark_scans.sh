#!/bin/bash
# msii-benchmark's scans case, small: the per-stage tables with an earlier program beside
# (here the same msii), and the GigaMesh rows through stand-ins that check they are called
# as GigaMesh's programs take their arguments and write what those write.
# Usage: test_benchmark_scans.sh MSII_BENCHMARK MSII
set -euo pipefail
benchmark=$1 msii=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat > "$work/gigamesh-featurevectors" <<'SH'
#!/bin/bash
# gigamesh-featurevectors -r R -n LOG2N -k FILE
[ "$1" = -r ] && [ "$3" = -n ] && [ "$4" = 4 ] && [ "$5" = -k ] && [ -f "$6" ] || { echo "bad arguments: $*"; exit 3; }
SH
cat > "$work/gigamesh-featurevectors-sl" <<'SH'
#!/bin/bash
# gigamesh-featurevectors-sl -input F -format ply -radius R -algorithm A -output O -threads 1 -max_load M
[ "$1" = -input ] && [ -f "$2" ] && [ "$3 $4" = "-format ply" ] && [ "$5" = -radius ] && [ "$7" = -algorithm ] &&
  { [ "$8" = sphere_volume ] || [ "$8" = sphere_surface ]; } && [ "$9" = -output ] && [ "${11}" = -threads ] ||
  { echo "bad arguments: $*"; exit 0; }  # as the real one: exit 0, no output
touch "${10}"
SH
chmod +x "$work"/gigamesh-*
out=$("$benchmark" --spacing 0.15 --runs 1 --tiles 0 --map-pixels 0 --exact-vertices 0 --exact-slab false \
  --processes false --sheets false --vessels false --before "$msii" --gigamesh "$work")
echo "$out"
grep -q "scan-like slab, .* vertices, R = .* (25 median edges), N = 16, 1 thread;" <<<"$out"
grep -q "scan-like slab, .* vertices, R = .*, 2 threads;" <<<"$out"
grep -q "^tablet, .* vertices, R = 1 " <<<"$out"
[ "$(grep -c '| \*\*wall, the whole process\*\* ' <<<"$out")" -eq 3 ]
[ "$(grep -c '^| stencils (V and S) .*|.*|.*|.*|.*|.*|' <<<"$out")" -eq 3 ]  # before, after, ratio twice
! grep -q "failed" <<<"$out"
! grep -q "not measured" <<<"$out"
grep -q "| GigaMesh / msii, all four " <<<"$out"
echo "benchmark scans case: ok"
