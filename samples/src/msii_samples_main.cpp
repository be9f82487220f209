/// @file msii_samples_main.cpp
/// @brief `msii-samples`: writes the deterministic sample meshes of
/// msii/samples/generators.h as PLY files (for the demo, the benchmark, and by hand).
///
///   msii-samples SHAPE --output FILE.ply [--spacing S] [--seed N] [shape options]
///   msii-samples --list
///
/// Open height fields (plane, terrain, tablet without --closed) in binary are streamed to
/// the file a band of rows at a time, so their size is limited by the disk, not by memory
/// (e.g. a 50M-vertex terrain for the benchmark).
///
/// Exit codes: 0 success; 2 bad command line or invalid option values (one line
/// "msii-samples: error: ..." on stderr); 1 any other failure (e.g. the file cannot be
/// written).

#include <msii/core/errors.h>
#include <msii/io/write_ply.h>
#include <msii/samples/generators.h>
#include <msii/terrain/raster_output.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <exception>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct ShapeInfo {
    const char* name;
    const char* description;
};

constexpr std::array<ShapeInfo, 6> kShapes = {{
    {"sphere", "closed sphere (jittered geodesic icosphere), vertices exactly on it; --radius, --center"},
    {"cavity", "the sphere with reversed orientation: the solid is outside (a spherical cavity)"},
    {"cube", "closed cube [0, side]^3, irregularly triangulated faces; --side"},
    {"plane", "flat open patch z = 0 over [0, width] x [0, height] (--closed: a slab)"},
    {"terrain", "smooth random hills and valleys, amplitude ~ --relief (--closed: a slab)"},
    {"tablet", "curved clay-tablet face with cuneiform wedge impressions (--closed: a slab)"},
}};

/// A usage error found after parsing (exit code 2).
struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

msii::Vec3 parseTriple(const std::string& text, const std::string& option)
{
    std::array<double, 3> c{};
    std::istringstream in(text);
    for (int k = 0; k < 3; ++k) {
        if (k > 0) {
            char comma = 0;
            if (!(in >> comma) || comma != ',') throw UsageError(option + " must be x,y,z (got '" + text + "')");
        }
        if (!(in >> c[std::size_t(k)])) throw UsageError(option + " must be x,y,z (got '" + text + "')");
    }
    in >> std::ws;
    if (!in.eof()) throw UsageError(option + " must be x,y,z (got '" + text + "')");
    return {c[0], c[1], c[2]};
}

int fail(int code, const std::string& message)
{
    std::cerr << "msii-samples: error: " << message << '\n';
    return code;
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"Writes deterministic, seedable sample meshes (irregular, scanner-like triangulations) "
                 "as PLY. Units are mm. The same options give the same mesh on every machine. Open height "
                 "fields (plane, terrain, tablet) in binary are streamed to the file, so their size is "
                 "limited by the disk, not by memory."};
    app.set_help_flag("-h,--help", "Print this help message and exit");

    std::string shape, output, centerText;
    double spacing = 0, radius = 0, side = 0, width = 0, height = 0, thickness = 0, relief = 0, noise = 0;
    double wedgeSize = 0, wedgeDensity = 0, holeSize = 0;
    std::size_t holes = 0;
    std::uint64_t seed = 1;
    bool closed = false, cavity = false, ascii = false, doublePoints = false, quiet = false, list = false;

    std::vector<std::string> shapeNames;
    for (const auto& s : kShapes) shapeNames.emplace_back(s.name);
    app.add_option("shape", shape, "Shape to generate (see --list)")->check(CLI::IsMember(shapeNames));
    app.add_flag("--list", list, "List the shapes with a one-line description and exit");
    app.add_option("-o,--output", output, "Output PLY file");
    auto* optSpacing = app.add_option("--spacing", spacing, "Mean vertex spacing, mm (~area / spacing^2 vertices)");
    // CLI11 would wrap "-3" around to 2^64 - 3; accept plain digits only.
    const CLI::Validator digitsOnly(
        [](std::string& text) {
            const bool ok = !text.empty() && text.size() <= 20 &&
                            std::all_of(text.begin(), text.end(), [](char ch) { return ch >= '0' && ch <= '9'; }) &&
                            (text.size() < 20 || text <= "18446744073709551615");
            return ok ? std::string() : "'" + text + "' is not an integer in 0 .. 2^64-1";
        },
        "", "UINT");
    app.add_option("--seed", seed, "Random seed, 0 .. 2^64-1 (default 1)")->check(digitsOnly);
    auto* optRadius = app.add_option("--radius", radius, "sphere/cavity: radius, mm (default 10)");
    auto* optCenter = app.add_option("--center", centerText, "sphere/cavity: centre x,y,z, mm (default 0,0,0)");
    std::string offsetText;
    auto* optOffset = app.add_option("--offset", offsetText,
                                     "Move the mesh by x,y,z: e.g. 500000,5500000,300 puts it in UTM-like "
                                     "coordinates, as georeferenced scans come (written in double precision)");
    auto* optCavity = app.add_flag("--cavity", cavity, "sphere: reverse the orientation (same as shape cavity)");
    auto* optSide = app.add_option("--side", side, "cube: edge length, mm (default 10)");
    auto* optWidth = app.add_option("--width", width, "plane/terrain/tablet: extent along x, mm (default 20)");
    auto* optHeight = app.add_option("--height", height, "plane/terrain/tablet: extent along y, mm (default 15)");
    auto* optClosed = app.add_flag("--closed", closed, "plane/terrain/tablet: closed slab instead of an open patch");
    auto* optThickness = app.add_option("--thickness", thickness, "slab thickness below z = 0, mm (default 5)");
    double wallStep = 0, anisotropy = 1, densityVariation = 1, roughness = 0;
    auto* optAnisotropy = app.add_option("--anisotropy", anisotropy,
                                         "plane/terrain/tablet: triangles this many times longer along x than y (default 1)");
    auto* optDensity = app.add_option("--density-variation", densityVariation,
                                      "plane/terrain/tablet: densest / sparsest vertex density, varying smoothly (default 1)");
    auto* optRoughness = app.add_option("--roughness", roughness,
                                        "plane/terrain/tablet: white scanner noise, z moved by up to this, mm (default 0)");
    auto* optWallStep = app.add_option("--wall-step", wallStep,
                                       "with --closed: walls and bottom of a few long triangles, bottom outline vertices "
                                       "this far apart, mm (as many meshers make them; default: as fine as the top)");
    auto* optRelief = app.add_option("--relief", relief, "terrain: hill amplitude, mm (default 1)");
    double hillWidth = 0;
    auto* optHillWidth = app.add_option("--hill-width", hillWidth, "terrain: typical hill width (Gaussian sigma), mm (default 2.5)");
    auto* optNoise = app.add_option("--noise", noise, "terrain/tablet: smooth noise amplitude, mm (default 0.002)");
    auto* optWedgeSize = app.add_option("--wedge-size", wedgeSize, "tablet: mean wedge length, mm (default 1.5)");
    auto* optWedgeDensity = app.add_option("--wedge-density", wedgeDensity, "tablet: wedges per mm^2 (default 0.15)");
    app.add_option("--holes", holes,
                   "Scanner-like holes: remove the faces around this many seeded spots (vertices are kept)");
    auto* optHoleSize = app.add_option("--hole-size", holeSize,
                                       "With --holes: largest hole radius, mm (default 2 spacings; the smallest is a "
                                       "quarter of it)");
    bool geotiff = false;
    std::string crs = "EPSG:25832";
    auto* optGeotiff = app.add_flag(
        "--geotiff", geotiff,
        "plane/terrain/tablet: write a DEM instead of a mesh: a GeoTIFF of heights on a regular grid of "
        "--spacing cells, in metres, its corner at --offset x,y (default 512000,5498000, UTM-like) lifted by z "
        "(default 300), in --crs; --holes makes nodata patches up to --hole-size in radius");
    auto* optCrs = app.add_option("--crs", crs, "With --geotiff: the coordinate system (default EPSG:25832, ETRS89 / UTM 32N)");
    app.add_flag("--ascii", ascii, "Write ascii PLY (default binary little endian)");
    app.add_flag("--double", doublePoints, "Write coordinates as double (exact) instead of float");
    app.add_flag("-q,--quiet", quiet, "Do not print the summary line");

    try {
        app.parse(argc, argv);
    } catch (const CLI::Success& e) {  // --help, --help-all
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        return fail(2, e.what());
    }

    if (list) {
        for (const auto& s : kShapes) std::cout << s.name << std::string(10 - std::string(s.name).size(), ' ') << s.description << '\n';
        return 0;
    }

    try {
        if (shape.empty()) throw UsageError("a SHAPE is required (one of sphere, cavity, cube, plane, terrain, tablet; see --list)");
        if (output.empty()) throw UsageError("--output FILE.ply is required");

        // Options that do not apply to the shape are rejected rather than silently ignored.
        const std::map<const CLI::Option*, std::set<std::string>> applies = {
            {optRadius, {"sphere", "cavity"}},
            {optCenter, {"sphere", "cavity"}},
            {optCavity, {"sphere", "cavity"}},
            {optSide, {"cube"}},
            {optWidth, {"plane", "terrain", "tablet"}},
            {optHeight, {"plane", "terrain", "tablet"}},
            {optClosed, {"plane", "terrain", "tablet"}},
            {optThickness, {"plane", "terrain", "tablet"}},
            {optWallStep, {"plane", "terrain", "tablet"}},
            {optAnisotropy, {"plane", "terrain", "tablet"}},
            {optDensity, {"plane", "terrain", "tablet"}},
            {optRoughness, {"plane", "terrain", "tablet"}},
            {optRelief, {"terrain"}},
            {optHillWidth, {"terrain"}},
            {optNoise, {"terrain", "tablet"}},
            {optWedgeSize, {"tablet"}},
            {optWedgeDensity, {"tablet"}},
            {optGeotiff, {"plane", "terrain", "tablet"}},
        };
        for (const auto& [opt, shapes] : applies)
            if (opt->count() > 0 && shapes.count(shape) == 0)
                throw UsageError("option " + opt->get_name() + " does not apply to shape " + shape);
        if (optThickness->count() > 0 && !closed) throw UsageError("--thickness needs --closed");
        if (optWallStep->count() > 0 && !closed) throw UsageError("--wall-step needs --closed");
        if (optCrs->count() > 0 && !geotiff) throw UsageError("--crs needs --geotiff");
        if (geotiff && (closed || ascii || doublePoints || anisotropy != 1 || densityVariation != 1 || roughness > 0))
            throw UsageError("--geotiff writes a regular grid: not with --closed, --ascii, --double, --anisotropy, "
                             "--density-variation or --roughness");
        if (optHoleSize->count() > 0 && holes == 0) throw UsageError("--hole-size needs --holes");

        msii::TriMesh mesh;
        std::ostringstream comment;
        comment << "msii-samples " << shape << " seed " << seed;
        if (shape == "sphere" || shape == "cavity") {
            msii::samples::SphereOptions o;
            if (optSpacing->count()) o.spacing = spacing;
            if (optRadius->count()) o.radius = radius;
            if (optCenter->count()) o.center = parseTriple(centerText, "--center");
            o.cavity = cavity || shape == "cavity";
            o.seed = seed;
            comment << " radius " << o.radius << " spacing " << o.spacing << (o.cavity ? " cavity" : "");
            mesh = msii::samples::makeSphere(o);
        } else if (shape == "cube") {
            msii::samples::CubeOptions o;
            if (optSpacing->count()) o.spacing = spacing;
            if (optSide->count()) o.side = side;
            o.seed = seed;
            comment << " side " << o.side << " spacing " << o.spacing;
            mesh = msii::samples::makeCube(o);
        } else {
            msii::samples::HeightFieldOptions o;
            o.kind = shape == "plane" ? msii::samples::HeightFieldKind::Plane
                     : shape == "terrain" ? msii::samples::HeightFieldKind::Terrain
                                          : msii::samples::HeightFieldKind::Tablet;
            if (optSpacing->count()) o.spacing = spacing;
            if (optWidth->count()) o.width = width;
            if (optHeight->count()) o.height = height;
            if (optThickness->count()) o.thickness = thickness;
            o.wallStep = wallStep;
            o.anisotropy = anisotropy;
            o.densityVariation = densityVariation;
            o.roughness = roughness;
            if (optRelief->count()) o.relief = relief;
            if (optHillWidth->count()) o.hillWidth = hillWidth;
            if (optNoise->count()) o.noise = noise;
            if (optWedgeSize->count()) o.wedgeSize = wedgeSize;
            if (optWedgeDensity->count()) o.wedgeDensity = wedgeDensity;
            o.closed = closed;
            o.seed = seed;
            comment << " width " << o.width << " height " << o.height << " spacing " << o.spacing;
            if (o.closed) comment << " closed thickness " << o.thickness;
            if (o.wallStep > 0) comment << " wall step " << o.wallStep;
            if (o.anisotropy != 1) comment << " anisotropy " << o.anisotropy;
            if (o.densityVariation != 1) comment << " density variation " << o.densityVariation;
            if (o.roughness > 0) comment << " roughness " << o.roughness;
            if (geotiff) {
                msii::samples::DemSampleOptions d;
                d.surface = o;
                d.crs = crs;
                if (optOffset->count()) {
                    const msii::Vec3 at = parseTriple(offsetText, "--offset");
                    d.west = at.x, d.north = at.y, d.baseHeight = at.z;
                }
                d.nodataPatches = holes;
                d.patchRadius = optHoleSize->count() ? holeSize : 0;
                const msii::Dem dem = msii::samples::makeDem(d);
                msii::RasterOutputOptions ro;
                ro.nodata = -9999.0;  // as DEMs often have it
                ro.description = comment.str() + " geotiff";
                try {
                    msii::writeRaster(output, dem.georeference, {{"height", dem.heights}}, ro);
                } catch (const msii::IOError& e) {
                    return fail(1, e.what());
                }
                if (!quiet)
                    std::cout << output << ": " << dem.georeference.width << " x " << dem.georeference.height
                              << " cells, " << dem.heights.size() - dem.numValid << " nodata\n";
                return 0;
            }
            if (!o.closed && !ascii && holes == 0 && optOffset->count() == 0) {
                // Streamed: never held in memory, so any size the disk takes.
                msii::WritePlyOptions plyOptions;
                plyOptions.forceDoublePoints = doublePoints;
                plyOptions.comments.push_back(comment.str());
                msii::samples::StreamedMeshCounts counts;
                try {
                    counts = msii::samples::writeHeightFieldPly(o, output, plyOptions);
                } catch (const msii::IOError& e) {
                    return fail(1, e.what());
                }
                if (!quiet) std::cout << output << ": " << counts.vertices << " vertices, " << counts.triangles << " triangles\n";
                return 0;
            }
            mesh = msii::samples::makeHeightField(o);
        }

        if (holes > 0) {
            msii::samples::HoleOptions ho;
            ho.count = holes;
            const double step = optSpacing->count()                       ? spacing
                                : shape == "sphere" || shape == "cavity" ? msii::samples::SphereOptions{}.spacing
                                : shape == "cube"                        ? msii::samples::CubeOptions{}.spacing
                                                                         : msii::samples::HeightFieldOptions{}.spacing;
            ho.maxSize = optHoleSize->count() ? holeSize : 2.0 * step;
            ho.minSize = 0.25 * ho.maxSize;
            ho.seed = seed;
            const msii::samples::HoleReport made = msii::samples::punchHoles(mesh, ho);
            comment << " holes " << made.holes << " up to " << ho.maxSize;
        }
        if (optOffset->count()) {
            const msii::Vec3 offset = parseTriple(offsetText, "--offset");
            for (msii::Vec3& p : mesh.points) p += offset;
            comment << " offset " << offsetText;
        }
        msii::WritePlyOptions plyOptions;
        plyOptions.binary = !ascii;
        plyOptions.forceDoublePoints = doublePoints;
        plyOptions.comments.push_back(comment.str());
        try {
            msii::writePly(output, mesh, {}, plyOptions);
        } catch (const msii::Error& e) {
            return fail(1, e.what());  // I/O, not usage
        }
        if (!quiet)
            std::cout << output << ": " << mesh.numVertices() << " vertices, " << mesh.numTriangles() << " triangles\n";
        return 0;
    } catch (const UsageError& e) {
        return fail(2, e.what());
    } catch (const msii::InvalidInputError& e) {
        return fail(2, e.what());
    } catch (const std::exception& e) {
        return fail(1, e.what());
    }
}
