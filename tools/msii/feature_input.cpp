#include "feature_input.h"

#include <msii/core/errors.h>
#include <msii/core/version.h>
#include <msii/io/atomic_file.h>
#include <msii/io/feature_table.h>
#include <msii/io/read_mesh.h>
#include <msii/terrain/dem.h>
#include <msii/terrain/raster_output.h>

#include "commands.h"
#include "compute_args.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <cstdio>
#include <limits>
#include <sstream>

namespace fs = std::filesystem;

namespace msii::tools {

bool isFeatureName(const std::string& name, char letter)
{
    if (name.size() < 4 || name[1] != '_') return false;
    const bool letterOk = letter != 0 ? name[0] == letter : std::string("VSPL").find(name[0]) != std::string::npos;
    return letterOk &&
           std::all_of(name.begin() + 2, name.end(), [](unsigned char c) { return std::isdigit(c); });
}

namespace {

void nodataAsNaN(RasterImage& raster)
{
    if (!raster.hasNodata || std::isnan(raster.nodata)) return;
    for (RasterBand& b : raster.bands)
        for (float& v : b.values)
            if (v == float(raster.nodata)) v = std::numeric_limits<float>::quiet_NaN();
}

} // namespace

RasterInput readRasterInput(const std::string& path, bool needHeights)
{
    RasterInput in;
    in.raster = readRaster(path);
    nodataAsNaN(in.raster);
    const RasterGeoreference& g = in.raster.georeference;
    // Short names for the scale bar and the units comment.
    in.units = g.units == "metre" || g.units == "meter" || g.units == "Meter"                 ? "m"
               : g.units == "foot" || g.units == "US survey foot" || g.units == "foot_us" ? "ft"
                                                                                          : g.units;
    in.heightBand = in.raster.bands.size();
    for (std::size_t k = 0; k < in.raster.bands.size(); ++k)
        if (in.raster.bands[k].name == "height") in.heightBand = k;
    // The only band of a DEM is its heights; that of msii's own output (e.g. --bands quality) is not.
    const bool msiiOutput = std::any_of(in.raster.metadata.begin(), in.raster.metadata.end(),
                                        [](const auto& kv) { return kv.first == "MSII_VERSION"; });
    if (in.heightBand == in.raster.bands.size() && in.raster.bands.size() == 1 && !msiiOutput) {
        in.heightBand = 0;
        in.heightsFile = std::filesystem::absolute(path).string();
    }
    if (in.heightBand < in.raster.bands.size()) in.heights = in.raster.bands[in.heightBand].values;
    if (!in.heights.empty()) {
        // As msii compute reads a DEM (terrain/dem.h): heights no terrain has are nodata.
        const UndeclaredNodata u = implausibleHeightsToNaN(in.heights, g.metresPerUnit);
        if (!u.empty()) in.warnings.push_back(describeUndeclaredNodata(u.cellsPerValue()));
    }
    if (in.heights.empty() && needHeights)  // msii compute's GeoTIFFs name their DEM
        for (const auto& [key, named] : in.raster.metadata) {
            if (key != "MSII_INPUT") continue;
            // Relative to the GeoTIFF's folder (absolute in files of earlier versions).
            const std::filesystem::path file = std::filesystem::path(named).is_absolute()
                                                   ? std::filesystem::path(named)
                                                   : std::filesystem::path(path).parent_path() / named;
            if (!std::filesystem::exists(file)) continue;
            // The DEM's cells under the GeoTIFF's: all of them, or one tile's of a mosaic.
            const DemSource source(file.string(), {});
            const RasterGeoreference& s = source.info().georeference;
            const std::array<double, 6>& t = s.transform;
            if (t[1] != g.transform[1] || t[5] != g.transform[5] || t[2] != g.transform[2] || t[4] != g.transform[4])
                continue;
            const double col = (g.transform[0] - t[0]) / t[1], row = (g.transform[3] - t[3]) / t[5];
            const int c = int(std::lround(col)), r = int(std::lround(row));
            if (std::abs(col - c) > 1e-6 || std::abs(row - r) > 1e-6 || c < 0 || r < 0 || c + g.width > s.width ||
                r + g.height > s.height)
                continue;
            Dem dem = source.read(c, r, g.width, g.height);
            in.heights = std::move(dem.heights);
            if (!dem.undeclared.empty()) in.warnings.push_back(describeUndeclaredNodata(dem.undeclared.cellsPerValue()));
            in.heightsFile = std::filesystem::absolute(file).lexically_normal().string();
        }
    return in;
}

FeatureMesh featureMeshFromRaster(const std::string& path)
{
    RasterInput in = readRasterInput(path, true);
    const RasterImage& raster = in.raster;
    const RasterGeoreference& g = raster.georeference;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    if (in.heights.empty())
        throw InvalidInputError(std::filesystem::path(path).filename().string() +
                                " has no heights: no band 'height', and its DEM (MSII_INPUT) is not where it was "
                                "(msii compute --bands ...,height writes them)");
    // The bands other than the heights become vertex properties.
    const std::size_t heightBand = in.heightBand;
    std::string radii;
    for (const auto& [key, value] : raster.metadata)
        if (key == "MSII_RADII") radii = value;
    Dem dem;
    dem.georeference = g;
    dem.heights = std::move(in.heights);
    for (float h : dem.heights) dem.numValid += !std::isnan(h);
    DemMesh dm = demToMesh(dem);
    FeatureMesh out;
    out.mesh = std::move(dm.mesh);
    out.cellSize = shortestCellStep(g);
    out.raster = FeatureRaster{g, dm.vertexOfCell, radii, in.heightsFile};
    out.warnings = in.warnings;
    for (std::size_t k = 0; k < raster.bands.size(); ++k) {
        if (k == heightBand) continue;
        VertexProperty p{raster.bands[k].name.empty() ? "band_" + std::to_string(k + 1) : raster.bands[k].name,
                         std::vector<float>(out.mesh.numVertices(), nan)};
        for (std::size_t c = 0; c < dm.vertexOfCell.size(); ++c)
            if (dm.vertexOfCell[c] != DemMesh::kNoVertex) p.values[dm.vertexOfCell[c]] = raster.bands[k].values[c];
        out.properties.push_back(std::move(p));
    }
    if (!in.units.empty()) out.comments.push_back("units " + in.units);
    if (!radii.empty()) {  // "0.9375,...,15": as msii compute's PLY comment states them
        const std::size_t n = std::size_t(std::count(radii.begin(), radii.end(), ',')) + 1;
        out.comments.push_back("msii raster compute R=" + radii.substr(radii.rfind(',') + 1) + " N=" + std::to_string(n));
    }
    return out;
}

FeatureMesh readFeatureMesh(const std::string& input, const std::vector<std::string>& matFiles)
{
    if (isRasterInput(input)) {
        if (!matFiles.empty()) throw InvalidInputError("GigaMesh files (--mat) go with meshes, not rasters");
        return featureMeshFromRaster(input);
    }
    ReadMeshOptions options;
    options.keepVertexProperties = true;
    ReadMeshResult read = readMesh(input, options);
    FeatureMesh out;
    out.mesh = std::move(read.mesh);
    out.properties = std::move(read.vertexProperties);
    out.comments = std::move(read.comments);
    for (const std::string& mat : matFiles) {
        std::vector<VertexProperty> add = featurePropertiesFromMat(mat, out.mesh.numVertices());
        const char letter = add.front().name[0];
        // A .mat replaces the whole feature vector of its invariant, whatever its length.
        out.properties.erase(std::remove_if(out.properties.begin(), out.properties.end(),
                                            [&](const VertexProperty& p) { return isFeatureName(p.name, letter); }),
                             out.properties.end());
        mergeProperties(out.properties, std::move(add));
    }
    return out;
}

void printWarnings(const std::string& input, const std::vector<std::string>& warnings, bool quiet)
{
    if (quiet) return;
    for (const std::string& w : warnings)
        std::fprintf(stderr, "msii: warning: %s: %s\n", input.c_str(), printableLine(w).c_str());
}

void qualityWithoutNaN(std::vector<VertexProperty>& properties)
{
    for (VertexProperty& p : properties)
        if (p.name == "quality")
            for (float& v : p.values)
                if (std::isnan(v)) v = 0.0f;
}

std::size_t findProperty(const FeatureMesh& in, const std::string& name)
{
    for (std::size_t k = 0; k < in.properties.size(); ++k)
        if (in.properties[k].name == name) return k;
    std::string present;
    for (const auto& p : in.properties) present += (present.empty() ? "" : " ") + p.name;
    throw InvalidInputError("the input has no vertex property '" + name + "' (it has: " +
                            (present.empty() ? std::string("none") : present) + ")");
}

std::vector<std::size_t> findProperties(const FeatureMesh& in, const std::string& commaList)
{
    std::vector<std::size_t> out;
    std::stringstream list(commaList);
    std::string name;
    while (std::getline(list, name, ','))
        if (!name.empty()) out.push_back(findProperty(in, name));
    if (out.empty()) throw InvalidInputError("--properties names no property");
    return out;
}

std::vector<double> parseNumberList(const std::string& text, const std::string& option)
{
    std::vector<double> out;
    std::stringstream list(text);
    std::string item;
    while (std::getline(list, item, ',')) {
        std::size_t used = 0;
        double v = 0;
        try {
            v = std::stod(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != item.size() || !std::isfinite(v))
            throw InvalidInputError(option + ": '" + item + "' is not a number");
        out.push_back(v);
    }
    return out;
}

void writeFeatureRaster(const std::string& path, const FeatureMesh& in, const std::vector<const VertexProperty*>& bands,
                        const std::string& description)
{
    const FeatureRaster& r = *in.raster;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<RasterBand> out;
    for (const VertexProperty* p : bands) {
        RasterBand b{p->name, std::vector<float>(r.vertexOfCell.size(), nan)};
        for (std::size_t c = 0; c < r.vertexOfCell.size(); ++c)
            if (r.vertexOfCell[c] != DemMesh::kNoVertex) b.values[c] = p->values[r.vertexOfCell[c]];
        out.push_back(std::move(b));
    }
    RasterOutputOptions options;
    options.description = description;
    if (!r.radii.empty()) options.metadata.push_back({"MSII_RADII", r.radii});
    options.metadata.push_back({"MSII_VERSION", versionString()});
    // Relative to the output's folder, as msii compute writes it: found again when both move together.
    if (!r.heightsFile.empty())
        options.metadata.push_back(
            {"MSII_INPUT",
             fs::path(r.heightsFile).lexically_relative(fs::absolute(path).parent_path()).string()});
    writeRaster(path, r.grid, out, options);
}

std::string featureOutputExtension(const std::string& input, const std::string& output)
{
    if (!isRasterInput(input)) return ".ply";
    return fs::path(output).extension() == ".ply" ? ".ply" : ".tif";
}

std::string outputPath(const std::string& input, const std::string& output, const std::string& suffix,
                       bool overwrite, const std::string& extension)
{
    std::string path = output;
    if (path.empty()) {
        const fs::path in(input);
        path = (in.parent_path() / (in.stem().string() + "." + suffix + extension)).string();
    }
    if (fs::path(path).extension() != extension)
        throw InvalidInputError("the output '" + path + "' must be a " + extension + " file");
    checkOutputs({path}, overwrite);
    return path;
}

} // namespace msii::tools
