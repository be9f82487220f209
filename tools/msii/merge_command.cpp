/// `msii merge PART... -o OUT.ply`: joins the tiles of one mesh computed separately
/// (`msii compute --tiles K --tile I`, e.g. one cluster job each) into the result of the
/// whole mesh, equal to computing it in one piece.
#include "commands.h"
#include "feature_input.h"

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/io/write_ply.h>
#include <msii/terrain/raster_output.h>
#include <msii/tiling/tiled_compute.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <cmath>
#include <regex>
#include <set>

namespace msii::tools {

namespace {

struct MergeArgs : CommonArgs {
    std::vector<std::string> parts;
    std::string output;
};

/// Whether @p path is a raster (a part written by `msii compute --tile-of-mosaic`).
bool isRasterPart(const std::string& path)
{
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".tif" || ext == ".tiff";
}

/// The parts of a mosaic joined into a VRT (docs/terrain.md, Mosaics on a cluster).
int mergeRasterParts(const MergeArgs& args)
{
    const Stopwatch total;
    const std::string output = args.output.empty()
                                   ? (std::filesystem::path(args.parts.front()).parent_path() / "mosaic.msii.vrt").string()
                                   : args.output;
    if (std::filesystem::exists(output) && !args.overwrite)
        throw InvalidInputError("'" + output + "' exists already (use --overwrite to replace it)");
    for (const std::string& part : args.parts)
        if (!isRasterPart(part)) throw InvalidInputError(part + " is not a GeoTIFF: give the parts of one mosaic");
    joinRasterParts(args.parts, output);
    if (!args.quiet)
        std::fprintf(stderr, "msii: %zu parts -> %s (%.1f s)\n", args.parts.size(), output.c_str(), total.seconds());
    return 0;
}

int runMerge(const MergeArgs& args)
{
    if (isRasterPart(args.parts.front())) return mergeRasterParts(args);
    const Stopwatch total;
    const std::string output = outputPath(args.parts.front(), args.output, "merged", args.overwrite);
    static const std::regex tileLine(R"(^msii tile ([0-9]+) of ([0-9]+) x ([0-9]+))");
    FeatureMesh merged;
    std::vector<char> written;  // per vertex: some part computed it
    std::set<int> seen;
    int tilesPerAxis = 0;
    // Which vertices a part computed: those whose filled_share is a number (msii compute
    // writes it for every vertex of the tile, and NaN elsewhere). Tiles are cut on the
    // prepared mesh, whose box can differ from the file's (vertices in no face are left
    // out), so the file's own tile grid is only the fallback for parts without it.
    const auto computedBy = [](const FeatureMesh& part, int tile, int k) {
        std::vector<char> own(part.mesh.numVertices(), 0);
        for (const VertexProperty& p : part.properties)
            if (p.name == "filled_share") {
                for (std::size_t i = 0; i < own.size(); ++i) own[i] = !std::isnan(p.values[i]);
                return own;
            }
        const std::vector<int> owner = tileOfVertices(part.mesh, k);
        for (std::size_t i = 0; i < own.size(); ++i) own[i] = owner[i] == tile;
        return own;
    };
    for (const std::string& part : args.parts) {
        FeatureMesh in = readFeatureMesh(part, {});
        int tile = -1, k = 0;
        std::vector<std::string> kept;
        for (const std::string& c : in.comments) {
            std::smatch m;
            if (std::regex_search(c, m, tileLine)) tile = std::stoi(m[1].str()), k = std::stoi(m[2].str());
            else kept.push_back(c);
        }
        if (tile < 0) throw InvalidInputError(part + " is not a tile of msii compute --tiles K --tile I");
        const std::vector<char> own = computedBy(in, tile, k);
        if (merged.properties.empty()) {
            tilesPerAxis = k;
            written = own;
            merged = std::move(in);
            merged.comments = kept;
        } else {
            if (k != tilesPerAxis || in.mesh.numVertices() != merged.mesh.numVertices() ||
                in.mesh.points != merged.mesh.points || in.properties.size() != merged.properties.size())
                throw InvalidInputError(part + " is not a tile of the same mesh and run as " + args.parts.front());
            for (std::size_t q = 0; q < in.properties.size(); ++q) {
                if (in.properties[q].name != merged.properties[q].name)
                    throw InvalidInputError(part + " has other features than " + args.parts.front());
                for (std::size_t i = 0; i < own.size(); ++i)
                    if (own[i]) merged.properties[q].values[i] = in.properties[q].values[i];
            }
            for (std::size_t i = 0; i < own.size(); ++i) written[i] |= own[i];
        }
        if (!seen.insert(tile).second) throw InvalidInputError("tile " + std::to_string(tile) + " is given twice");
    }
    // Every vertex of a face must have been computed by some part; else a tile is missing.
    for (const Triangle& t : merged.mesh.triangles)
        for (std::uint32_t v : t)
            if (!written[v]) {
                for (int tile = 0; tile < tilesPerAxis * tilesPerAxis; ++tile)
                    if (!seen.count(tile))
                        throw InvalidInputError("tile " + std::to_string(tile) + " of " + std::to_string(tilesPerAxis) +
                                                " x " + std::to_string(tilesPerAxis) + " is missing");
                throw InvalidInputError("vertex " + std::to_string(v) + " was computed by none of the parts");
            }
    WritePlyOptions plyOptions;
    plyOptions.propertyPrefix = args.propertyPrefix;
    plyOptions.comments = merged.comments;
    qualityWithoutNaN(merged.properties);
    writePly(output, merged.mesh, merged.properties, plyOptions);
    if (!args.quiet)
        std::fprintf(stderr, "msii: %zu tiles -> %s (%zu vertices, %.1f s)\n", args.parts.size(), output.c_str(),
                     merged.mesh.numVertices(), total.seconds());
    return 0;
}

} // namespace

std::function<int()> addMergeCommand(CLI::App& app)
{
    auto args = std::make_shared<MergeArgs>();
    CLI::App* cmd = app.add_subcommand(
        "merge", "Join the tiles of one mesh computed separately (msii compute --tiles K --tile I) into "
                 "the whole result, equal to computing it in one piece.");
    cmd->add_option("parts", args->parts,
                    "The tiles' PLY files (any order), or the GeoTIFFs of a mosaic's tiles "
                    "(msii compute --tile-of-mosaic), joined into a VRT")
        ->required();
    cmd->add_option("-o,--output", args->output,
                    "Output PLY (default <first part's stem>.merged.ply), or VRT for GeoTIFF parts (default "
                    "mosaic.msii.vrt next to the first)");
    addCommonOptions(cmd, *args);
    addPropertyNamesOption(cmd, args->propertyPrefix);
    return [args]() {
        const auto limit = limitThreads(args->threads);
        return runMerge(*args);
    };
}

} // namespace msii::tools
