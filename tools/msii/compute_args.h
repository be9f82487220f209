#pragma once

#include <CLI/CLI.hpp>
/// @file compute_args.h
/// @brief `msii compute`'s arguments and the pieces its two files share:
/// compute_command.cpp (the options and one input's run) and compute_collection.cpp
/// (folders and several inputs: skipping, resuming, the manifest).

#include "commands.h"

#include <msii/core/diagnostics.h>
#include <msii/io/read_mesh.h>
#include <msii/pipeline/compute.h>

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace msii::tools {

struct ComputeArgs : CommonArgs {
    std::vector<std::string> inputs;
    std::string output, outputDir;
    double radius = 0;
    int scales = 16;
    const CLI::Option* scalesOption = nullptr;  // given on the command line (DEMs default otherwise)
    double voxelSize = 0;
    double precision = 6.0;
    double plPrecision = 0;  // 0 = 4/3 of precision (the engine's default)
    std::string plCheck = "on";  // --pl-check: on (exact where the kernels blur) or off
    std::string units;           // --units: the mesh's units, recorded for pictures (empty: unstated)
    bool repair = false, strict = false, noSphere = false;
    double fillHoles = -1;      // longest hole border filled; -1 = pi R (default), 0 = none
    std::string engine = "heights";  ///< a DEM's V and S: heights or mesh
    std::string border = "continue";  // --border: continue (default) or mask
    std::string invariants = "V,S,P,L";
    bool exact = false;
    std::string vertices;       // exact mode: comma-separated indices
    std::size_t randomVertices = 0;
    std::uint64_t seed = 1;
    bool gigamesh = false;
    std::string memoryBudget;   // e.g. "8G": tiles sized to fit
    int tiles = 0;              // tiles per axis (0: from the budget)
    int tile = -1;              // compute only this tile (with --tiles), for merging later
    std::string manifest;       // JSON lines; default for collections: <output folder>/msii-manifest.jsonl
    bool recursive = false;     // folders: also their subfolders
    // Rasters (DEMs) in, georeferenced rasters out (compute_raster.cpp)
    std::string rasterOutput;   // output GeoTIFF (default <stem>.msii.tif)
    std::string bands;          // features written as bands (default V at every radius and quality)
    int band = 0;               // the input's height band (0: the only one)
    int windowCells = 0;        // own cells per window side (0: from the memory budget)
    bool float32 = false;       // float32 raster bands even where scaled 16-bit integers hold them
    std::string tileOfMosaic;   // the source tile of a mosaic whose cells alone are computed
};

/// What one input gave, for the summary and the manifest.
struct OneResult {
    std::size_t vertices = 0;
    double voxelSize = 0, seconds = 0;
};

/// The P and L precision the engine uses for these arguments (0 = its automatic choice).
double plPrecisionOf(const ComputeArgs& args);

/// The invariants of --invariants ("V,S,P,L", "VSPL", any case, subset: parseInvariantList);
/// --no-sphere removes S. @throw InvalidInputError naming --invariants.
std::vector<Invariant> invariantsOf(const ComputeArgs& args);

/// The pipeline's options for these arguments, for meshes and rasters alike.
/// @throw InvalidInputError for unusable arguments, naming the option.
ComputeOptions computeOptionsOf(const ComputeArgs& args);

/// Where the result of @p input goes: --output for a single input, else
/// <output-dir or input's folder>/<stem>.msii.ply
std::string outputPathFor(const ComputeArgs& args, const std::string& input);

/// The JSON record next to an output PLY.
std::string sidecarPathFor(const std::string& plyPath);

/// Whether @p input is read as a raster (DEM) rather than a mesh: not a mesh format msii
/// reads itself (.ply, .obj, .off, .stl), and one GDAL opens as a raster.
bool isRasterInput(const std::string& input);

/// "8G", "500M", "8GB", "2.5e9" (bytes) to bytes; empty = 0 (no limit).
double parseBytes(const std::string& text);

/// A diagnostic as `msii compute` prints it: the engine's sentence, plus the option that
/// changes what it is about.
std::string worded(const Diagnostic& d);

/// What one mesh input's run gives its JSON record (compute_record.cpp).
struct MeshRunRecord {
    const ComputeArgs& args;
    const std::string &input, &output;
    const ReadMeshResult& read;
    const ComputeOptions& options;
    const ComputeResult& result;
    double readSeconds, writeSeconds, totalSeconds;
};
nlohmann::json runRecord(const MeshRunRecord& record);
/// The `patch_line` of a JSON record: P and L's pairs given a value, and of them those
/// evaluated exactly where the kernels blur.
nlohmann::json patchLineRecord(const InvariantsCost& cost);
/// ", P and L exact at S % of values" for the summary line ("" without P and L).
std::string exactShareText(const InvariantsCost& cost);
/// The `parameters` of a JSON record, mesh or raster (@p letters: the invariants, e.g. "VS").
nlohmann::json parametersRecord(const ComputeArgs& args, const ScalePlan& plan, const std::string& letters,
                                double maxHolePerimeter);

/// This process's peak resident memory so far, bytes (0 if unknown).
double peakMemoryBytes();
/// Adds `diagnostics` (coded) and `warnings` (as printed) to a JSON record.
void addDiagnostics(nlohmann::json& record, const std::vector<Diagnostic>& diagnostics);

/// One raster input (DEM): read through GDAL, triangulate, prepare, compute, write the
/// chosen features as a GeoTIFF on the input's grid and its JSON record (docs/terrain.md).
OneResult computeRasterOne(const ComputeArgs& args, const std::string& input, const std::string& output);

/// One input: read, prepare, compute, write the PLY (and GigaMesh files) and its JSON record.
/// @throw InvalidInputError, IOError with one sentence.
OneResult computeOne(const ComputeArgs& args, const std::string& input, const std::string& output);

/// The inputs with folders replaced by the mesh files in them (sorted; subfolders with
/// --recursive); @p collection is set when there are several or a folder was given.
/// @throw InvalidInputError for a folder without mesh files.
std::vector<std::string> expandInputs(const ComputeArgs& args, bool& collection);

/// A collection: each input on its own; a failure is reported and the rest go on; finished
/// outputs made with the same parameters are skipped unless --overwrite, so an interrupted
/// run resumes; one manifest line per input. Returns the exit code (1 if any failed).
int computeCollection(const ComputeArgs& args, const std::vector<std::string>& inputs);

} // namespace msii::tools
