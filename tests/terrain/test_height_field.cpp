// V and S straight from the heights (terrain/height_field.h): a plane and a slope give ½
// exactly; on rough terrain with mounds, ditches and walls, and on steeper terrain with a
// quarry face, a sunken lane and a bank, at random interior cells and
// every radius, the values are within V̂ 1e-4 (mean) and 5e-4 (largest) and Ŝ 2e-4 and 1e-3
// of the exact mode on the DEM's own mesh (terrain/dem.h: a vertex per cell centre, two
// triangles per square); every lane of a row block agrees with the cell computed alone; the
// rim's cells are weighed exactly.
#include <msii/core/errors.h>
#include <msii/invariants/exact.h>
#include <msii/terrain/dem.h>
#include <msii/terrain/height_field.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

using namespace msii;

namespace {

/// Terrain like a 1 m lidar DEM: rolling hills, mounds and hollows, ditches, a wall (a step
/// of 1.5 m over one cell), and white roughness of ±@p roughness m.
double terrain(double x, double y, std::uint64_t seed)
{
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double z = 4.0 * std::sin(x / 23.0 + 6.0 * u(rng)) * std::cos(y / 31.0 + 6.0 * u(rng)) + 0.05 * x;
    for (int k = 0; k < 40; ++k) {  // mounds and hollows
        const double cx = 120 * u(rng), cy = 120 * u(rng), w = 1.5 + 5 * u(rng), a = -1.5 + 3 * u(rng);
        z += a * std::exp(-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (2 * w * w));
    }
    for (int k = 0; k < 6; ++k) {  // ditches
        const double th = M_PI * u(rng), c = 120 * u(rng);
        const double d = x * std::cos(th) + y * std::sin(th) - c;
        z -= 1.0 * std::exp(-d * d / 1.5);
    }
    const double wall = 0.6 * x + 0.8 * y - 70 * (0.8 + 0.4 * u(rng));  // a terrace's wall
    z += 1.5 / (1 + std::exp(-wall / 0.4));
    return z;
}

/// Steeper than terrain(), as lidar DEMs have it: a quarry face of 6 m over about a cell, a
/// sunken lane 2 m deep with sides of a cell, a round bank of 3 m.
double steepTerrain(double x, double y, std::uint64_t seed)
{
    double z = terrain(x, y, seed);
    z += 6.0 / (1 + std::exp(-(0.8 * x - 0.6 * y - 20) / 0.15));
    z -= 2.0 / (1 + std::exp((std::abs(0.3 * x + 0.95 * y - 60) - 2.5) / 0.15));
    z += 3.0 / (1 + std::exp((std::hypot(x - 80, y - 40) - 15) / 0.2));
    return z;
}

/// A DEM of @p n × @p n cells of @p cell m from @p height, with white roughness.
Dem makeDem(int n, double cell, double roughness, std::uint64_t seed, double (*height)(double, double, std::uint64_t))
{
    Dem dem;
    dem.georeference.width = dem.georeference.height = n;
    dem.georeference.transform = {0, cell, 0, n * cell, 0, -cell};
    dem.heights.resize(std::size_t(n) * n);
    std::mt19937_64 rng(seed + 100);
    std::uniform_real_distribution<double> rough(-roughness, roughness);
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c)
            dem.heights[std::size_t(r) * n + c] = float(height((c + 0.5) * cell, (n - r - 0.5) * cell, seed) + rough(rng));
    dem.numValid = dem.heights.size();
    return dem;
}

HeightGrid gridOf(const Dem& dem)
{
    HeightGrid g;
    g.cols = dem.georeference.width, g.rows = dem.georeference.height;
    g.z = dem.heights;
    return g;
}

struct Comparison {
    double meanV = 0, maxV = 0, meanS = 0, maxS = 0;
    std::size_t count = 0;
};

/// The kernel against the exact mode at @p samples random cells at least R + 2 cells from
/// the edge.
Comparison againstExact(const Dem& dem, double cell, const std::vector<double>& radii, std::size_t samples)
{
    const int n = dem.georeference.width;
    const DemMesh dm = demToMesh(dem);
    const int margin = int(std::ceil(radii.back() / cell)) + 3;
    std::mt19937 rng(5);
    std::vector<std::uint32_t> vertices;
    std::vector<std::pair<int, int>> at;
    while (at.size() < samples) {
        const int c = margin + int(rng() % unsigned(n - 2 * margin)), r = margin + int(rng() % unsigned(n - 2 * margin));
        at.push_back({c, r});
        vertices.push_back(dm.vertexOfCell[std::size_t(r) * n + c]);
    }
    ExactOptions eo;
    eo.radii = radii;
    eo.vertices = vertices;
    eo.computePatchLine = false;
    const ExactResult exact = computeExact(dm.mesh, eo);
    const HeightGrid grid = gridOf(dem);
    HeightFieldOptions ho;
    ho.radii = radii;
    ho.cellWidth = ho.cellHeight = cell;
    Comparison cmp;
    std::vector<double> perV(radii.size()), perS(radii.size()), maxV(radii.size()), maxS(radii.size());
    for (std::size_t k = 0; k < at.size(); ++k) {
        const HeightFieldResult hf = computeHeightField(grid, {at[k].first, at[k].second, 1, 1}, ho);
        for (std::size_t j = 0; j < radii.size(); ++j) {
            const double dv = std::abs(hf.volume[j][0] - exact.volume[j][k]), ds = std::abs(hf.sphere[j][0] - exact.sphere[j][k]);
            cmp.meanV += dv, cmp.meanS += ds, cmp.maxV = std::max(cmp.maxV, dv), cmp.maxS = std::max(cmp.maxS, ds);
            perV[j] += dv / double(at.size()), perS[j] += ds / double(at.size());
            maxV[j] = std::max(maxV[j], dv), maxS[j] = std::max(maxS[j], ds);
            ++cmp.count;
        }
    }
    cmp.meanV /= double(cmp.count), cmp.meanS /= double(cmp.count);
    for (std::size_t j = 0; j < radii.size(); ++j)
        std::printf("   r %5.2f: V %.1e / %.1e  S %.1e / %.1e\n", radii[j], perV[j], maxV[j], perS[j], maxS[j]);
    return cmp;
}

std::vector<double> radiiUpTo(double R, int n)
{
    std::vector<double> radii;
    for (int j = 1; j <= n; ++j) radii.push_back(R * j / n);
    return radii;
}

} // namespace

TEST(HeightField, PlaneAndSlopeAreOneHalf)
{
    for (const double slope : {0.0, 0.3, 1.2}) {
        Dem dem = makeDem(60, 1.0, 0.0, 1, [](double, double, std::uint64_t) { return 0.0; });
        for (int r = 0; r < 60; ++r)
            for (int c = 0; c < 60; ++c) dem.heights[std::size_t(r) * 60 + c] = float(100 + slope * (0.6 * c + 0.8 * r));
        HeightFieldOptions ho;
        ho.radii = radiiUpTo(12, 12);
        const HeightFieldResult hf = computeHeightField(gridOf(dem), {20, 20, 20, 20}, ho);
        double worstV = 0, worstS = 0;
        for (std::size_t j = 0; j < ho.radii.size(); ++j)
            for (std::size_t k = 0; k < 400; ++k) {
                worstV = std::max(worstV, std::abs(hf.volume[j][k] - 0.5));
                worstS = std::max(worstS, std::abs(hf.sphere[j][k] - 0.5));
            }
        std::printf("slope %.1f: largest |V - 1/2| %.1e, |S - 1/2| %.1e\n", slope, worstV, worstS);
        EXPECT_LE(worstV, slope == 0 ? 1e-6 : 2e-4) << slope;
        EXPECT_LE(worstS, slope == 0 ? 1e-6 : 5e-4) << slope;
    }
}

TEST(HeightField, RoughTerrainAgainstTheExactMode)
{
    for (const bool steep : {false, true}) {
        for (const double roughness : {0.05, 0.15}) {
            const Dem dem = steep ? makeDem(120, 1.0, roughness, 7, steepTerrain) : makeDem(120, 1.0, roughness, 3, terrain);
            for (const double R : {10.0, 30.0}) {
                const Comparison c = againstExact(dem, 1.0, radiiUpTo(R, int(R) > 16 ? 16 : int(R)), R > 20 ? 25 : 60);
                std::printf("%sroughness %.2f m, R %.0f cells: V mean %.1e max %.1e; S mean %.1e max %.1e (%zu values)\n",
                            steep ? "steep, " : "", roughness, R, c.meanV, c.maxV, c.meanS, c.maxS, c.count);
                EXPECT_GT(c.count, 200u);
                EXPECT_LE(c.meanV, 1e-4);
                EXPECT_LE(c.maxV, 5e-4);
                EXPECT_LE(c.meanS, 2e-4);
                EXPECT_LE(c.maxS, 1e-3);
            }
        }
    }
}

/// Cells are summed 16, 8 or 1 at a time, as the own rectangle's width, the grid's edge and
/// gaps allow: each way gives the cell's values bit for bit, with blocks of 16 in vectors of
/// @p vectorLanes (0: the processor's widest).
void expectEveryBlockAgreesWithTheCellAlone(int vectorLanes)
{
    const Dem dem = makeDem(80, 1.0, 0.15, 11, steepTerrain);
    HeightGrid grid = gridOf(dem);
    for (int r = 30; r < 34; ++r)
        for (int c = 50; c < 53; ++c) grid.z[std::size_t(r) * 80 + std::size_t(c)] = std::numeric_limits<float>::quiet_NaN();
    HeightFieldOptions ho;
    ho.radii = radiiUpTo(6.0, 4);
    ho.cellWidth = ho.cellHeight = 1.0;
    ho.vectorLanes = vectorLanes;
    std::size_t compared = 0, valued = 0;
    for (const GridRect own : {GridRect{0, 0, 80, 80}, GridRect{7, 9, 41, 30}, GridRect{13, 21, 17, 5}, GridRect{3, 40, 9, 3}}) {
        const HeightFieldResult block = computeHeightField(grid, own, ho);
        for (int r = 0; r < own.rows; r += 3)
            for (int c = 0; c < own.cols; ++c) {
                const HeightFieldResult alone = computeHeightField(grid, {own.col + c, own.row + r, 1, 1}, ho);
                const std::size_t at = std::size_t(r) * std::size_t(own.cols) + std::size_t(c);
                for (std::size_t j = 0; j < ho.radii.size(); ++j) {
                    const float v = block.volume[j][at], s = block.sphere[j][at];
                    ASSERT_EQ(std::isnan(v), std::isnan(alone.volume[j][0])) << own.col + c << ", " << own.row + r;
                    ASSERT_EQ(std::isnan(s), std::isnan(alone.sphere[j][0])) << own.col + c << ", " << own.row + r;
                    if (!std::isnan(v)) {
                        ASSERT_EQ(v, alone.volume[j][0]) << own.col + c << ", " << own.row + r << ", r " << ho.radii[j];
                    }
                    if (!std::isnan(s)) {
                        ASSERT_EQ(s, alone.sphere[j][0]) << own.col + c << ", " << own.row + r << ", r " << ho.radii[j];
                    }
                    valued += !std::isnan(v);
                    ++compared;
                }
            }
    }
    EXPECT_GT(compared, 10000u);
    EXPECT_GT(valued, compared / 2);  // most cells have their balls' heights
}

TEST(HeightField, EveryBlockAgreesWithTheCellAlone)
{
    expectEveryBlockAgreesWithTheCellAlone(0);
}

// A processor without AVX-512 sums blocks of 16 as two vectors of 8; on one with it, this
// compares those with its single lanes too.
TEST(HeightField, EveryBlockOfTwoVectorsAgreesWithTheCellAlone)
{
    expectEveryBlockAgreesWithTheCellAlone(8);
}
