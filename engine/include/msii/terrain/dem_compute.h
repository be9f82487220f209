#pragma once
/// @file dem_compute.h
/// @brief The invariants of a DEM of any size, window by window: the raster is read in
/// windows of cells with a halo, each window is triangulated (terrain/dem.h), prepared
/// (holes filled) and computed, and the chosen features of its own cells are written into
/// their place in the output raster. The surface is never held whole, so memory stays at
/// one window's computation whatever the raster's size (docs/terrain.md). A window whose
/// surface would exceed the memory limit (spikes, noise) is split further (docs/limits.md).
///
/// All windows share one plan: the voxel size and P and L's vertex spacing from the central
/// window's mesh, and the local frame's origin at the raster's centre; the halo reaches past
/// everything a value depends on (tiling/tiled_compute.h, haloWidth), and where a nodata
/// gap crosses its edge also the widest gap that is filled. So a window's own values are those
/// of the whole raster computed as one piece, bit for bit (tested), and there are no seams.

#include <msii/core/diagnostics.h>
#include <msii/core/run_context.h>
#include <msii/pipeline/compute.h>
#include <msii/terrain/dem.h>
#include <msii/terrain/raster_output.h>

#include <string>
#include <vector>

namespace msii {

/// How a DEM's V and S are computed (docs/terrain.md, Engines).
enum class DemEngine {
    /// Straight from the heights, without a level set (terrain/height_field.h), the raster's
    /// small gaps filled and its borders continued on the grid (terrain/grid_continuation.h).
    /// A run that needs P or L takes the mesh route instead, and its record says so.
    HeightField,
    /// The DEM's mesh through the level set, as a scan (pipeline/compute.h).
    Mesh,
};

struct DemComputeOptions {
    /// What each window runs (pipeline/compute.h): radius, scales, precision, which
    /// invariants (not exact); nodata gaps are holes, filled up to maxHolePerimeter (-1: πR).
    /// tiling.memoryBudget sizes the windows (0: defaultDemMemoryBudget); windows are the
    /// tiling, so no tilesPerAxis.
    ComputeOptions compute;
    int band = 0;                   ///< DemReadOptions::band
    /// Features written, by name (demBandNames: V_01 …, quality, valid_radii, filled_share
    /// and the input's `height`); empty = V at every radius (or the first invariant
    /// computed) and quality.
    std::vector<std::string> bands;
    /// Own cells per window side; 0 = from the memory budget.
    int windowCells = 0;
    /// Only these cells are computed and written, on their own grid (one source tile of a
    /// mosaic, a job of a cluster); the rest of the raster is read as far as their halos
    /// reach. The values equal those of the whole raster computed in one piece, bit for bit.
    RasterRegion region;
    /// Float32 bands even where every band is a fraction in [0, 1] (V̂, Ŝ, their quality,
    /// filled_share), which are otherwise written as scaled 16-bit integers
    /// (RasterOutputOptions::scaled16: a resolution of 1.5e-5, a third of the size).
    bool float32 = false;
    RasterOutputOptions output;     ///< description and metadata of the output raster
    DemEngine engine = DemEngine::HeightField;
};

/// The names of the bands a DEM computation with @p options can write, for parseFeatureNames
/// (io/feature_properties.h): the output properties, then `height`.
std::vector<std::string> demBandNames(const ComputeOptions& options);

struct DemComputeResult {
    /// The raster's band and counts (heights left empty), and the output's grid: the region's
    /// cells of the raster's (all of it by default).
    Dem input;
    ScalePlan plan;
    std::vector<std::string> bands;          ///< as written
    /// The invariants computed: of those asked, only the ones the bands need (V alone for
    /// the default bands); the values written do not depend on the others.
    std::vector<Invariant> computed;
    bool scaled16 = false;                   ///< written as scaled 16-bit integers
    std::vector<Diagnostic> diagnostics;     ///< summed over the windows
    int windowsPerRow = 1, windowsPerColumn = 1, windowCells = 0;
    /// The halo: narrow (haloWidth) unless a nodata gap crosses its edge, then wide (plus
    /// the widest gap filled); windows are sized for the wide one.
    int haloCells = 0, narrowHaloCells = 0;
    int wideHaloWindows = 0;       ///< windows that needed the wide halo
    /// Windows computed in quarters because their surface exceeded the memory limit (spikes
    /// or noise in the heights); the values do not depend on it.
    int splitWindows = 0;
    std::size_t triangles = 0;     ///< of all windows' own squares
    MaskedValues masked;           ///< over the own cells in a face of all windows
    InvariantsCost cost;           ///< summed over the windows
    double readSeconds = 0, prepareSeconds = 0, writeSeconds = 0;
    /// The route taken, and why it is not the one asked for (P or L asked from the height
    /// field), empty if it is.
    DemEngine engine = DemEngine::HeightField;
    std::string engineNote;
    double heightFieldSeconds = 0;  ///< the kernel's, summed over the windows
};

/// Computes the invariants of the DEM @p input and writes the chosen features to @p output,
/// a Cloud-Optimized GeoTIFF on the input's grid (terrain/raster_output.h), atomically.
/// @throw InvalidInputError, IOError as readDem and writeRaster, and for unusable options
///        (before any computation: a band that the options cannot give is named).
DemComputeResult computeDem(const std::string& input, const std::string& output, const DemComputeOptions& options,
                            RunContext* context = nullptr);

} // namespace msii
