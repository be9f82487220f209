#pragma once
/// @file msii.h
/// @brief The umbrella header of the msii library (`find_package(msii)`, target msii::msii):
/// reading meshes, preparing them, the invariants (fast and exact, tiled), their metrics
/// and smoothing, feature maps, pictures, components and outlines. docs/library.md shows
/// its use; docs/method.md the formulas.

#include <msii/core/diagnostics.h>
#include <msii/core/errors.h>
#include <msii/core/feature_set.h>
#include <msii/core/run_context.h>
#include <msii/core/terminal_progress.h>
#include <msii/core/version.h>
#include <msii/invariants/compute.h>
#include <msii/invariants/exact.h>
#include <msii/invariants/patch_line.h>
#include <msii/invariants/volume_sphere.h>
#include <msii/invariants/scales.h>
#include <msii/io/feature_properties.h>
#include <msii/io/write_ply.h>
#include <msii/map/feature_map.h>
#include <msii/mesh/prepare_mesh.h>
#include <msii/mesh/read_mesh.h>
#include <msii/mesh/trimesh.h>
#include <msii/metrics/feature_metrics.h>
#include <msii/outline/isolines.h>
#include <msii/render/annotate.h>
#include <msii/render/picture.h>
#include <msii/segmentation/components.h>
#include <msii/smoothing/ring_smoothing.h>
#include <msii/tiling/tiled_compute.h>
