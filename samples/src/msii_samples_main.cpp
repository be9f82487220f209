/// @file msii_samples_main.cpp
/// @brief `msii-samples`: writes the deterministic sample meshes of
/// msii/samples/generators.h and msii/samples/vessels.h as PLY files (for the demo, the
/// benchmark, the tests, and by hand); vessels, sherds and seals with their known answers
/// (--truth FILE.json).
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
#include <msii/io/atomic_file.h>
#include <msii/io/write_ply.h>
#include <msii/samples/generators.h>
#include <msii/samples/vessels.h>
#include <msii/terrain/raster_output.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <charconv>
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

constexpr std::array<ShapeInfo, 10> kShapes = {{
    {"sphere", "closed sphere (jittered geodesic icosphere), vertices exactly on it; --radius, --center"},
    {"cavity", "the sphere with reversed orientation: the solid is outside (a spherical cavity)"},
    {"cube", "closed cube [0, side]^3, irregularly triangulated faces; --side"},
    {"plane", "flat open patch z = 0 over [0, width] x [0, height] (--closed: a slab)"},
    {"terrain", "smooth random hills and valleys, amplitude ~ --relief (--closed: a slab)"},
    {"tablet", "curved clay-tablet face with cuneiform wedge impressions (--closed: a slab)"},
    {"rounded-tablet", "a whole tablet, closed: rounded box, bulging reverse, marks on all six sides; --marks-csv"},
    {"vessel", "a pot, closed: a profile (--profile cylinder|cone|vase) revolved, marks in its wall; --truth"},
    {"sherd", "a piece of a vessel's wall, jagged breaks (--angle, --from, --to or --rim); --truth"},
    {"seal", "a cylinder seal, marks engraved in its side; --truth"},
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

/// The command line: the values given, and the options themselves, which tell whether a
/// value was given.
struct Arguments {
    std::string shape, output, centerText, offsetText, crs = "EPSG:25832", marksText, marksCsv;
    std::string profile = "vase", truth;
    double spacing = 0, radius = 0, side = 0, width = 0, height = 0, thickness = 0, relief = 0, noise = 0;
    double wedgeSize = 0, wedgeDensity = 0, holeSize = 0, wallStep = 0, anisotropy = 1, densityVariation = 1;
    double roughness = 0, hillWidth = 0, rounding = 0, reverseBulge = 0, markRadius = 0, markDepth = 0;
    double topRadius = 0, wall = 0, base = 0, angle = 0, from = 0, to = 0;
    std::size_t holes = 0;
    std::uint64_t seed = 1, poseSeed = 0;
    bool closed = false, cavity = false, ascii = false, doublePoints = false, quiet = false, list = false;
    bool rim = false;
    bool geotiff = false;
    CLI::Option *optSpacing = nullptr, *optRadius = nullptr, *optCenter = nullptr, *optOffset = nullptr;
    CLI::Option *optCavity = nullptr, *optSide = nullptr, *optWidth = nullptr, *optHeight = nullptr;
    CLI::Option *optClosed = nullptr, *optThickness = nullptr, *optAnisotropy = nullptr, *optDensity = nullptr;
    CLI::Option *optRoughness = nullptr, *optWallStep = nullptr, *optRelief = nullptr, *optHillWidth = nullptr;
    CLI::Option *optNoise = nullptr, *optWedgeSize = nullptr, *optWedgeDensity = nullptr, *optHoleSize = nullptr;
    CLI::Option *optGeotiff = nullptr, *optCrs = nullptr;
    CLI::Option *optRounding = nullptr, *optReverseBulge = nullptr, *optMarks = nullptr, *optMarkRadius = nullptr;
    CLI::Option *optMarkDepth = nullptr, *optMarksCsv = nullptr;
    CLI::Option *optProfile = nullptr, *optTopRadius = nullptr, *optWall = nullptr, *optBase = nullptr;
    CLI::Option *optAngle = nullptr, *optFrom = nullptr, *optTo = nullptr, *optRim = nullptr;
    CLI::Option *optPoseSeed = nullptr, *optTruth = nullptr;
};

/// The options of the vessels, sherds and seals (msii/samples/vessels.h).
void addVesselOptions(CLI::App& app, Arguments& a, const CLI::Validator& digitsOnly)
{
    a.optProfile = app.add_option("--profile", a.profile, "vessel/sherd: the outer wall's shape (default vase)")
                       ->check(CLI::IsMember({"cylinder", "cone", "vase"}));
    a.optTopRadius = app.add_option("--top-radius", a.topRadius,
                                    "vessel/sherd with --profile cone: outer radius at the rim, mm (default 35)");
    a.optWall = app.add_option("--wall", a.wall, "vessel/sherd: wall thickness, mm (default 5)");
    a.optBase = app.add_option("--base", a.base, "vessel/sherd: base thickness, mm (default 6)");
    a.optAngle = app.add_option("--angle", a.angle, "sherd: degrees of the circumference it covers (default 75)");
    a.optFrom = app.add_option("--from", a.from, "sherd: lowest z of its outer wall, mm (default 40)");
    a.optTo = app.add_option("--to", a.to, "sherd: highest z of its outer wall, mm (default 80)");
    a.optRim = app.add_flag("--rim", a.rim, "sherd: the piece reaches the rim (its top is the lip; not with --to)");
    a.optPoseSeed = app.add_option("--pose-seed", a.poseSeed,
                                   "vessel/sherd/seal: 0 (default) as built, axis z; otherwise a seeded rotation and "
                                   "a translation of up to 1000 mm")
                        ->check(digitsOnly);
    a.optTruth = app.add_option("--truth", a.truth,
                                "vessel/sherd/seal: also write the known answers as JSON (axis, rim diameter, "
                                "height, marks, profiles)");
}

void addOptions(CLI::App& app, Arguments& a)
{
    std::vector<std::string> shapeNames;
    for (const auto& s : kShapes) shapeNames.emplace_back(s.name);
    app.add_option("shape", a.shape, "Shape to generate (see --list)")->check(CLI::IsMember(shapeNames));
    app.add_flag("--list", a.list, "List the shapes with a one-line description and exit");
    app.add_option("-o,--output", a.output, "Output PLY file");
    a.optSpacing = app.add_option("--spacing", a.spacing, "Mean vertex spacing, mm (~area / spacing^2 vertices)");
    // CLI11 would wrap "-3" around to 2^64 - 3; accept plain digits only.
    const CLI::Validator digitsOnly(
        [](std::string& text) {
            const bool ok = !text.empty() && text.size() <= 20 &&
                            std::all_of(text.begin(), text.end(), [](char ch) { return ch >= '0' && ch <= '9'; }) &&
                            (text.size() < 20 || text <= "18446744073709551615");
            return ok ? std::string() : "'" + text + "' is not an integer in 0 .. 2^64-1";
        },
        "", "UINT");
    app.add_option("--seed", a.seed, "Random seed, 0 .. 2^64-1 (default 1)")->check(digitsOnly);
    a.optRadius = app.add_option("--radius", a.radius,
                                 "sphere/cavity: radius, mm (default 10); vessel/sherd: outer radius (the cone's at "
                                 "the base, the vase's widest; default 50); seal (default 12.5)");
    a.optCenter = app.add_option("--center", a.centerText, "sphere/cavity: centre x,y,z, mm (default 0,0,0)");
    a.optOffset = app.add_option("--offset", a.offsetText,
                                 "Move the mesh by x,y,z: e.g. 500000,5500000,300 puts it in UTM-like "
                                 "coordinates, as georeferenced scans come (written in double precision)");
    a.optCavity = app.add_flag("--cavity", a.cavity, "sphere: reverse the orientation (same as shape cavity)");
    a.optSide = app.add_option("--side", a.side, "cube: edge length, mm (default 10)");
    a.optWidth = app.add_option("--width", a.width,
                                "plane/terrain/tablet: extent along x, mm (default 20; rounded-tablet 24)");
    a.optHeight = app.add_option("--height", a.height,
                                 "plane/terrain/tablet: extent along y, mm (default 15; rounded-tablet 32); "
                                 "vessel/sherd: base bottom to rim top (default 120); seal (default 35)");
    a.optClosed = app.add_flag("--closed", a.closed, "plane/terrain/tablet: closed slab instead of an open patch");
    a.optThickness = app.add_option("--thickness", a.thickness,
                                    "slab thickness below z = 0, mm (default 5); rounded-tablet: along z (default 10)");
    a.optRounding = app.add_option("--rounding", a.rounding, "rounded-tablet: radius of edges and corners, mm (default 2.5)");
    a.optReverseBulge = app.add_option("--reverse-bulge", a.reverseBulge,
                                       "rounded-tablet: rise of the reverse's centre, mm (default 1.5; the obverse's is 0.1)");
    a.optMarks = app.add_option("--marks", a.marksText,
                                "rounded-tablet: marks on the obverse, reverse, top, bottom, left and right sides "
                                "(default 6,5,1,2,4,3)");
    a.optMarkRadius = app.add_option("--mark-radius", a.markRadius,
                                     "rounded-tablet/seal: radius of a mark, mm (default 1); vessel/sherd (default 2)");
    a.optMarkDepth = app.add_option("--mark-depth", a.markDepth,
                                    "rounded-tablet/seal: depth of a mark, mm (default 0.4); vessel/sherd (default "
                                    "0.6); 0: no marks on vessels, sherds and seals");
    a.optMarksCsv = app.add_option("--marks-csv", a.marksCsv,
                                   "rounded-tablet: also write the marks as CSV (side,x,y,z,nx,ny,nz,radius,depth)");
    a.optAnisotropy = app.add_option("--anisotropy", a.anisotropy,
                                     "plane/terrain/tablet: triangles this many times longer along x than y (default 1)");
    a.optDensity = app.add_option("--density-variation", a.densityVariation,
                                  "plane/terrain/tablet: densest / sparsest vertex density, varying smoothly (default 1)");
    a.optRoughness = app.add_option("--roughness", a.roughness,
                                    "plane/terrain/tablet: white scanner noise, z moved by up to this, mm (default 0); "
                                    "rounded-tablet/vessel/sherd/seal: along the normal");
    a.optWallStep = app.add_option("--wall-step", a.wallStep,
                                   "with --closed: walls and bottom of a few long triangles, bottom outline vertices "
                                   "this far apart, mm (as many meshers make them; default: as fine as the top)");
    a.optRelief = app.add_option("--relief", a.relief, "terrain: hill amplitude, mm (default 1)");
    a.optHillWidth = app.add_option("--hill-width", a.hillWidth,
                                    "terrain: typical hill width (Gaussian sigma), mm (default 2.5)");
    a.optNoise = app.add_option("--noise", a.noise, "terrain/tablet: smooth noise amplitude, mm (default 0.002)");
    a.optWedgeSize = app.add_option("--wedge-size", a.wedgeSize, "tablet: mean wedge length, mm (default 1.5)");
    a.optWedgeDensity = app.add_option("--wedge-density", a.wedgeDensity, "tablet: wedges per mm^2 (default 0.15)");
    app.add_option("--holes", a.holes,
                   "Scanner-like holes: remove the faces around this many seeded spots (vertices are kept)");
    a.optHoleSize = app.add_option("--hole-size", a.holeSize,
                                   "With --holes: largest hole radius, mm (default 2 spacings; the smallest is a "
                                   "quarter of it)");
    a.optGeotiff = app.add_flag(
        "--geotiff", a.geotiff,
        "plane/terrain/tablet: write a DEM instead of a mesh: a GeoTIFF of heights on a regular grid of "
        "--spacing cells, in metres, its corner at --offset x,y (default 512000,5498000, UTM-like) lifted by z "
        "(default 300), in --crs; --holes makes nodata patches up to --hole-size in radius");
    a.optCrs = app.add_option("--crs", a.crs, "With --geotiff: the coordinate system (default EPSG:25832, ETRS89 / UTM 32N)");
    addVesselOptions(app, a, digitsOnly);
    app.add_flag("--ascii", a.ascii, "Write ascii PLY (default binary little endian)");
    app.add_flag("--double", a.doublePoints, "Write coordinates as double (exact) instead of float");
    app.add_flag("-q,--quiet", a.quiet, "Do not print the summary line");
}

/// @throw UsageError without a shape or an output, for options that do not apply to the
/// shape (rejected rather than silently ignored), and for options that need another.
void checkUsage(const Arguments& a)
{
    if (a.shape.empty())
        throw UsageError("a SHAPE is required (one of sphere, cavity, cube, plane, terrain, tablet, rounded-tablet, "
                         "vessel, sherd, seal; see --list)");
    if (a.output.empty()) throw UsageError("--output FILE.ply is required");
    const std::map<const CLI::Option*, std::set<std::string>> applies = {
        {a.optRadius, {"sphere", "cavity", "vessel", "sherd", "seal"}},
        {a.optCenter, {"sphere", "cavity"}},
        {a.optCavity, {"sphere", "cavity"}},
        {a.optSide, {"cube"}},
        {a.optWidth, {"plane", "terrain", "tablet", "rounded-tablet"}},
        {a.optHeight, {"plane", "terrain", "tablet", "rounded-tablet", "vessel", "sherd", "seal"}},
        {a.optClosed, {"plane", "terrain", "tablet"}},
        {a.optThickness, {"plane", "terrain", "tablet", "rounded-tablet"}},
        {a.optWallStep, {"plane", "terrain", "tablet"}},
        {a.optAnisotropy, {"plane", "terrain", "tablet"}},
        {a.optDensity, {"plane", "terrain", "tablet"}},
        {a.optRoughness, {"plane", "terrain", "tablet", "rounded-tablet", "vessel", "sherd", "seal"}},
        {a.optRounding, {"rounded-tablet"}},
        {a.optReverseBulge, {"rounded-tablet"}},
        {a.optMarks, {"rounded-tablet"}},
        {a.optMarkRadius, {"rounded-tablet", "vessel", "sherd", "seal"}},
        {a.optMarkDepth, {"rounded-tablet", "vessel", "sherd", "seal"}},
        {a.optMarksCsv, {"rounded-tablet"}},
        {a.optRelief, {"terrain"}},
        {a.optHillWidth, {"terrain"}},
        {a.optNoise, {"terrain", "tablet"}},
        {a.optWedgeSize, {"tablet"}},
        {a.optWedgeDensity, {"tablet"}},
        {a.optGeotiff, {"plane", "terrain", "tablet"}},
        {a.optProfile, {"vessel", "sherd"}},
        {a.optTopRadius, {"vessel", "sherd"}},
        {a.optWall, {"vessel", "sherd"}},
        {a.optBase, {"vessel", "sherd"}},
        {a.optAngle, {"sherd"}},
        {a.optFrom, {"sherd"}},
        {a.optTo, {"sherd"}},
        {a.optRim, {"sherd"}},
        {a.optPoseSeed, {"vessel", "sherd", "seal"}},
        {a.optTruth, {"vessel", "sherd", "seal"}},
    };
    for (const auto& [opt, shapes] : applies)
        if (opt->count() > 0 && shapes.count(a.shape) == 0)
            throw UsageError("option " + opt->get_name() + " does not apply to shape " + a.shape);
    if (a.optThickness->count() > 0 && !a.closed && a.shape != "rounded-tablet")
        throw UsageError("--thickness needs --closed");
    if (a.optWallStep->count() > 0 && !a.closed) throw UsageError("--wall-step needs --closed");
    if (a.optCrs->count() > 0 && !a.geotiff) throw UsageError("--crs needs --geotiff");
    if (a.geotiff && (a.closed || a.ascii || a.doublePoints || a.anisotropy != 1 || a.densityVariation != 1 ||
                      a.roughness > 0))
        throw UsageError("--geotiff writes a regular grid: not with --closed, --ascii, --double, --anisotropy, "
                         "--density-variation or --roughness");
    if (a.optHoleSize->count() > 0 && a.holes == 0) throw UsageError("--hole-size needs --holes");
    if (a.optTopRadius->count() > 0 && a.profile != "cone") throw UsageError("--top-radius needs --profile cone");
    if (a.optTo->count() > 0 && a.rim) throw UsageError("--to does not apply with --rim (the piece reaches the rim)");
}

msii::TriMesh sphereMesh(const Arguments& a, std::ostringstream& comment)
{
    msii::samples::SphereOptions o;
    if (a.optSpacing->count()) o.spacing = a.spacing;
    if (a.optRadius->count()) o.radius = a.radius;
    if (a.optCenter->count()) o.center = parseTriple(a.centerText, "--center");
    o.cavity = a.cavity || a.shape == "cavity";
    o.seed = a.seed;
    comment << " radius " << o.radius << " spacing " << o.spacing << (o.cavity ? " cavity" : "");
    return msii::samples::makeSphere(o);
}

msii::TriMesh cubeMesh(const Arguments& a, std::ostringstream& comment)
{
    msii::samples::CubeOptions o;
    if (a.optSpacing->count()) o.spacing = a.spacing;
    if (a.optSide->count()) o.side = a.side;
    o.seed = a.seed;
    comment << " side " << o.side << " spacing " << o.spacing;
    return msii::samples::makeCube(o);
}

/// A rounded tablet, said in @p comment; its marks written to --marks-csv.
msii::TriMesh roundedTabletMesh(const Arguments& a, std::ostringstream& comment)
{
    msii::samples::RoundedTabletOptions o;
    if (a.optSpacing->count()) o.spacing = a.spacing;
    if (a.optWidth->count()) o.width = a.width;
    if (a.optHeight->count()) o.height = a.height;
    if (a.optThickness->count()) o.thickness = a.thickness;
    if (a.optRounding->count()) o.rounding = a.rounding;
    if (a.optReverseBulge->count()) o.reverseBulge = a.reverseBulge;
    if (a.optMarkRadius->count()) o.markRadius = a.markRadius;
    if (a.optMarkDepth->count()) o.markDepth = a.markDepth;
    if (a.optMarks->count()) {
        std::istringstream in(a.marksText);
        std::string item;
        std::size_t k = 0;
        while (std::getline(in, item, ',')) {
            if (k >= 6 || item.empty() || item.find_first_not_of("0123456789") != std::string::npos || item.size() > 4)
                throw UsageError("--marks takes six counts, e.g. 6,5,1,2,4,3 (got '" + a.marksText + "')");
            o.marks[k++] = std::stoi(item);
        }
        if (k != 6) throw UsageError("--marks takes six counts, e.g. 6,5,1,2,4,3 (got '" + a.marksText + "')");
    }
    o.roughness = a.roughness;
    o.seed = a.seed;
    comment << " width " << o.width << " height " << o.height << " thickness " << o.thickness << " rounding "
            << o.rounding << " spacing " << o.spacing;
    msii::samples::RoundedTablet tablet = msii::samples::makeRoundedTablet(o);
    if (!a.marksCsv.empty()) {
        std::ostringstream csv;
        csv.precision(17);
        csv << "side,x,y,z,nx,ny,nz,radius,depth\n";
        for (const msii::samples::TabletMark& m : tablet.marks)
            csv << msii::samples::tabletSideName(m.side) << ',' << m.centre.x << ',' << m.centre.y << ','
                << m.centre.z << ',' << m.normal.x << ',' << m.normal.y << ',' << m.normal.z << ',' << m.radius
                << ',' << m.depth << '\n';
        msii::writeTextFileAtomic(a.marksCsv, csv.str());
    }
    return std::move(tablet.mesh);
}

/// What vessels, sherds and seals share on the command line: their marks (where given), the
/// spacing, the scanner noise and the seeds of the mesh and of its pose.
template <class Options> void applyMarksAndSampling(const Arguments& a, Options& o)
{
    if (a.optMarkRadius->count()) o.markRadius = a.markRadius;
    if (a.optMarkDepth->count()) o.markDepth = a.markDepth;
    if (a.optSpacing->count()) o.spacing = a.spacing;
    o.roughness = a.roughness;
    o.seed = a.seed;
    o.poseSeed = a.poseSeed;
}

/// The vessel of the command line (for a vessel and a sherd).
msii::samples::VesselOptions vesselOptions(const Arguments& a)
{
    using msii::samples::VesselShape;
    msii::samples::VesselOptions o;
    o.shape = a.profile == "cylinder" ? VesselShape::Cylinder
              : a.profile == "cone"   ? VesselShape::Cone
                                      : VesselShape::Vase;
    if (a.optHeight->count()) o.height = a.height;
    if (a.optRadius->count()) o.radius = a.radius;
    if (a.optTopRadius->count()) o.topRadius = a.topRadius;
    if (a.optWall->count()) o.wall = a.wall;
    if (a.optBase->count()) o.base = a.base;
    applyMarksAndSampling(a, o);
    return o;
}

/// A vessel, sherd or seal with its known answers, said in @p comment.
msii::samples::Vessel vesselObject(const Arguments& a, std::ostringstream& comment)
{
    if (a.shape == "seal") {
        msii::samples::SealOptions o;
        if (a.optRadius->count()) o.radius = a.radius;
        if (a.optHeight->count()) o.height = a.height;
        applyMarksAndSampling(a, o);
        comment << " radius " << o.radius << " height " << o.height << " spacing " << o.spacing;
        if (o.poseSeed != 0) comment << " pose seed " << o.poseSeed;
        return msii::samples::makeCylinderSeal(o);
    }
    const msii::samples::VesselOptions v = vesselOptions(a);
    comment << " profile " << a.profile << " height " << v.height << " radius " << v.radius << " spacing " << v.spacing;
    if (v.poseSeed != 0) comment << " pose seed " << v.poseSeed;
    if (a.shape == "vessel") return msii::samples::makeVessel(v);
    msii::samples::SherdOptions o;
    o.vessel = v;
    if (a.optAngle->count()) o.angle = a.angle;
    if (a.optFrom->count()) o.fromHeight = a.from;
    if (a.optTo->count()) o.toHeight = a.to;
    o.rim = a.rim;
    comment << " angle " << o.angle << " from " << o.fromHeight;
    if (o.rim) comment << " rim";
    else comment << " to " << o.toHeight;
    return msii::samples::makeSherd(o);
}

/// A number in JSON, as short as reads back exactly.
std::string jsonNumber(double value)
{
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, value).ptr;
    return std::string(text, end);
}

std::string jsonVec3(const msii::Vec3& v)
{
    return "[" + jsonNumber(v.x) + ", " + jsonNumber(v.y) + ", " + jsonNumber(v.z) + "]";
}

std::string jsonPolyline(const std::vector<std::array<double, 2>>& line)
{
    std::string out = "[";
    for (std::size_t i = 0; i < line.size(); ++i)
        out += (i ? ", [" : "[") + jsonNumber(line[i][0]) + ", " + jsonNumber(line[i][1]) + "]";
    return out + "]";
}

/// --truth: the known answers of a vessel, sherd or seal (docs/cli.md#msii-samples).
std::string truthJson(const msii::samples::Vessel& v, const Arguments& a)
{
    std::ostringstream out;
    out << "{\n  \"shape\": \"" << a.shape << "\",\n";
    if (a.shape != "seal") out << "  \"profile\": \"" << a.profile << "\",\n";
    out << "  \"units\": \"mm\",\n  \"seed\": " << a.seed << ",\n  \"pose_seed\": " << a.poseSeed << ",\n";
    out << "  \"axis\": {\"point\": " << jsonVec3(v.axisPoint) << ", \"direction\": " << jsonVec3(v.axisDirection)
        << "},\n";
    out << "  \"rim_diameter\": " << (v.rimDiameter > 0 ? jsonNumber(v.rimDiameter) : "null") << ",\n";
    out << "  \"height\": " << jsonNumber(v.height) << ",\n  \"marks\": [";
    for (std::size_t k = 0; k < v.marks.size(); ++k) {
        const msii::samples::VesselMark& m = v.marks[k];
        out << (k ? ",\n    " : "\n    ") << "{\"theta\": " << jsonNumber(m.theta) << ", \"height\": "
            << jsonNumber(m.height) << ", \"centre\": " << jsonVec3(m.centre) << ", \"normal\": " << jsonVec3(m.normal)
            << ", \"radius\": " << jsonNumber(m.radius) << ", \"depth\": " << jsonNumber(m.depth) << "}";
    }
    out << (v.marks.empty() ? "],\n" : "\n  ],\n");
    out << "  \"outer_profile\": " << jsonPolyline(v.outerProfile) << ",\n";
    out << "  \"inner_profile\": " << jsonPolyline(v.innerProfile) << ",\n";
    out << "  \"section\": " << jsonPolyline(v.section) << "\n}\n";
    return out.str();
}

/// The options of a plane, terrain or tablet, said in @p comment.
msii::samples::HeightFieldOptions heightFieldOptions(const Arguments& a, std::ostringstream& comment)
{
    msii::samples::HeightFieldOptions o;
    o.kind = a.shape == "plane"     ? msii::samples::HeightFieldKind::Plane
             : a.shape == "terrain" ? msii::samples::HeightFieldKind::Terrain
                                    : msii::samples::HeightFieldKind::Tablet;
    if (a.optSpacing->count()) o.spacing = a.spacing;
    if (a.optWidth->count()) o.width = a.width;
    if (a.optHeight->count()) o.height = a.height;
    if (a.optThickness->count()) o.thickness = a.thickness;
    o.wallStep = a.wallStep;
    o.anisotropy = a.anisotropy;
    o.densityVariation = a.densityVariation;
    o.roughness = a.roughness;
    if (a.optRelief->count()) o.relief = a.relief;
    if (a.optHillWidth->count()) o.hillWidth = a.hillWidth;
    if (a.optNoise->count()) o.noise = a.noise;
    if (a.optWedgeSize->count()) o.wedgeSize = a.wedgeSize;
    if (a.optWedgeDensity->count()) o.wedgeDensity = a.wedgeDensity;
    o.closed = a.closed;
    o.seed = a.seed;
    comment << " width " << o.width << " height " << o.height << " spacing " << o.spacing;
    if (o.closed) comment << " closed thickness " << o.thickness;
    if (o.wallStep > 0) comment << " wall step " << o.wallStep;
    if (o.anisotropy != 1) comment << " anisotropy " << o.anisotropy;
    if (o.densityVariation != 1) comment << " density variation " << o.densityVariation;
    if (o.roughness > 0) comment << " roughness " << o.roughness;
    return o;
}

/// --geotiff: the height field as a DEM of heights on a regular grid. Returns the exit code.
int writeDem(const msii::samples::HeightFieldOptions& o, const Arguments& a, const std::string& comment)
{
    msii::samples::DemSampleOptions d;
    d.surface = o;
    d.crs = a.crs;
    if (a.optOffset->count()) {
        const msii::Vec3 at = parseTriple(a.offsetText, "--offset");
        d.west = at.x, d.north = at.y, d.baseHeight = at.z;
    }
    d.nodataPatches = a.holes;
    d.patchRadius = a.optHoleSize->count() ? a.holeSize : 0;
    const msii::Dem dem = msii::samples::makeDem(d);
    msii::RasterOutputOptions ro;
    ro.nodata = -9999.0;  // as DEMs often have it
    ro.description = comment + " geotiff";
    try {
        msii::writeRaster(a.output, dem.georeference, {{"height", dem.heights}}, ro);
    } catch (const msii::IOError& e) {
        return fail(1, e.what());
    }
    if (!a.quiet)
        std::cout << a.output << ": " << dem.georeference.width << " x " << dem.georeference.height << " cells, "
                  << dem.heights.size() - dem.numValid << " nodata\n";
    return 0;
}

/// An open height field in binary PLY, streamed: never held in memory, so any size the
/// disk takes. Returns the exit code.
int writeStreamed(const msii::samples::HeightFieldOptions& o, const Arguments& a, const std::string& comment)
{
    msii::WritePlyOptions plyOptions;
    plyOptions.forceDoublePoints = a.doublePoints;
    plyOptions.comments.push_back(comment);
    msii::samples::StreamedMeshCounts counts;
    try {
        counts = msii::samples::writeHeightFieldPly(o, a.output, plyOptions);
    } catch (const msii::IOError& e) {
        return fail(1, e.what());
    }
    if (!a.quiet) std::cout << a.output << ": " << counts.vertices << " vertices, " << counts.triangles << " triangles\n";
    return 0;
}

/// --holes: scanner-like holes punched into @p mesh, said in @p comment.
void addHoles(msii::TriMesh& mesh, const Arguments& a, std::ostringstream& comment)
{
    msii::samples::HoleOptions ho;
    ho.count = a.holes;
    const double step = a.optSpacing->count()                          ? a.spacing
                        : a.shape == "sphere" || a.shape == "cavity" ? msii::samples::SphereOptions{}.spacing
                        : a.shape == "cube"                          ? msii::samples::CubeOptions{}.spacing
                        : a.shape == "rounded-tablet" ? msii::samples::RoundedTabletOptions{}.spacing
                        : a.shape == "vessel" || a.shape == "sherd" ? msii::samples::VesselOptions{}.spacing
                        : a.shape == "seal"                          ? msii::samples::SealOptions{}.spacing
                                                                     : msii::samples::HeightFieldOptions{}.spacing;
    ho.maxSize = a.optHoleSize->count() ? a.holeSize : 2.0 * step;
    ho.minSize = 0.25 * ho.maxSize;
    ho.seed = a.seed;
    const msii::samples::HoleReport made = msii::samples::punchHoles(mesh, ho);
    comment << " holes " << made.holes << " up to " << ho.maxSize;
}

/// Writes @p mesh as PLY. Returns the exit code.
int writeMesh(const msii::TriMesh& mesh, const Arguments& a, const std::string& comment)
{
    msii::WritePlyOptions plyOptions;
    plyOptions.binary = !a.ascii;
    plyOptions.forceDoublePoints = a.doublePoints;
    plyOptions.comments.push_back(comment);
    try {
        msii::writePly(a.output, mesh, {}, plyOptions);
    } catch (const msii::Error& e) {
        return fail(1, e.what());  // I/O, not usage
    }
    if (!a.quiet)
        std::cout << a.output << ": " << mesh.numVertices() << " vertices, " << mesh.numTriangles() << " triangles\n";
    return 0;
}

/// Generates and writes the shape. Returns the exit code.
/// @throw UsageError, msii::InvalidInputError for invalid options.
int generate(const Arguments& a)
{
    checkUsage(a);
    msii::TriMesh mesh;
    msii::samples::Vessel truth;  // vessel, sherd and seal: the known answers (mesh moved out)
    const bool revolved = a.shape == "vessel" || a.shape == "sherd" || a.shape == "seal";
    std::ostringstream comment;
    comment << "msii-samples " << a.shape << " seed " << a.seed;
    if (revolved) {
        truth = vesselObject(a, comment);
        mesh = std::move(truth.mesh);
    } else if (a.shape == "sphere" || a.shape == "cavity") {
        mesh = sphereMesh(a, comment);
    } else if (a.shape == "cube") {
        mesh = cubeMesh(a, comment);
    } else if (a.shape == "rounded-tablet") {
        mesh = roundedTabletMesh(a, comment);
    } else {
        const msii::samples::HeightFieldOptions o = heightFieldOptions(a, comment);
        if (a.geotiff) return writeDem(o, a, comment.str());
        if (!o.closed && !a.ascii && a.holes == 0 && a.optOffset->count() == 0) return writeStreamed(o, a, comment.str());
        mesh = msii::samples::makeHeightField(o);
    }
    if (a.holes > 0) addHoles(mesh, a, comment);
    if (a.optOffset->count()) {
        const msii::Vec3 offset = parseTriple(a.offsetText, "--offset");
        for (msii::Vec3& p : mesh.points) p += offset;
        truth.axisPoint += offset;
        for (msii::samples::VesselMark& m : truth.marks) m.centre += offset;
        comment << " offset " << a.offsetText;
    }
    const int code = writeMesh(mesh, a, comment.str());
    if (code == 0 && revolved && !a.truth.empty()) msii::writeTextFileAtomic(a.truth, truthJson(truth, a));
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
    Arguments a;
    addOptions(app, a);

    try {
        app.parse(argc, argv);
    } catch (const CLI::Success& e) {  // --help, --help-all
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        return fail(2, e.what());
    }

    if (a.list) {
        for (const auto& s : kShapes) std::cout << s.name << std::string(16 - std::string(s.name).size(), ' ') << s.description << '\n';
        return 0;
    }

    try {
        return generate(a);
    } catch (const UsageError& e) {
        return fail(2, e.what());
    } catch (const msii::InvalidInputError& e) {
        return fail(2, e.what());
    } catch (const std::exception& e) {
        return fail(1, e.what());
    }
}
