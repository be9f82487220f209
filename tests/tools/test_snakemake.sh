#!/usr/bin/env bash
# The Snakemake workflow of samples/snakemake on a folder of generated scans:
# runs locally with --cores 2; every scan gives the same PLY as `msii compute` run directly
# (byte for byte), a picture, a sheet of six views and a summary line; a DEM gives the GeoTIFF msii compute gives; border=mask
# is passed on; a rerun does nothing; a broken scan fails
# its job while the others finish (--keep-going); the workflow is ready for Slurm (dry run).
# Usage: test_snakemake.sh MSII MSII_SAMPLES SNAKEFILE
set -euo pipefail
msii="$1" samples="$2" snakefile="$3"
fail() { echo "FAIL: $*" >&2; exit 1; }
command -v snakemake >/dev/null || fail "snakemake is not installed (tools/setup.sh installs it)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
mkdir scans
"$samples" tablet --width 5 --height 4 --spacing 0.1 -o scans/a.ply -q
"$samples" terrain --width 5 --height 4 --spacing 0.1 -o scans/b.ply -q
"$samples" sphere --radius 2 --spacing 0.15 -o scans/c.ply -q
"$samples" terrain --geotiff --width 12 --height 10 --spacing 0.25 --relief 1 --holes 2 -o scans/e.tif -q
run() { snakemake --snakefile "$snakefile" --cores 2 --config scans=scans results=results radius=0.6 scales=4 \
          sheets=1 dpi=150 msii="$msii" "$@"; }

run -q > log1.txt 2>&1 || { cat log1.txt; fail "the workflow failed"; }
for name in a b c; do
  for f in results/$name.msii.ply results/$name.msii.json results/$name.quality.png; do
    [ -s "$f" ] || fail "missing $f"
  done
  "$msii" compute scans/$name.ply --radius 0.6 --scales 4 --quiet --output direct-$name.ply
  cmp -s results/$name.msii.ply direct-$name.ply || fail "$name: the workflow's PLY differs from msii compute's"
done
# The DEM: a GeoTIFF of the same values as msii compute gives directly.
[ -s results/e.msii.tif ] && [ -s results/e.msii.json ] || fail "missing the DEM's results"
"$msii" compute scans/e.tif --radius 0.6 --scales 4 --quiet --raster-output direct-e.tif
gdal_translate -q -of ENVI results/e.msii.tif workflow-e.raw && gdal_translate -q -of ENVI direct-e.tif direct-e.raw
[ -s direct-e.raw ] && cmp -s workflow-e.raw direct-e.raw || fail "e: the workflow's GeoTIFF differs from msii compute's"
[ "$(wc -l < results/msii-summary.jsonl)" -eq 4 ] || fail "the summary should have 4 lines"
# The sheets: one per scan at the dpi asked, and their contact sheet naming each.
for name in a b c; do
  [ -s results/sheets/$name.msii.quality.sheet.png ] || fail "missing the sheet of $name"
  grep -q '"dpi": 150' results/sheets/$name.msii.quality.sheet.json || fail "$name's sheet is not at 150 dpi"
  grep -q "$name.msii.ply" results/sheets/index.html || fail "the contact sheet does not name $name"
done
grep -q '"vertices"' results/msii-summary.jsonl || fail "the summary has no vertex counts"

run > log2.txt 2>&1 || { cat log2.txt; fail "the rerun failed"; }
grep -q "Nothing to be done" log2.txt || { cat log2.txt; fail "the rerun did work again"; }

# A broken scan: its job fails, the others still finish, nothing half-written is left.
printf 'OFF\n0 0 0\n' > scans/d.off
rm results/b.msii.ply
if run --keep-going > log3.txt 2>&1; then fail "a broken scan should fail the workflow"; fi
[ -s results/b.msii.ply ] || fail "b should have been redone despite d failing"
[ ! -e results/d.msii.ply ] || fail "d.msii.ply should not exist"
grep -q "contains no vertices" results/logs/d.compute.log || fail "d's log should say why"

# Tiles of one mesh: 2 x 2 tile jobs per scan joined by msii merge give the same PLY.
rm scans/d.off
snakemake --snakefile "$snakefile" --cores 2 -q --config scans=scans results=results-tiled radius=0.6 scales=4 \
  msii="$msii" tiles=2 > log5.txt 2>&1 || { cat log5.txt; fail "the tiled workflow failed"; }
for name in a b c; do
  [ -s results-tiled/tiles/$name.tile3.ply ] || fail "missing tile 3 of $name"
  cmp -s results-tiled/$name.msii.ply direct-$name.ply || fail "$name: the merged tiles differ from msii compute's"
done
grep -q '"tiles_per_axis": 2' results-tiled/a.msii.json || fail "the merged JSON does not record the tiles"

# border=mask: the workflow passes it on (NaN where a ball reaches the tablet's rim).
snakemake --snakefile "$snakefile" --cores 2 -q --config scans=scans results=results-mask radius=0.6 scales=4 \
  msii="$msii" border=mask pictures=0 > log6.txt 2>&1 || { cat log6.txt; fail "the workflow with border=mask failed"; }
"$msii" compute scans/a.ply --radius 0.6 --scales 4 --border mask --quiet --output direct-mask-a.ply
cmp -s results-mask/a.msii.ply direct-mask-a.ply || fail "a: border=mask differs from msii compute --border mask"
cmp -s results-mask/a.msii.ply direct-a.ply && fail "a: border=mask gave the continued values"

# A DEM mosaic of 4 unequal tiles: one job per tile (mosaic=VRT, and dem_tiles=FOLDER through
# a VRT the workflow builds), joined into a VRT equal to the mosaic computed in one piece.
mkdir tiles
"$samples" terrain --geotiff --width 30 --height 22 --spacing 0.25 --relief 1 --holes 2 -o whole-dem.tif -q
gdal_translate -q -srcwin 0 0 50 40 whole-dem.tif tiles/t1.tif
gdal_translate -q -srcwin 50 0 70 40 whole-dem.tif tiles/t2.tif
gdal_translate -q -srcwin 0 40 65 48 whole-dem.tif tiles/t3.tif
gdal_translate -q -srcwin 65 40 55 48 whole-dem.tif tiles/t4.tif
gdalbuildvrt -q mosaic.vrt tiles/t1.tif tiles/t2.tif tiles/t3.tif tiles/t4.tif
"$msii" compute mosaic.vrt --radius 1.5 --scales 4 --quiet --raster-output one-piece.tif
checksums() { gdalinfo -checksum "$1" | grep Checksum | tr -d ' \n'; }
for mode in "mosaic=mosaic.vrt" "dem_tiles=tiles"; do
  rm -rf results-mosaic
  snakemake --snakefile "$snakefile" --cores 2 -q --config $mode results=results-mosaic radius=1.5 scales=4 \
    msii="$msii" > log7.txt 2>&1 || { cat log7.txt; fail "the mosaic workflow ($mode) failed"; }
  name=$( [ "$mode" = "mosaic=mosaic.vrt" ] && echo mosaic || echo tiles )
  for t in t1 t2 t3 t4; do [ -s results-mosaic/$name/$t.msii.tif ] || fail "$mode: missing tile $t"; done
  [ "$(checksums results-mosaic/$name.msii.vrt)" = "$(checksums one-piece.tif)" ] \
    || fail "$mode: the joined tiles differ from the mosaic computed in one piece"
  snakemake --snakefile "$snakefile" --cores 2 --config $mode results=results-mosaic radius=1.5 scales=4 \
    msii="$msii" > log8.txt 2>&1 || { cat log8.txt; fail "the mosaic rerun failed"; }
  grep -q "Nothing to be done" log8.txt || { cat log8.txt; fail "$mode: the rerun did work again"; }
done
snakemake --snakefile "$snakefile" --slurm --jobs 10 --default-resources slurm_partition=main runtime=60 -n \
  --config mosaic=mosaic.vrt results=results-mosaic-slurm radius=1.5 scales=4 msii="$msii" > log9.txt 2>&1 \
  || { cat log9.txt; fail "the mosaic's Slurm dry run failed"; }
[ "$(grep -c '^rule mosaic_tile:' log9.txt)" -eq 4 ] || { cat log9.txt; fail "the Slurm dry run should plan one job per tile"; }

# Ready for a cluster: the same workflow plans its jobs for Slurm (dry run).
snakemake --snakefile "$snakefile" --slurm --jobs 10 --default-resources slurm_partition=main runtime=60 -n \
  --config scans=scans results=results-slurm radius=0.6 scales=4 msii="$msii" > log4.txt 2>&1 \
  || { cat log4.txt; fail "the Slurm dry run failed"; }
grep -q "compute" log4.txt || fail "the Slurm dry run planned no compute jobs"
echo "snakemake workflow: ok"
