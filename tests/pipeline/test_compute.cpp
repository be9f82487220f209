// The pipeline (pipeline/compute.h), the one entry point of every door: on a scan that needs
// repair (duplicate, degenerate and flipped faces, a vertex twice, an isolated vertex, small
// holes) it gives exactly what its parts give when run by hand (prepareMesh, then
// computeInvariants, then toInputVertices), with preparation's diagnostics; streamed pieces
// carry the same values; the exact mode's vertices are the input's; errors are one sentence.
#include <msii/core/errors.h>
#include <msii/invariants/invariants.h>
#include <msii/mesh/prepare_mesh.h>
#include <msii/pipeline/compute.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

using namespace msii;

namespace {

/// A scan-like tablet with what real scans have: small holes, two duplicate faces, a
/// degenerate face, one flipped face, a vertex stored twice and one in no face.
TriMesh scanNeedingRepair()
{
    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Tablet;
    ho.width = 8;
    ho.height = 6;
    ho.spacing = 0.1;
    ho.seed = 5;
    TriMesh mesh = samples::makeHeightField(ho);
    samples::HoleOptions holes;
    holes.count = 4;
    holes.minSize = 0.1;
    holes.maxSize = 0.25;
    samples::punchHoles(mesh, holes);
    const std::size_t n = mesh.numTriangles();
    mesh.triangles.push_back(mesh.triangles[n / 3]);      // duplicates
    mesh.triangles.push_back(mesh.triangles[n / 2]);
    Triangle& flipped = mesh.triangles[n / 5];
    std::swap(flipped[1], flipped[2]);
    const Triangle t = mesh.triangles[n / 7];
    mesh.triangles.push_back({t[0], t[0], t[1]});          // degenerate
    mesh.points.push_back(mesh.points[t[2]]);               // t[2] stored twice: one face uses the copy
    mesh.triangles[n / 7][2] = std::uint32_t(mesh.points.size() - 1);
    mesh.points.push_back(Vec3(100, 100, 100));             // in no face
    return mesh;
}

/// Vertices of @p mesh in a face.
std::size_t verticesInFaces(const TriMesh& mesh)
{
    std::vector<char> used(mesh.numVertices(), 0);
    for (const Triangle& t : mesh.triangles)
        for (std::uint32_t v : t) used[v] = 1;
    return std::size_t(std::count(used.begin(), used.end(), 1));
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

/// Values of @p a and @p b that differ in their bits (NaN equal to NaN).
std::size_t differing(const FeatureSet& a, const FeatureSet& b, std::size_t& compared)
{
    std::size_t count = 0;
    compared = 0;
    for (Invariant i : kAllInvariants) {
        EXPECT_EQ(a[i].size(), b[i].size());
        for (std::size_t j = 0; j < a[i].size() && j < b[i].size(); ++j) {
            EXPECT_EQ(a[i][j].size(), b[i][j].size());
            for (std::size_t v = 0; v < a[i][j].size() && v < b[i][j].size(); ++v) {
                count += !sameBits(a[i][j][v], b[i][j][v]);
                compared += !std::isnan(a[i][j][v]);
            }
        }
    }
    return count;
}

ComputeOptions options(double radius)
{
    ComputeOptions o;
    o.invariants.radius = radius;
    o.invariants.scales = 8;
    return o;
}

} // namespace

TEST(Pipeline, EqualsItsPartsRunByHand)
{
    const TriMesh scan = scanNeedingRepair();
    ComputeOptions o = options(0.8);
    o.border = BorderHandling::Mask;  // the parts by hand do not continue the borders
    const ComputeResult r = compute(scan, o);

    PrepareMeshOptions po;
    po.radius = 0.8;
    po.maxHolePerimeter = defaultMaxHolePerimeter(0.8);
    const PrepareMeshResult prepared = prepareMesh(scan, po);
    const InvariantsResult parts = computeInvariants(prepared.mesh, o.invariants);
    FeatureSet byHand;
    byHand.radii = parts.features.radii;
    for (Invariant i : kAllInvariants)
        for (const std::vector<float>& column : parts.features[i]) byHand[i].push_back(toInputVertices(prepared, column));

    std::size_t compared = 0;
    EXPECT_EQ(differing(r.features, byHand, compared), 0u);
    EXPECT_GT(compared, scan.numVertices());
    ASSERT_EQ(r.features.numVertices(), scan.numVertices());
    EXPECT_TRUE(std::isnan(r.features[Invariant::Volume][0].back()));  // the vertex in no face
    EXPECT_TRUE(std::isnan(r.filledShare.back()));
    EXPECT_EQ(r.filledShare.size(), scan.numVertices());
    EXPECT_EQ(r.plan.voxelSize, parts.plan.voxelSize);

    // What preparation did is said, first, and summarised.
    std::vector<std::string> kinds;
    for (const Diagnostic& d : r.diagnostics) kinds.push_back(d.kind);
    for (const char* kind : {"duplicate_faces_removed", "degenerate_faces_removed", "holes_filled"})
        EXPECT_NE(std::find(kinds.begin(), kinds.end(), kind), kinds.end()) << kind;
    ASSERT_GE(r.diagnostics.size(), prepared.changes.size());
    for (std::size_t k = 0; k < prepared.changes.size(); ++k) EXPECT_EQ(r.diagnostics[k].kind, prepared.changes[k].kind);
    const std::size_t inFaces = verticesInFaces(scan);  // holes leave vertices in no face
    EXPECT_EQ(r.preparation.isolatedVertices, scan.numVertices() - inFaces);
    EXPECT_GT(r.preparation.holes.numFilled, 0u);
    EXPECT_EQ(r.preparation.faces, prepared.mesh.numTriangles());
    EXPECT_DOUBLE_EQ(r.preparation.maxHolePerimeter, po.maxHolePerimeter);
    // Masked values over the input's vertices in a face.
    EXPECT_EQ(r.masked.vertices, inFaces);
    EXPECT_GT(r.masked.total(), 0u);
}

TEST(Pipeline, StreamedPiecesCarryTheSameValues)
{
    const TriMesh scan = scanNeedingRepair();
    for (const int tiles : {0, 2}) {
        ComputeOptions o = options(0.8);
        o.tiling.tilesPerAxis = tiles;
        const ComputeResult whole = compute(scan, o);
        std::vector<int> seen(scan.numVertices(), 0);
        std::size_t mismatches = 0, pieces = 0;
        const ComputeResult streamed = computeStreamed(scan, o, [&](const ComputedPiece& piece) {
            ++pieces;
            EXPECT_EQ(piece.plan.voxelSize, whole.plan.voxelSize);
            for (std::size_t k = 0; k < piece.vertices.size(); ++k) {
                const std::uint32_t v = piece.vertices[k];
                ++seen[v];
                mismatches += !sameBits(piece.filledShare[k], whole.filledShare[v]);
                for (Invariant i : kAllInvariants)
                    for (std::size_t j = 0; j < whole.features[i].size(); ++j)
                        mismatches += !sameBits(piece.features[i][j][k], whole.features[i][j][v]);
            }
        });
        SCOPED_TRACE(std::to_string(tiles) + " tiles per axis");
        EXPECT_EQ(pieces, tiles == 0 ? 1u : 4u);
        EXPECT_EQ(mismatches, 0u);
        EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), std::ptrdiff_t(verticesInFaces(scan)));
        EXPECT_EQ(seen.back(), 0);  // in no face: in no piece
        EXPECT_TRUE(streamed.features[Invariant::Volume].empty());
        EXPECT_EQ(streamed.masked.total(), whole.masked.total());
        EXPECT_EQ(streamed.masked.vertices, whole.masked.vertices);
    }
}

TEST(Pipeline, ExactVerticesAreTheInputs)
{
    const TriMesh scan = scanNeedingRepair();
    ComputeOptions o = options(0.8);
    o.invariants.exact = true;
    const std::uint32_t copy = std::uint32_t(scan.numVertices() - 2);  // the vertex stored twice
    o.invariants.exactVertices = {copy, 1000};
    const ComputeResult r = compute(scan, o);
    std::size_t valued = 0;
    for (std::size_t v = 0; v < scan.numVertices(); ++v) valued += !std::isnan(r.features[Invariant::Volume][0][v]);
    // The two chosen, and the first copy of the vertex stored twice, which shares its value.
    EXPECT_EQ(valued, 3u);
    EXPECT_FALSE(std::isnan(r.features[Invariant::Volume][0][1000]));
    EXPECT_FALSE(std::isnan(r.features[Invariant::Volume][0][copy]));
    o.invariants.exactVertices = {std::uint32_t(scan.numVertices() - 1)};
    try {
        compute(scan, o);
        FAIL() << "a vertex in no face was accepted for the exact mode";
    } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("belongs to no face"), std::string::npos) << e.what();
    }
}

TEST(Pipeline, RefusesWhatItCannotCompute)
{
    TriMesh empty;
    EXPECT_THROW(compute(empty, options(1.0)), InvalidInputError);
    ComputeOptions strict = options(0.8);
    strict.repair = false;
    EXPECT_THROW(compute(scanNeedingRepair(), strict), InvalidInputError);
    ComputeOptions exactTiled = options(0.8);
    exactTiled.invariants.exact = true;
    exactTiled.tiling.tilesPerAxis = 2;
    EXPECT_THROW(compute(scanNeedingRepair(), exactTiled), InvalidInputError);
}

// A scanner spike (one vertex of a closed sphere moved 10^6 away) costs its own faces, not
// the scan: they are left out with a warning that counts them, the hole they leave is
// filled, and every other vertex keeps its values, close to those of the sphere without the
// spike. Long faces of the surface itself (a plane of four triangles next to a fine part)
// stay. With the check off (DEM windows), the spike is computed with, or refused at once
// with the memory it would take.
TEST(Compute, SpikeFacesAreLeftOutAndTheRestKeepsItsValues)
{
    samples::SphereOptions so;
    so.radius = 10.0;
    so.spacing = 0.5;
    const TriMesh sphere = samples::makeSphere(so);
    TriMesh spiked = sphere;
    spiked.points[100] = {1e6, 0, 0};
    ComputeOptions o;
    o.invariants.radius = 2.0;
    o.invariants.scales = 4;
    o.invariants.select({Invariant::Volume});
    const ComputeResult clean = compute(sphere, o), r = compute(spiked, o);
    const auto left = std::find_if(r.diagnostics.begin(), r.diagnostics.end(),
                                   [](const Diagnostic& d) { return d.kind == "spike_faces_left_out"; });
    ASSERT_NE(left, r.diagnostics.end());
    EXPECT_EQ(left->count, 6u);  // the spike vertex's fan
    EXPECT_NE(left->message.find("left out 6 faces"), std::string::npos) << left->message;
    const std::vector<float>& v = r.features[Invariant::Volume][3];
    const std::vector<float>& c = clean.features[Invariant::Volume][3];
    EXPECT_TRUE(std::isnan(v[100]));
    std::size_t compared = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
        if (i == 100) continue;
        ASSERT_FALSE(std::isnan(v[i])) << i;
        const double d2 = squaredNorm(sphere.points[i] - sphere.points[100]);
        if (d2 > 4 * 2.0 * 2.0) {  // beyond the reach of the filled hole: the sphere's values
            EXPECT_NEAR(v[i], c[i], 1e-6) << i;
            ++compared;
        }
    }
    EXPECT_GT(compared, v.size() * 9 / 10);
    for (const Diagnostic& d : clean.diagnostics) EXPECT_NE(d.kind, "spike_faces_left_out");

    // A fine patch beside a plane of two long triangles, 30 times its edge: nothing left out.
    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Tablet;
    ho.width = 4, ho.height = 4, ho.spacing = 0.1;
    TriMesh patch = samples::makeHeightField(ho);
    const std::uint32_t base = std::uint32_t(patch.points.size());
    for (const Vec3& p : {Vec3{-30, -30, -5}, Vec3{30, -30, -5}, Vec3{30, 30, -5}, Vec3{-30, 30, -5}})
        patch.points.push_back(p);
    patch.triangles.push_back({base, base + 1, base + 2});
    patch.triangles.push_back({base, base + 2, base + 3});
    ComputeOptions po = o;
    po.invariants.radius = 0.5;
    const ComputeResult kept = compute(patch, po);
    for (const Diagnostic& d : kept.diagnostics) EXPECT_NE(d.kind, "spike_faces_left_out") << d.message;

    // Without the rule, a grid 10^6 wide at a voxel of a third is refused before anything is
    // allocated; a spike of large area (a fan of long, wide faces) with the memory estimate.
    o.leaveOutSpikes = false;
    EXPECT_THROW(compute(spiked, o), InvalidInputError);
    TriMesh wide = sphere;
    for (std::size_t i = 0; i < wide.points.size(); ++i)
        if (wide.points[i].z > 9.0) wide.points[i].z += 2e4;  // the cap pulled up 20 m: a tower of faces
    o.invariants.memoryLimit = 1e8;  // the tower's 5e5 mm² of faces take about 0.4 GB
    try {
        compute(wide, o);
        ADD_FAILURE() << "the tower was computed";
    } catch (const InvalidInputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("the surface would take about"), std::string::npos) << what;
        EXPECT_NE(what.find("spikes or noise"), std::string::npos) << what;
    }
    // In tiles too, refused at once (the whole is planned without the check; each tile has it).
    o.tiling.tilesPerAxis = 2;
    try {
        compute(wide, o);
        ADD_FAILURE() << "the tower was computed in tiles";
    } catch (const MemoryLimitError& e) {
        EXPECT_NE(std::string(e.what()).find("the surface would take about"), std::string::npos) << e.what();
    }
}
