#pragma once
/// @file msii.h
/// @brief The umbrella header of the msii library (`find_package(msii)`, target msii::msii):
/// every public header, in the order of the pipeline (docs/architecture.md). Most programs
/// need only pipeline/compute.h, msii::compute; docs/library.md shows its use, docs/method.md
/// the formulas.

// The vocabulary: results, errors, diagnostics, progress and cancellation.
#include <msii/core/diagnostics.h>
#include <msii/core/errors.h>
#include <msii/core/feature_set.h>
#include <msii/core/run_context.h>
#include <msii/core/stopwatch.h>
#include <msii/core/terminal_progress.h>
#include <msii/core/vec3.h>
#include <msii/core/version.h>
// Files: meshes in and out, feature tables, GigaMesh files, atomic writes.
#include <msii/io/atomic_file.h>
#include <msii/io/feature_properties.h>
#include <msii/io/feature_table.h>
#include <msii/io/gigamesh_files.h>
#include <msii/io/read_mesh.h>
#include <msii/io/read_ply.h>
#include <msii/io/write_ply.h>
// The mesh: its check, statistics and preparation (repair, orientation, holes).
#include <msii/mesh/border_distance.h>
#include <msii/mesh/fill_holes.h>
#include <msii/mesh/mesh_check.h>
#include <msii/mesh/mesh_stats.h>
#include <msii/mesh/prepare_mesh.h>
#include <msii/mesh/principal_axes.h>
#include <msii/mesh/trimesh.h>
#include <msii/mesh/vertex_normals.h>
// The level set and the invariants (fast and exact), in tiles.
#include <msii/levelset/levelset.h>
#include <msii/invariants/exact.h>
#include <msii/invariants/invariants.h>
#include <msii/invariants/patch_line.h>
#include <msii/invariants/scales.h>
#include <msii/invariants/volume_sphere.h>
#include <msii/tiling/tiled_compute.h>
// The whole pipeline, the one entry point: a mesh as read to values per input vertex.
#include <msii/pipeline/compute.h>
#include <msii/pipeline/masked_values.h>
// Terrain: DEM rasters in, window by window, and georeferenced rasters out.
#include <msii/terrain/dem.h>
#include <msii/terrain/dem_compute.h>
#include <msii/terrain/raster_output.h>
// After the values: metrics, smoothing, feature maps, pictures, components, outlines.
#include <msii/metrics/feature_metrics.h>
#include <msii/smoothing/ring_smoothing.h>
#include <msii/featuremap/feature_map.h>
#include <msii/featuremap/half_floats.h>
#include <msii/featuremap/map_frame.h>
#include <msii/featuremap/rasterize.h>
#include <msii/render/annotate.h>
#include <msii/render/colormap.h>
#include <msii/render/image.h>
#include <msii/render/picture.h>
#include <msii/render/shading.h>
#include <msii/render/typeface.h>
// Figures: the six views of an object on one sheet.
#include <msii/figures/fat_cross.h>
#include <msii/figures/sheet_orientation.h>
#include <msii/figures/sheet_raster.h>
// Vessels: the axis of rotation, the profile and the rollout.
#include <msii/vessels/axis_of_rotation.h>
#include <msii/vessels/profile_section.h>
#include <msii/vessels/unroll.h>
#include <msii/segmentation/components.h>
#include <msii/outline/isolines.h>
