// msii-accuracy as users run it: on a given mesh it prints one table row per mesh with the
// mean and largest differences of V̂, Ŝ, P̂ and L̂ between the fast and the exact mode. On a
// flat open patch both modes are near-exact, so the row's figures must be small; on the
// generated scan-like set the means must be within the bounds the documentation quotes; a
// missing radius is a usage error.
#include <msii/io/write_ply.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "../support/run_program.h"
#include "../support/temp_dir.h"

using namespace msii;

namespace {
/// A flat open patch of 5 × 5 mm at 0.05 mm in @p dir, where both modes are near-exact.
std::string writeFlatPatch(const msii::test::TempDir& dir)
{
    samples::HeightFieldOptions o;
    o.kind = samples::HeightFieldKind::Plane;
    o.width = 5;
    o.height = 5;
    o.spacing = 0.05;
    const std::string mesh = dir.file("plane.ply");
    writePly(mesh, samples::makeHeightField(o), {});
    return mesh;
}
} // namespace

TEST(AccuracyCli, FlatPatchRowIsSmallAndComplete)
{
    const msii::test::TempDir dir;
    const std::string mesh = writeFlatPatch(dir);
    const msii::test::RunResult r = msii::test::runProgram(MSII_ACCURACY_EXE, "'" + mesh + "' -r 0.8 --vertices 40",
                                                          dir.path());
    ASSERT_EQ(r.code, 0) << r.err;
    // The row: | mesh | vertices | R / median edge | V̂ | Ŝ | P̂ | L̂ | V̂ at R | Ŝ at R |
    const std::size_t at = r.out.find("| " + mesh + " |");
    ASSERT_NE(at, std::string::npos) << r.out;
    std::istringstream row(r.out.substr(at, r.out.find('\n', at) - at));
    std::vector<std::string> cells;
    for (std::string cell; std::getline(row, cell, '|');) cells.push_back(cell);
    ASSERT_EQ(cells.size(), 10u) << r.out;  // an empty first cell, then nine columns
    std::size_t checked = 0;
    for (std::size_t c = 4; c < 10; ++c) {
        double mean = -1, largest = -1;
        ASSERT_EQ(std::sscanf(cells[c].c_str(), " %lf / %lf", &mean, &largest), 2) << cells[c];
        EXPECT_GE(mean, 0.0);
        EXPECT_LE(mean, largest);
        EXPECT_LE(largest, 2e-3) << "column " << c << ": " << cells[c];
        ++checked;
    }
    EXPECT_EQ(checked, 6u);
}

namespace {
/// The cells of the table row that starts with "| @p name", split at '|' (an empty first cell).
std::vector<std::string> rowCells(const std::string& out, const std::string& name)
{
    const std::size_t at = out.find("| " + name);
    if (at == std::string::npos) return {};
    std::istringstream row(out.substr(at, out.find('\n', at) - at));
    std::vector<std::string> cells;
    for (std::string cell; std::getline(row, cell, '|');) cells.push_back(cell);
    return cells;
}
} // namespace

// The generated set at the default settings (seed 1, 200 vertices): tablet, closed slab,
// scan-like slab (3:1 triangles, 4x density, noise of a tenth of an edge, long walls) and a
// scan-like sheet 2 R thick. Bounds: means of V̂ and Ŝ within 1e-3; P̂ (checked, exact where
// the kernels blur) mean 5e-4 and largest 5e-3, L̂ 1.5e-3 and 1.5e-2; on the tablet V̂ at R
// within 5e-4 at every vertex; and the share of P and L values the check evaluated exactly
// is stated.
TEST(AccuracyCli, GeneratedSetMeansWithinBounds)
{
    const msii::test::TempDir dir;
    const msii::test::RunResult r = msii::test::runProgram(MSII_ACCURACY_EXE, "", dir.path());
    ASSERT_EQ(r.code, 0) << r.err;
    std::size_t rows = 0;
    for (const std::string name : {"tablet", "closed tablet slab", "scan-like slab", "scan-like sheet"}) {
        const std::vector<std::string> cells = rowCells(r.out, name);
        ASSERT_EQ(cells.size(), 10u) << name << "\n" << r.out;
        const double bound[4] = {1e-3, 1e-3, 5e-4, 1.5e-3}, largestBound[4] = {1, 1, 5e-3, 1.5e-2};
        for (std::size_t c = 4; c < 8; ++c) {
            double mean = -1, largest = -1;
            ASSERT_EQ(std::sscanf(cells[c].c_str(), " %lf / %lf", &mean, &largest), 2) << cells[c];
            EXPECT_GT(mean, 0.0) << name << " column " << c;  // something was compared
            EXPECT_LE(mean, bound[c - 4]) << name << " column " << c << ": " << cells[c];
            EXPECT_LE(largest, largestBound[c - 4]) << name << " column " << c << ": " << cells[c];
        }
        if (name == std::string("tablet")) {
            double mean = -1, largest = -1;
            ASSERT_EQ(std::sscanf(cells[8].c_str(), " %lf / %lf", &mean, &largest), 2) << cells[8];
            EXPECT_GT(largest, 0.0);
            EXPECT_LE(largest, 5e-4) << "V at R on the tablet: " << cells[8];
        }
        ++rows;
    }
    EXPECT_EQ(rows, 4u);
    const std::size_t shares = [&] {
        std::size_t n = 0;
        for (std::size_t at = 0; (at = r.out.find("P and L exact where the kernels blur: ", at)) != std::string::npos; ++at) ++n;
        return n;
    }();
    EXPECT_EQ(shares, 4u) << r.out;
}

TEST(AccuracyCli, MeshWithoutRadiusIsAUsageError)
{
    const msii::test::TempDir dir;
    const msii::test::RunResult r = msii::test::runProgram(MSII_ACCURACY_EXE, "some.ply", dir.path());
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("-r"), std::string::npos) << r.err;
}

// --by-radius splits the differences by range of radii (3-8, 8-16, over 16 median edges):
// on a flat patch with R of 16 edges the first two ranges hold radii and are small, the
// last holds none and says so ("–") instead of printing zeros.
TEST(AccuracyCli, ByRadiusGivesEachRangeOrADash)
{
    const msii::test::TempDir dir;
    const std::string mesh = writeFlatPatch(dir);
    const msii::test::RunResult r =
        msii::test::runProgram(MSII_ACCURACY_EXE, "'" + mesh + "' -r 0.75 --vertices 40 --by-radius", dir.path());
    ASSERT_EQ(r.code, 0) << r.err;
    const double edges = [&] {
        const std::vector<std::string> cells = rowCells(r.out, mesh);
        return cells.size() > 3 ? std::stod(cells[3]) : 0.0;
    }();
    ASSERT_GT(edges, 8.0) << r.out;
    ASSERT_LT(edges, 16.0) << r.out;
    std::size_t compared = 0;
    for (const char* range : {"radii of 3–8 edges", "radii of 8–16 edges", "radii of over 16 edges"}) {
        const std::vector<std::string> cells = rowCells(r.out, "  " + std::string(range));
        ASSERT_EQ(cells.size(), 10u) << range << "\n" << r.out;
        for (std::size_t c = 4; c < 8; ++c) {
            double mean = -1, largest = -1;
            if (std::string(range) == "radii of over 16 edges") {
                EXPECT_NE(cells[c].find("–"), std::string::npos) << range << ": " << cells[c];
                continue;
            }
            ASSERT_EQ(std::sscanf(cells[c].c_str(), " %lf / %lf", &mean, &largest), 2) << range << ": " << cells[c];
            EXPECT_LE(mean, largest);
            EXPECT_LE(largest, 2e-3) << range << " column " << c << ": " << cells[c];
            ++compared;
        }
    }
    EXPECT_EQ(compared, 8u);
}
