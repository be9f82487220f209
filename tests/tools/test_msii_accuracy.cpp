// msii-accuracy as users run it: on a given mesh it prints one table row per mesh with the
// mean and largest differences of V̂, Ŝ, P̂ and L̂ between the fast and the exact mode. On a
// flat open patch both modes are near-exact, so the row's figures must be small; a missing
// radius is a usage error.
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

TEST(AccuracyCli, FlatPatchRowIsSmallAndComplete)
{
    const msii::test::TempDir dir;
    samples::HeightFieldOptions o;
    o.kind = samples::HeightFieldKind::Plane;
    o.width = 5;
    o.height = 5;
    o.spacing = 0.05;
    const std::string mesh = dir.file("plane.ply");
    writePly(mesh, samples::makeHeightField(o), {});
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

TEST(AccuracyCli, MeshWithoutRadiusIsAUsageError)
{
    const msii::test::TempDir dir;
    const msii::test::RunResult r = msii::test::runProgram(MSII_ACCURACY_EXE, "some.ply", dir.path());
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("-r"), std::string::npos) << r.err;
}
