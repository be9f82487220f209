/// @file test_profile_section.cpp
/// @brief Tests of vessels/profile_section.h: the section through the axis of a generated
/// vessel lies on its true profile and covers it; x is positive on the side of the point the
/// plane goes through and y starts at the lowest point; a plane section of a cube is its
/// square; the SVG has its parts.

#include <msii/core/errors.h>
#include <msii/samples/generators.h>
#include <msii/samples/vessels.h>
#include <msii/vessels/profile_section.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "../support/temp_dir.h"

using namespace msii;
using namespace msii::samples;

namespace {

double distanceToPolyline(double r, double z, const std::vector<std::array<double, 2>>& line)
{
    double best = 1e300;
    for (std::size_t i = 0; i + 1 < line.size(); ++i) {
        const double ax = line[i][0], ay = line[i][1], dx = line[i + 1][0] - ax, dy = line[i + 1][1] - ay;
        const double l2 = dx * dx + dy * dy;
        const double t = l2 > 0 ? std::clamp(((r - ax) * dx + (z - ay) * dy) / l2, 0.0, 1.0) : 0.0;
        best = std::min(best, std::hypot(r - ax - t * dx, z - ay - t * dy));
    }
    return best;
}

AxisOfRotation trueAxis(const Vessel& v)
{
    AxisOfRotation a;
    a.point = v.axisPoint, a.direction = normalized(v.axisDirection), a.meanRadius = 40;
    return a;
}

}  // namespace

TEST(ProfileSection, TheSectionThroughTheAxisIsTheTrueProfile)
{
    VesselOptions o;
    o.spacing = 0.7;
    o.markDepth = 0;
    o.poseSeed = 3;
    const Vessel v = makeVessel(o);
    const AxisOfRotation axis = trueAxis(v);
    const Vec3 through = axis.point + normalized(cross(axis.direction, Vec3(0.3, 0.5, 0.8))) * 30 + axis.direction * 10;
    const Section s = axisSection(v.mesh, axis, through);
    double worst = 0;
    for (const SectionLine& l : s.lines)
        for (const auto& p : l.points) worst = std::max(worst, distanceToPolyline(std::abs(p[0]), p[1], v.section));
    double trueLength = 0;
    for (std::size_t i = 0; i + 1 < v.section.size(); ++i)
        trueLength += std::hypot(v.section[i + 1][0] - v.section[i][0], v.section[i + 1][1] - v.section[i][1]);
    EXPECT_LT(worst, 0.07 * o.spacing);  // points on the mesh's edges, a tenth of an edge from the curve
    EXPECT_NEAR(s.length, 2 * trueLength, 0.01 * 2 * trueLength);
    EXPECT_NEAR(s.yMin, 0, 1e-6);
    EXPECT_NEAR(s.yMax, o.height, 0.01);
    // x positive towards the point the plane goes through.
    EXPECT_GT(dot(through - axis.point, s.xAxis), 0);
    EXPECT_NEAR(dot(s.xAxis, axis.direction), 0, 1e-12);
    EXPECT_THROW(axisSection(v.mesh, axis, axis.point + axis.direction * 5), InvalidInputError);
}

TEST(ProfileSection, APlaneSectionOfACubeIsItsSquare)
{
    CubeOptions o;
    o.side = 10, o.spacing = 0.5;
    const Section s = planeSection(makeCube(o), Vec3(5, 5, 5.1), Vec3(0, 0, 1));
    ASSERT_EQ(s.lines.size(), 1u);
    EXPECT_TRUE(s.lines[0].closed);
    EXPECT_NEAR(s.length, 40, 1e-9);
    EXPECT_NEAR(s.xMax, 10, 1e-9);
    EXPECT_NEAR(s.yMax, 10, 1e-9);
    EXPECT_THROW(planeSection(makeCube(o), Vec3(5, 5, 50), Vec3(0, 0, 1)), InvalidInputError);
    EXPECT_THROW(planeSection(makeCube(o), Vec3(5, 5, 5), Vec3(0, 0, 0)), InvalidInputError);
}

TEST(ProfileSection, TheDrawingHasItsParts)
{
    VesselOptions o;
    o.shape = VesselShape::Cylinder;
    o.spacing = 1.0;
    const Vessel v = makeVessel(o);
    const AxisOfRotation axis = trueAxis(v);
    const Section s = axisSection(v.mesh, axis, axis.point + Vec3(1, 0, 0));
    const test::TempDir dir;
    ProfileDrawingOptions d;
    d.scale = 0.5;
    d.axisX = 0.0;
    d.rimDiameter = 100.0;
    d.title = "a <vessel> & more";
    writeProfileSvg(dir.file("p.svg"), s, d);
    std::ifstream in(dir.file("p.svg"));
    std::stringstream text;
    text << in.rdbuf();
    const std::string svg = text.str();
    for (const char* part : {"class=\"axis\"", "stroke-dasharray", "class=\"rim\"", "&#216; 100.0 mm", "scale 1:2",
                             "a &lt;vessel&gt; &amp; more", "fill=\"#222\""})
        EXPECT_NE(svg.find(part), std::string::npos) << part;
    // At 1:2 the drawing is half the vessel's size, in mm.
    const std::size_t at = svg.find("height=\"");
    ASSERT_NE(at, std::string::npos);
    EXPECT_GT(std::stod(svg.substr(at + 8)), 0.5 * o.height);
    EXPECT_LT(std::stod(svg.substr(at + 8)), 0.5 * o.height + 60);
}
