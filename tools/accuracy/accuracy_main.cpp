/// @file accuracy_main.cpp
/// @brief `msii-accuracy`: the fast mode against the exact mode, as `msii compute` runs them
/// (the engine's pipeline: mesh preparation and default settings; values near open borders
/// masked, `--border mask`, since past a border the two modes' solids need not agree where
/// continuations meet), at random vertices and every radius of at least 3 median edges: mean and
/// largest |difference| of V̂, Ŝ, P̂ and L̂, over those radii and at the largest radius, and
/// with --by-radius per range of radii (3–8, 8–16 and over 16 median edges). Without mesh files it builds the generated set the documentation
/// quotes: the tablet the benchmark uses, a closed tablet slab, and scan-like meshes
/// (anisotropic triangles, 4× density variation, white noise of a tenth of an edge, long
/// wall triangles, a thin sheet). With mesh files (and -r) it measures those: real scans.
#include <msii/core/stopwatch.h>
#include <msii/invariants/invariants.h>
#include <msii/invariants/scales.h>
#include <msii/mesh/mesh_stats.h>
#include <msii/pipeline/compute.h>
#include <msii/io/read_mesh.h>
#include <msii/samples/generators.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

using namespace msii;

namespace {

struct Case {
    std::string name;
    TriMesh mesh;
    double radius = 0;
};

/// Mean and largest |fast − exact| of one invariant, over values both modes have.
struct Difference {
    double sum = 0, max = 0;
    std::size_t count = 0, maskedFastOnly = 0, maskedExactOnly = 0;
    void add(float fast, float exact)
    {
        // The fast mode masks a value whose grid reaches a border (a little beyond r).
        if (std::isnan(fast) && !std::isnan(exact)) ++maskedFastOnly;
        if (!std::isnan(fast) && std::isnan(exact)) ++maskedExactOnly;
        if (std::isnan(fast) || std::isnan(exact)) return;
        const double d = std::abs(double(fast) - double(exact));
        sum += d;
        max = std::max(max, d);
        ++count;
    }
    double mean() const { return count ? sum / double(count) : 0.0; }
};

/// Ranges of radii, in median edges: [3, 8), [8, 16), [16, ∞).
constexpr int kRanges = 3;
const char* const kRangeNames[kRanges] = {"3–8 edges", "8–16 edges", "over 16 edges"};
int rangeOf(double edges) { return edges < 8 ? 0 : edges < 16 ? 1 : 2; }

struct Row {
    std::string name;
    std::size_t vertices = 0, compared = 0, maskedFastOnly = 0, maskedExactOnly = 0;
    double edgesPerRadius = 0, fastSeconds = 0;
    double exactShare = 0;  ///< of the fast run's P and L values, those evaluated exactly where the kernels blur
    Difference all[4], largest[4];  // V, S, P, L
    Difference byRange[kRanges][4];
    struct Worst {
        double difference;
        int invariant;
        std::size_t radius;
        std::uint32_t vertex;
        float fast, exact;
    };
    std::vector<Worst> worst;  // the largest differences, largest first
};

Row measure(const Case& c, const InvariantsOptions& settings, std::size_t numVertices, std::uint64_t seed,
            std::size_t keepWorst)
{
    Row row;
    row.name = c.name;
    ComputeOptions o;
    o.invariants = settings;
    o.invariants.radius = c.radius;
    // Where continuations meet they leave a narrow crack: the grid closes it, the exact sums
    // do not, so their solids differ there. Compared on the input's own surface.
    o.border = BorderHandling::Mask;
    const int scales = o.invariants.scales;
    const Stopwatch fastTime;
    const ComputeResult fast = compute(c.mesh, o);
    row.fastSeconds = fastTime.seconds();
    row.exactShare = double(fast.cost.patchLinePairsExact) / double(std::max<std::size_t>(1, fast.cost.patchLinePairs));
    row.vertices = c.mesh.numVertices();
    const double edge = fast.stats.medianEdge;
    row.edgesPerRadius = c.radius / edge;

    // Vertices of the input that are in a face (the others have no values).
    std::vector<std::uint32_t> candidates;
    for (std::uint32_t v = 0; v < c.mesh.numVertices(); ++v)
        if (!std::isnan(fast.filledShare[v])) candidates.push_back(v);
    std::mt19937_64 rng(seed);
    std::vector<std::uint32_t> chosen;
    std::vector<char> taken(candidates.size(), 0);
    while (chosen.size() < std::min<std::size_t>(numVertices, candidates.size())) {
        const std::size_t k = std::size_t(rng() % candidates.size());
        if (!taken[k]) taken[k] = 1, chosen.push_back(candidates[k]);
    }
    std::sort(chosen.begin(), chosen.end());
    ComputeOptions eo = o;
    eo.invariants.exact = true;
    eo.invariants.exactVertices = chosen;
    const ComputeResult exact = compute(c.mesh, eo);

    const std::vector<double> radii = equidistantRadii(c.radius, scales);
    const FeatureColumns* columns[4][2];
    for (Invariant i : kAllInvariants)
        columns[std::size_t(i)][0] = &fast.features[i], columns[std::size_t(i)][1] = &exact.features[i];
    for (std::size_t j = 0; j < radii.size(); ++j) {
        if (radii[j] < 3 * edge) continue;
        const int range = rangeOf(radii[j] / edge);
        for (int i = 0; i < 4; ++i)
            for (const std::uint32_t v : chosen) {
                const float f = (*columns[i][0])[j][v], e = (*columns[i][1])[j][v];
                row.all[i].add(f, e);
                row.byRange[range][i].add(f, e);
                if (j + 1 == radii.size()) row.largest[i].add(f, e);
                const double d = std::abs(double(f) - double(e));
                if (keepWorst > 0 && d == d) {
                    row.worst.push_back({d, i, j, v, f, e});
                    std::sort(row.worst.begin(), row.worst.end(),
                              [](const Row::Worst& a, const Row::Worst& b) { return a.difference > b.difference; });
                    if (row.worst.size() > keepWorst) row.worst.pop_back();
                }
            }
    }
    row.compared = row.all[0].count + row.all[1].count + row.all[2].count + row.all[3].count;
    for (const Difference& d : row.all) {
        row.maskedFastOnly += d.maskedFastOnly;
        row.maskedExactOnly += d.maskedExactOnly;
    }
    return row;
}

samples::HeightFieldOptions tabletOptions(double spacing)
{
    samples::HeightFieldOptions o;
    o.kind = samples::HeightFieldKind::Tablet;
    o.width = 10;
    o.height = 8;
    o.spacing = spacing;
    return o;
}

/// The generated set (radius R = 1 mm, about 25 median edges at the default spacing).
std::vector<Case> generatedCases(double spacing, std::uint64_t seed)
{
    std::vector<Case> cases;
    samples::HeightFieldOptions tablet = tabletOptions(spacing);
    tablet.seed = seed;
    cases.push_back({"tablet (open, the benchmark's kind)", samples::makeHeightField(tablet), 1.0});
    samples::HeightFieldOptions slab = tablet;
    slab.closed = true;
    slab.thickness = 3;
    cases.push_back({"closed tablet slab", samples::makeHeightField(slab), 1.0});
    // Scan-like: triangles 3:1, density varying 4x, white noise of a tenth of an edge, walls
    // and bottom of long triangles.
    samples::HeightFieldOptions scan = slab;
    scan.anisotropy = 3;
    scan.densityVariation = 4;
    scan.roughness = 0.1 * spacing;
    scan.wallStep = 1.5;
    cases.push_back({"scan-like slab (3:1, 4x density, noise, long walls)", samples::makeHeightField(scan), 1.0});
    // A thin part: the same scan-like tablet as a sheet 2 R thick.
    samples::HeightFieldOptions sheet = scan;
    sheet.thickness = 2.0;
    sheet.sag = 0.2;
    sheet.wallStep = 0;
    cases.push_back({"scan-like sheet, 2 R thick", samples::makeHeightField(sheet), 1.0});
    return cases;
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"msii-accuracy: the fast mode against the exact mode (mean and largest |difference| of V, S, P, L "
                 "at radii of at least 3 median edges), on a generated set of scan-like meshes or on given meshes"};
    std::vector<std::string> files;
    double radius = 0, spacing = 0.04;
    int scales = 16;
    std::size_t vertices = 200;
    std::uint64_t seed = 1;
    std::size_t worst = 0;
    InvariantsOptions settings;
    app.add_option("--precision", settings.minVoxelsPerRadius, "as msii compute --precision (default 6)");
    app.add_option("--pl-precision", settings.patchLinePrecision, "as msii compute --pl-precision (default: 4/3 of --precision)");
    std::string plCheck = "on";
    app.add_option("--pl-check", plCheck, "as msii compute --pl-check: on (default) or off, the kernel sums alone")
        ->check(CLI::IsMember({"on", "off"}));
    bool byRadius = false;
    app.add_flag("--by-radius", byRadius, "also give P̂ and L̂ (and V̂, Ŝ) per range of radii: 3-8, 8-16, over 16 median edges");
    app.add_option("--worst", worst, "also list the K largest differences (vertex of the input, radius index)");
    app.add_option("meshes", files, "meshes to measure (PLY, OBJ, OFF, STL); default: the generated set");
    app.add_option("-r,--radius", radius, "largest radius R for the given meshes (mesh units)");
    app.add_option("-n,--scales", scales, "N (default 16)");
    app.add_option("--vertices", vertices, "random vertices per mesh compared with the exact mode (default 200)");
    app.add_option("--seed", seed, "seed of the vertices and of the generated meshes (default 1)");
    app.add_option("--spacing", spacing, "vertex spacing of the generated set, mm (default 0.04)");
    CLI11_PARSE(app, argc, argv);
    settings.patchLineExactWhereBlurred = plCheck == "on";
    if (!files.empty() && !(radius > 0)) {
        std::fprintf(stderr, "msii-accuracy: error: give the radius for the meshes (-r)\n");
        return 2;
    }
    try {
        std::vector<Case> cases;
        if (files.empty()) {
            cases = generatedCases(spacing, seed);
        } else {
            for (const std::string& f : files) cases.push_back({f, readMesh(f).mesh, radius});
        }
        std::printf("msii-accuracy: fast mode (default settings) against the exact mode, %zu random vertices per "
                    "mesh (seed %llu), N = %d, radii of at least 3 median edges; mean / largest |difference|\n\n",
                    vertices, static_cast<unsigned long long>(seed), scales);
        std::printf("| mesh | vertices | R / median edge | V̂ | Ŝ | P̂ | L̂ | V̂ at R | Ŝ at R |\n");
        std::printf("|---|---|---|---|---|---|---|---|---|\n");
        for (const Case& c : cases) {
            settings.scales = scales;
            const Row r = measure(c, settings, vertices, seed, worst);
            const auto pair = [](const Difference& d) {
                if (d.count == 0) return std::string("–");  // no radius in this range
                char text[48];
                std::snprintf(text, sizeof(text), "%.1e / %.1e", d.mean(), d.max);
                return std::string(text);
            };
            std::printf("| %s | %zu | %.1f | %s | %s | %s | %s | %s | %s |\n", r.name.c_str(), r.vertices,
                        r.edgesPerRadius, pair(r.all[0]).c_str(), pair(r.all[1]).c_str(), pair(r.all[2]).c_str(),
                        pair(r.all[3]).c_str(), pair(r.largest[0]).c_str(), pair(r.largest[1]).c_str());
            if (r.maskedFastOnly + r.maskedExactOnly > 0)
                std::printf("|   near borders: %zu values masked by the fast mode only (its grid reaches a little "
                            "beyond r), %zu by the exact mode only | | | | | | | | |\n",
                            r.maskedFastOnly, r.maskedExactOnly);
            if (settings.patchLineExactWhereBlurred && (settings.computePatch || settings.computeLine))
                std::printf("|   P and L exact where the kernels blur: %.1f %% of the values | | | | | | | | |\n",
                            100.0 * r.exactShare);
            if (byRadius)
                for (int k = 0; k < kRanges; ++k)
                    std::printf("|   radii of %s | | | %s | %s | %s | %s | | |\n", kRangeNames[k],
                                pair(r.byRange[k][0]).c_str(), pair(r.byRange[k][1]).c_str(),
                                pair(r.byRange[k][2]).c_str(), pair(r.byRange[k][3]).c_str());
            for (const Row::Worst& w : r.worst)
                std::printf("|   %c at r_%zu, input vertex %u: fast %.4f, exact %.4f | | | | | | | | |\n", "VSPL"[w.invariant],
                            w.radius + 1, w.vertex, double(w.fast), double(w.exact));
            std::fflush(stdout);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "msii-accuracy: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
