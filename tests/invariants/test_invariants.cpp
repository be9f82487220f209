// The invariants of a prepared mesh, computeInvariants: georeferenced coordinates (the local frame of
// ScalePlan::origin) and cancellation through the RunContext.
#include <msii/core/run_context.h>
#include <msii/invariants/invariants.h>
#include <msii/samples/generators.h>
#include <msii/pipeline/compute.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

using namespace msii;

namespace {

TriMesh terrainPatch(double spacing)
{
    samples::HeightFieldOptions ho;
    ho.kind = samples::HeightFieldKind::Terrain;
    ho.width = 60.0;  // metres, say
    ho.height = 45.0;
    ho.spacing = spacing;
    ho.relief = 3.0;
    ho.hillWidth = 6.0;
    ho.anisotropy = 1.7;  // irregular triangles
    ho.roughness = 0.02;
    ho.seed = 5;
    return samples::makeHeightField(ho);
}

struct Differences {
    double worst = 0, mean = 0;
    std::size_t compared = 0, nanMismatches = 0;
};

/// Differences between two results over the values both have at radii of at least
/// @p minRadius, and the count of values NaN in one only.
Differences differences(const InvariantsResult& a, const InvariantsResult& b, double minRadius = 0)
{
    Differences d;
    double sum = 0;
    for (Invariant inv : kAllInvariants) {
        EXPECT_EQ(a.features[inv].size(), b.features[inv].size());
        for (std::size_t j = 0; j < a.features[inv].size(); ++j) {
            if (a.plan.radii[j] < minRadius) continue;
            for (std::size_t i = 0; i < a.features[inv][j].size(); ++i) {
                const float x = a.features[inv][j][i], y = b.features[inv][j][i];
                if (std::isnan(x) != std::isnan(y)) ++d.nanMismatches;
                else if (!std::isnan(x)) {
                    d.worst = std::max(d.worst, double(std::abs(x - y)));
                    sum += std::abs(x - y);
                    ++d.compared;
                }
            }
        }
    }
    d.mean = d.compared ? sum / double(d.compared) : 0;
    return d;
}

TriMesh moved(const TriMesh& mesh, const Vec3& offset)
{
    TriMesh m = mesh;
    for (Vec3& p : m.points) p += offset;
    return m;
}

} // namespace

// A terrain in UTM coordinates (x ≈ 500 km, y ≈ 5,500 km, z ≈ 300 m), as photogrammetry and
// LiDAR software export it, computes in a local frame (ScalePlan::origin):
// - moved by a multiple of the voxel grid's period, its values are those at the origin up
//   to float rounding;
// - moved by any offset, they differ from those at the origin as much as a sub-voxel move
//   near the origin makes them differ (the fast mode samples the surface on a grid), no more;
// - tiles still equal one piece bit for bit.
TEST(Compute, GeoreferencedCoordinatesComputeAsAtTheOrigin)
{
    const TriMesh local = terrainPatch(0.35);
    InvariantsOptions o;
    o.radius = 5.0;
    o.scales = 8;
    const InvariantsResult atOrigin = computeInvariants(local, o);
    const double h0 = atOrigin.plan.voxelSize, minRadius = 3.0 * atOrigin.stats.medianEdge;

    const Vec3 onGrid{1024.0 * h0 * 500.0, 1024.0 * h0 * 5370.0, 1024.0 * h0 * 3.0};
    const InvariantsResult aligned = computeInvariants(moved(local, onGrid), o);
    EXPECT_EQ(aligned.plan.origin.x, onGrid.x);
    Differences d = differences(atOrigin, aligned);
    EXPECT_GT(d.compared, local.numVertices() * 8 * 2);  // V, S, P, L at 8 radii: most have values
    EXPECT_EQ(d.nanMismatches, 0u);
    EXPECT_LE(d.worst, 1e-6);

    const Vec3 utm{512345.678, 5498765.432, 312.5};
    const InvariantsResult b = computeInvariants(moved(local, utm), o);
    EXPECT_NEAR(b.plan.origin.x, utm.x + 30.0, 1024.0 * h0);
    EXPECT_NEAR(b.plan.origin.y, utm.y + 22.5, 1024.0 * h0);
    const InvariantsResult nudged = computeInvariants(moved(local, {0.37 * h0, 0.61 * h0, 0.23 * h0}), o);
    const Differences far = differences(atOrigin, b, minRadius), near = differences(atOrigin, nudged, minRadius);
    EXPECT_EQ(far.nanMismatches, 0u);
    std::printf("from the origin: moved to UTM max %.2e mean %.2e; moved by a fraction of a voxel max %.2e mean %.2e\n",
                far.worst, far.mean, near.worst, near.mean);
    EXPECT_LE(far.worst, 1e-2);
    EXPECT_LE(far.mean, 1e-3);
    EXPECT_LE(far.mean, 2.0 * near.mean);

    ComputeOptions tiled;  // through the pipeline, which computes in tiles
    tiled.invariants = o;
    tiled.tiling.tilesPerAxis = 3;
    tiled.border = BorderHandling::Mask;  // as computeInvariants
    InvariantsResult parts;
    parts.plan = b.plan;
    parts.features = compute(moved(local, utm), tiled).features;
    d = differences(parts, b);
    EXPECT_EQ(d.worst, 0.0);
    EXPECT_EQ(d.nanMismatches, 0u);
    EXPECT_GT(d.compared, 0u);
}

// cancel() from the listener (any thread could call it) stops the computation with
// Cancelled at its next step; a context cancelled before the start stops it at once.
TEST(Compute, CancelStopsTheWork)
{
    const TriMesh mesh = terrainPatch(0.35);
    InvariantsOptions o;
    o.radius = 5.0;
    o.scales = 8;
    RunContext context;
    std::size_t updates = 0;
    std::string lastStage;
    context.setListener([&](const ProgressUpdate& u) {
        ++updates;
        lastStage = u.stage;
        if (u.stage.rfind("V and S", 0) == 0) context.cancel();
    });
    EXPECT_THROW(computeInvariants(mesh, o, &context), Cancelled);
    EXPECT_TRUE(context.wasInterrupted());
    EXPECT_EQ(lastStage.rfind("V and S", 0), 0u) << lastStage;  // no stage after the cancel

    RunContext early;
    early.cancel();
    EXPECT_THROW(computeInvariants(mesh, o, &early), Cancelled);

    RunContext fine;  // and one that is not cancelled runs to the end
    EXPECT_NO_THROW(computeInvariants(mesh, o, &fine));
}
