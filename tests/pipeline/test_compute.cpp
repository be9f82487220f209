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
