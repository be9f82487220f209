#!/usr/bin/env bash
# Sets up (installs missing Debian packages, builds Release), generates the bundled default
# sample (a tablet-like surface with wedge impressions), runs msii compute on it, and makes
# the pictures, the EXR feature map, the components and the outlines of the README.
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
msii="$build_dir/tools/msii"
"$msii" map "$out/tablet.msii.ply" --pixels 2048 --overwrite --output "$out/tablet.map.exr"
"$msii" render "$out/tablet.msii.ply" --show quality --shade --isolines 5 --pixels 800 --overwrite \
  --output "$out/tablet.quality.png"
"$msii" render "$out/tablet.msii.ply" --show V_04 --colormap coolwarm --center 0.5 --pixels 800 --overwrite \
  --output "$out/tablet.V_04.png"
"$msii" render "$out/tablet.msii.ply" --show relief --pixels 800 --overwrite --output "$out/tablet.relief.png"
"$msii" render "$out/tablet.msii.ply" --show relief --high-contrast --pixels 800 --overwrite \
  --output "$out/tablet.relief-contrast.png"
"$msii" render "$out/tablet.msii.ply" --show height --colormap cividis --isolines 8 --pixels 800 --overwrite \
  --output "$out/tablet.height.png"
"$msii" segment "$out/tablet.msii.ply" --threshold 0.55 --min-vertices 20 --overwrite \
  --output "$out/tablet.segments.ply"
"$msii" render "$out/tablet.segments.ply" --show label --colormap viridis --range 0,30 --shade --pixels 800 --overwrite \
  --output "$out/tablet.segments.png"
"$msii" outline "$out/tablet.msii.ply" --levels 0.55 --overwrite --output "$out/tablet.outline.svg"
# A whole tablet (closed, round marks on all six sides): the six views on one sheet at 300 dpi,
# with its record (docs/figures.md).
"$build_dir/samples/msii-samples" rounded-tablet --roughness 0.004 --output "$out/whole.ply" -q
"$msii" compute "$out/whole.ply" --radius 1.5 --invariants V --overwrite --output "$out/whole.msii.ply"
"$msii" render "$out/whole.msii.ply" --layout fat-cross --dpi 300 --shade --isolines 4 --labels --overwrite \
  --output "$out/whole.sheet.png"
# Terrain: a generated DEM (GeoTIFF, UTM 32N, 0.5 m cells, small nodata patches) to a
# georeferenced GeoTIFF of features, and its picture (docs/terrain.md).
"$build_dir/samples/msii-samples" terrain --geotiff --width 200 --height 150 --spacing 0.5 --relief 3 \
  --hill-width 12 --holes 8 --hole-size 1.5 --output "$out/dem.tif" -q
"$msii" compute "$out/dem.tif" --radius 15 --overwrite --raster-output "$out/dem.msii.tif"
"$msii" render "$out/dem.msii.tif" --shade --isolines 5 --pixels 800 --overwrite --output "$out/dem.quality.png"
echo "msii demo: results in $out:"
echo "  tablet.msii.ply (V_01..V_16, S_01..S_16, P_01..P_16, L_01..L_16, quality, valid_radii, filled_share),"
echo "  tablet.msii.json,"
echo "  tablet.map.exr (feature map), tablet.*.png (pictures), tablet.segments.ply/.csv, tablet.outline.svg,"
echo "  whole.sheet.png and whole.sheet.json (a whole tablet's six views on one sheet),"
echo "  dem.tif (a generated DEM) and dem.msii.tif (its features as a GeoTIFF for QGIS), dem.quality.png"
