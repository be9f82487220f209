/// Tests of map/map_frame.h and map/rasterize.h: the best-fit plane of tilted planes (normal,
/// facing, right-handed axes, u along the longer extent, zero heights), the named and
/// direction views and their parsing, the resolution rules (longer side in pixels, pixel size,
/// DPI, given exactly once, positive, within maxSidePixels, not edge-on), the pixel grid (centres
/// inside the mesh's bounding box, the box inside the image), and rasterisation (no gaps on
/// shared edges, barycentrics that reproduce the pixel centres, the depth test from both
/// sides, ties to the lower triangle index, the same result with 1 and 2 threads).

#include <msii/featuremap/map_frame.h>
#include <msii/featuremap/rasterize.h>

#include <msii/core/errors.h>
#include <msii/samples/generators.h>

#include "../support/flat_patch.h"
#include "../support/rotation.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

using namespace msii;
using msii::test::flatPatch;

namespace msii {
/// Readable Vec3 values in gtest messages.
void PrintTo(const Vec3& v, std::ostream* os) { *os << "(" << v.x << ", " << v.y << ", " << v.z << ")"; }
} // namespace msii

namespace {

/// A measured value for the XML report (--gtest_output=xml), not printed.
void record(const std::string& key, double value)
{
    std::ostringstream s;
    s.precision(3);
    s << value;
    ::testing::Test::RecordProperty(key, s.str());
}

TriMesh cubeMesh(double side, double spacing)
{
    samples::CubeOptions o;
    o.side = side;
    o.spacing = spacing;
    return samples::makeCube(o);
}

TriMesh sphereMesh(double radius, double spacing)
{
    samples::SphereOptions o;
    o.radius = radius;
    o.spacing = spacing;
    return samples::makeSphere(o);
}

/// Both meshes in one (the second's triangles after the first's).
TriMesh concat(const TriMesh& a, const TriMesh& b)
{
    TriMesh m = a;
    const auto offset = std::uint32_t(a.numVertices());
    m.points.insert(m.points.end(), b.points.begin(), b.points.end());
    for (const Triangle& t : b.triangles) m.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    return m;
}

TriMesh translated(TriMesh m, const Vec3& d)
{
    for (Vec3& p : m.points) p += d;
    return m;
}

MapFrameOptions viewOptions(const std::string& view, double pixelSize)
{
    MapFrameOptions o;
    parseMapView(view, o);
    o.pixelSize = pixelSize;
    return o;
}

double maxAbs(const Vec3& a) { return std::max({std::abs(a.x), std::abs(a.y), std::abs(a.z)}); }

void expectVecNear(const Vec3& a, const Vec3& b, double tolerance, const std::string& what)
{
    EXPECT_LE(maxAbs(a - b), tolerance) << what << ": (" << a.x << ", " << a.y << ", " << a.z << ") vs ("
                                        << b.x << ", " << b.y << ", " << b.z << ")";
}

/// Orthonormal and right-handed (axisU × axisV = normal).
void expectRightHanded(const MapFrame& f, const std::string& what)
{
    EXPECT_NEAR(norm(f.axisU), 1.0, 1e-12) << what;
    EXPECT_NEAR(norm(f.axisV), 1.0, 1e-12) << what;
    EXPECT_NEAR(norm(f.normal), 1.0, 1e-12) << what;
    EXPECT_NEAR(dot(f.axisU, f.axisV), 0.0, 1e-12) << what;
    EXPECT_NEAR(dot(f.axisU, f.normal), 0.0, 1e-12) << what;
    EXPECT_NEAR(dot(f.axisV, f.normal), 0.0, 1e-12) << what;
    expectVecNear(cross(f.axisU, f.axisV), f.normal, 1e-12, what + ": u x v = normal");
}

struct Box2 {
    double minU = std::numeric_limits<double>::max(), maxU = -std::numeric_limits<double>::max();
    double minV = std::numeric_limits<double>::max(), maxV = -std::numeric_limits<double>::max();
};

Box2 projectedBox(const TriMesh& mesh, const MapFrame& f)
{
    Box2 b;
    for (const Vec3& p : mesh.points) {
        const Vec3 m = f.toMap(p);
        b.minU = std::min(b.minU, m.x), b.maxU = std::max(b.maxU, m.x);
        b.minV = std::min(b.minV, m.y), b.maxV = std::max(b.maxV, m.y);
    }
    return b;
}

double centreU(const MapFrame& f, int x) { return f.minU + (x + 0.5) * f.pixelSize; }
double centreV(const MapFrame& f, int y) { return f.maxV - (y + 0.5) * f.pixelSize; }

// ---------------------------------------------------------------------------------------------
// Best-fit plane

struct TiltCase {
    double w, h;       // the patch's size before the rotation
    Vec3 axis;         // rotation axis (not normalised)
    double angle;      // radians
    Vec3 offset;
};

void PrintTo(const TiltCase& c, std::ostream* os)
{
    *os << c.w << " x " << c.h << " rotated by " << c.angle << " about (" << c.axis.x << ", " << c.axis.y << ", "
        << c.axis.z << ")";
}

class BestFitRotatedPlane : public ::testing::TestWithParam<TiltCase> {};

TEST_P(BestFitRotatedPlane, NormalAxesAndHeights)
{
    const TiltCase c = GetParam();
    const test::Rotation rot(normalized(c.axis), c.angle);
    TriMesh mesh = flatPatch(c.w, c.h, 0.5);
    for (Vec3& p : mesh.points) p = rot(p) + c.offset;
    const double size = std::max(c.w, c.h);

    MapFrameOptions o;  // BestFit by default
    o.longerSidePixels = 100;
    const MapFrame f = makeMapFrame(mesh, o);
    EXPECT_EQ(f.view, MapView::BestFit);
    expectRightHanded(f, "best fit");

    // The patch faces +z before the rotation, so the frame faces rot(+z) (not its opposite).
    const Vec3 n = rot(Vec3(0, 0, 1));
    expectVecNear(f.normal, n, 1e-9, "normal");
    record("normalError", maxAbs(f.normal - n));

    // u along the longer side of the rectangle (either sign), v along the shorter one.
    const Vec3 longer = rot(c.w >= c.h ? Vec3(1, 0, 0) : Vec3(0, 1, 0));
    const Vec3 shorter = rot(c.w >= c.h ? Vec3(0, 1, 0) : Vec3(1, 0, 0));
    EXPECT_NEAR(std::abs(dot(f.axisU, longer)), 1.0, 1e-9);
    EXPECT_NEAR(std::abs(dot(f.axisV, shorter)), 1.0, 1e-9);

    // The origin is the centroid of the rectangle; every vertex lies in the plane.
    expectVecNear(f.origin, rot(Vec3(c.w / 2, c.h / 2, 0)) + c.offset, 1e-9 * size, "origin");
    double worst = 0;
    for (const Vec3& p : mesh.points) worst = std::max(worst, std::abs(f.toMap(p).z));
    EXPECT_LE(worst, 1e-9 * size);
    record("axisUError", std::abs(std::abs(dot(f.axisU, longer)) - 1));
    record("relativeHeight", worst / size);

    // 100 pixels along the longer side; the shorter side in proportion.
    EXPECT_EQ(std::max(f.width, f.height), 100);
    EXPECT_EQ(f.width, 100);  // u is the longer extent
    EXPECT_EQ(f.height, int(std::ceil(std::min(c.w, c.h) / f.pixelSize - 1e-9)));
    EXPECT_NEAR(f.pixelSize, size / 100, 1e-12 * size);

    // flip looks at the other side: normal reversed, still right-handed.
    MapFrameOptions flipped = o;
    flipped.flip = true;
    const MapFrame g = makeMapFrame(mesh, flipped);
    expectRightHanded(g, "flipped");
    expectVecNear(g.normal, -n, 1e-9, "flipped normal");
    EXPECT_NEAR(std::abs(dot(g.axisU, longer)), 1.0, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, BestFitRotatedPlane,
    ::testing::Values(TiltCase{20, 10, {1, 2, 3}, 0.7, {5, -3, 2}},
                      TiltCase{8, 20, {-2, 1, 0.5}, 2.1, {-40, 17, 100}},   // longer side along y
                      TiltCase{12, 7, {0, 1, 0}, 3.0, {0, 0, 0}},           // almost upside down
                      TiltCase{15, 9, {1, 0, 0}, 1.5707963267948966, {1, 1, 1}}));  // on its edge: vertical

TEST(BestFit, LinearHeightField)
{
    // z = a x + b y + c over a 12 x 9 patch: normal (-a, -b, 1) / |.|, facing up.
    const double a = 0.3, b = -0.2, c = 1.7;
    TriMesh mesh = flatPatch(12, 9, 0.3, 7);
    for (Vec3& p : mesh.points) p.z = a * p.x + b * p.y + c;
    MapFrameOptions o;
    o.pixelSize = 0.1;
    const MapFrame f = makeMapFrame(mesh, o);
    expectRightHanded(f, "linear field");
    expectVecNear(f.normal, normalized(Vec3(-a, -b, 1)), 1e-9, "normal");
    double worst = 0;
    for (const Vec3& p : mesh.points) worst = std::max(worst, std::abs(f.toMap(p).z));
    EXPECT_LE(worst, 1e-9 * 12);
    record("normalError", maxAbs(f.normal - normalized(Vec3(-a, -b, 1))));
    record("relativeHeight", worst / 12);
    const Box2 box = projectedBox(mesh, f);
    EXPECT_GE(box.maxU - box.minU, box.maxV - box.minV);  // u along the longer extent
    EXPECT_GE(f.width, f.height);
}

// ---------------------------------------------------------------------------------------------
// Named and direction views

TEST(MapView, NamedViewsAxes)
{
    struct Named {
        const char* name;
        MapView view;
        Vec3 u, v, n;
    };
    // Seen from that side (the normal points at the viewer); side views keep +z up; +z has
    // u = +x, v = +y (documented), −z mirrors u.
    const Named named[] = {
        {"+x", MapView::PlusX, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}},
        {"-x", MapView::MinusX, {0, -1, 0}, {0, 0, 1}, {-1, 0, 0}},
        {"+y", MapView::PlusY, {-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
        {"-y", MapView::MinusY, {1, 0, 0}, {0, 0, 1}, {0, -1, 0}},
        {"+z", MapView::PlusZ, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
        {"-z", MapView::MinusZ, {-1, 0, 0}, {0, 1, 0}, {0, 0, -1}},
    };
    const TriMesh cube = translated(cubeMesh(10, 2), Vec3(1, 2, 3));  // [1,11] x [2,12] x [3,13]
    for (const Named& c : named) {
        MapFrameOptions o;
        parseMapView(c.name, o);
        EXPECT_EQ(o.view, c.view) << c.name;
        o.longerSidePixels = 50;
        const MapFrame f = makeMapFrame(cube, o);
        EXPECT_EQ(f.view, c.view);
        EXPECT_EQ(mapViewName(f), c.name);
        expectRightHanded(f, c.name);
        EXPECT_EQ(f.axisU, c.u) << c.name;
        EXPECT_EQ(f.axisV, c.v) << c.name;
        EXPECT_EQ(f.normal, c.n) << c.name;
        // The origin is the surface's centroid (the cube's centre) for every view.
        expectVecNear(f.origin, Vec3(6, 7, 8), 1e-9, c.name);
        // A cube face: 50 x 50 pixels of 0.2, the image exactly over the projected square.
        EXPECT_EQ(f.width, 50) << c.name;
        EXPECT_EQ(f.height, 50) << c.name;
        EXPECT_NEAR(f.pixelSize, 0.2, 1e-12) << c.name;
        const Box2 box = projectedBox(cube, f);
        EXPECT_NEAR(f.minU, box.minU, 1e-9) << c.name;
        EXPECT_NEAR(f.maxV, box.maxV, 1e-9) << c.name;
        // toMap: the cube's far corner along the normal has height = its offset along n.
        EXPECT_NEAR(f.toMap(Vec3(11, 12, 13)).z, dot(Vec3(11, 12, 13) - f.origin, c.n), 1e-12) << c.name;
    }
    MapFrameOptions best;
    best.view = MapView::PlusX;
    parseMapView("best", best);
    EXPECT_EQ(best.view, MapView::BestFit);
}

TEST(MapView, DirectionViews)
{
    const TriMesh sphere = sphereMesh(5, 1);
    MapFrameOptions o;
    parseMapView("1,1,1", o);
    EXPECT_EQ(o.view, MapView::Direction);
    EXPECT_EQ(o.direction, Vec3(1, 1, 1));
    o.longerSidePixels = 64;
    const MapFrame f = makeMapFrame(sphere, o);
    expectRightHanded(f, "direction 1,1,1");
    expectVecNear(f.normal, Vec3(1, 1, 1) / std::sqrt(3.0), 1e-15, "normal");
    EXPECT_GT(f.axisV.z, 0);  // up on the picture is +z projected
    EXPECT_NEAR(f.axisU.z, 0, 1e-15);  // the horizon stays horizontal
    EXPECT_EQ(mapViewName(f).rfind("direction ", 0), 0u) << mapViewName(f);

    // Any length, with spaces: the same frame.
    MapFrameOptions o2;
    parseMapView(" 2.5, 2.5 ,2.5", o2);
    EXPECT_EQ(o2.view, MapView::Direction);
    o2.longerSidePixels = 64;
    const MapFrame f2 = makeMapFrame(sphere, o2);
    expectVecNear(f2.normal, f.normal, 1e-15, "scaled direction");
    expectVecNear(f2.axisU, f.axisU, 1e-15, "scaled direction u");

    // Looking straight down: up is +y, so the frame equals the +z view.
    MapFrameOptions o3;
    parseMapView("0,0,3", o3);
    o3.longerSidePixels = 64;
    const MapFrame f3 = makeMapFrame(sphere, o3);
    expectVecNear(f3.axisU, Vec3(1, 0, 0), 1e-15, "0,0,3 u");
    expectVecNear(f3.axisV, Vec3(0, 1, 0), 1e-15, "0,0,3 v");
    expectVecNear(f3.normal, Vec3(0, 0, 1), 1e-15, "0,0,3 normal");
}

TEST(MapView, ParseRejects)
{
    for (const char* bad : {"0,0,0", "abc", "", "1,2", "1,2,3,4", "1;2;3", "nan,0,1", "inf,0,0", "+w", "BEST", "1,2,3x"}) {
        MapFrameOptions o;
        EXPECT_THROW(parseMapView(bad, o), InvalidInputError) << "'" << bad << "'";
    }
    // A zero direction set directly is rejected by makeMapFrame too.
    MapFrameOptions o;
    o.view = MapView::Direction;
    o.direction = Vec3(0, 0, 0);
    o.longerSidePixels = 10;
    EXPECT_THROW(makeMapFrame(cubeMesh(1, 0.5), o), InvalidInputError);
}

// ---------------------------------------------------------------------------------------------
// Resolution

TEST(MapResolution, LongerSidePixelSizeAndDpi)
{
    const TriMesh plane = flatPatch(20, 10, 0.5);
    {
        MapFrameOptions o = viewOptions("+z", 0);
        o.longerSidePixels = 200;
        const MapFrame f = makeMapFrame(plane, o);
        EXPECT_EQ(f.width, 200);
        EXPECT_EQ(f.height, 100);
        EXPECT_NEAR(f.pixelSize, 0.1, 1e-15);
    }
    {
        MapFrameOptions o = viewOptions("+z", 0);
        o.longerSidePixels = 7;  // 20 / 7 per pixel: 10 / (20 / 7) = 3.5 → 4 rows
        const MapFrame f = makeMapFrame(plane, o);
        EXPECT_EQ(f.width, 7);
        EXPECT_EQ(f.height, 4);
    }
    {
        const MapFrame f = makeMapFrame(plane, viewOptions("+z", 0.3));  // 66.7 x 33.3
        EXPECT_EQ(f.pixelSize, 0.3);
        EXPECT_EQ(f.width, 67);
        EXPECT_EQ(f.height, 34);
    }
    {
        const MapFrame f = makeMapFrame(plane, viewOptions("+z", 0.5));  // exactly 40 x 20
        EXPECT_EQ(f.width, 40);
        EXPECT_EQ(f.height, 20);
    }
    {
        MapFrameOptions o = viewOptions("+z", 0);
        o.dpi = 254;  // 0.1 mm
        const MapFrame f = makeMapFrame(plane, o);
        EXPECT_NEAR(f.pixelSize, 0.1, 1e-15);
        EXPECT_EQ(f.width, 200);
        EXPECT_EQ(f.height, 100);
    }
    {
        MapFrameOptions o = viewOptions("+z", 0);
        o.dpi = 100;  // 0.254 mm: 78.7 x 39.4
        const MapFrame f = makeMapFrame(plane, o);
        EXPECT_DOUBLE_EQ(f.pixelSize, 0.254);
        EXPECT_EQ(f.width, 79);
        EXPECT_EQ(f.height, 40);
    }
    {
        // The largest allowed side is allowed.
        MapFrameOptions o = viewOptions("+z", 0);
        o.longerSidePixels = 100;
        o.maxSidePixels = 100;
        const MapFrame f = makeMapFrame(plane, o);
        EXPECT_EQ(f.width, 100);
        EXPECT_EQ(f.height, 50);
    }
}

TEST(MapResolution, Rejects)
{
    const TriMesh plane = flatPatch(20, 10, 0.5);
    const auto throws = [&](MapFrameOptions o, const char* what) {
        EXPECT_THROW(makeMapFrame(plane, o), InvalidInputError) << what;
    };
    MapFrameOptions none;
    none.view = MapView::PlusZ;
    throws(none, "no resolution");
    {
        MapFrameOptions o = none;
        o.longerSidePixels = 100, o.pixelSize = 0.1;
        throws(o, "pixels and pixel size");
        o.pixelSize = 0, o.dpi = 300;
        throws(o, "pixels and dpi");
        o.longerSidePixels = 0, o.pixelSize = 0.1;
        throws(o, "pixel size and dpi");
        o.longerSidePixels = 100;
        throws(o, "all three");
    }
    {
        MapFrameOptions o = none;
        o.longerSidePixels = -5;
        throws(o, "negative pixels");
    }
    {
        MapFrameOptions o = none;
        o.pixelSize = -0.1;
        throws(o, "negative pixel size");
        o.pixelSize = std::numeric_limits<double>::quiet_NaN();
        throws(o, "NaN pixel size");
        o.pixelSize = std::numeric_limits<double>::infinity();
        throws(o, "infinite pixel size");
    }
    {
        MapFrameOptions o = none;
        o.dpi = -300;
        throws(o, "negative dpi");
        o.dpi = std::numeric_limits<double>::infinity();
        throws(o, "infinite dpi");
    }
    {
        MapFrameOptions o = none;
        o.longerSidePixels = 20000;  // beyond the default 16384
        throws(o, "too many pixels");
        o.longerSidePixels = 101;
        o.maxSidePixels = 100;
        throws(o, "one pixel beyond maxSidePixels");
        o.longerSidePixels = 0;
        o.pixelSize = 0.001;  // 20000 x 10000
        o.maxSidePixels = 16384;
        throws(o, "pixel size too small");
    }
    {
        // The plane z = 0 seen edge-on from +x and from -y.
        MapFrameOptions o = viewOptions("+x", 0.1);
        throws(o, "edge-on +x");
        o = viewOptions("-y", 0.1);
        throws(o, "edge-on -y");
        o = viewOptions("1,0,0", 0.1);
        throws(o, "edge-on direction");
    }
    {
        MapFrameOptions o = viewOptions("+z", 0.1);
        EXPECT_THROW(makeMapFrame(TriMesh{}, o), InvalidInputError);
        TriMesh pointsOnly;
        pointsOnly.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        EXPECT_THROW(makeMapFrame(pointsOnly, o), InvalidInputError);
        TriMesh degenerate = pointsOnly;
        degenerate.triangles = {{0, 1, 1}};
        EXPECT_THROW(makeMapFrame(degenerate, o), InvalidInputError);
    }
}

// ---------------------------------------------------------------------------------------------
// Pixel geometry

TEST(MapPixels, CentresInsideBoundingBoxAndBoxInsideImage)
{
    // [3, 23] x [-2, 8] at z = 0.
    const TriMesh plane = translated(flatPatch(20, 10, 0.5), Vec3(3, -2, 0));
    for (double ps : {0.3, 0.5, 0.07, 1.7}) {
        const MapFrame f = makeMapFrame(plane, viewOptions("+z", ps));
        // Map coordinates are measured from the origin, the surface's centroid (13, 3, 0).
        EXPECT_NEAR(f.origin.x, 13, 1e-9);
        EXPECT_NEAR(f.origin.y, 3, 1e-9);
        const double ox = f.origin.x, oy = f.origin.y;
        EXPECT_EQ(f.width, int(std::ceil(20 / ps - 1e-9))) << ps;
        EXPECT_EQ(f.height, int(std::ceil(10 / ps - 1e-9))) << ps;
        // The box [3, 23] x [-2, 8] inside the image (up to 1e-9 pixel), centred in it.
        const double slack = 1e-9 * ps;
        EXPECT_LE(f.minU + ox, 3 + slack) << ps;
        EXPECT_GE(f.minU + ox + f.width * ps, 23 - slack) << ps;
        EXPECT_GE(f.maxV + oy, 8 - slack) << ps;
        EXPECT_LE(f.maxV + oy - f.height * ps, -2 + slack) << ps;
        EXPECT_NEAR(f.minU + ox + 0.5 * f.width * ps, 13, 1e-9) << ps;
        EXPECT_NEAR(f.maxV + oy - 0.5 * f.height * ps, 3, 1e-9) << ps;
        // Less than one pixel of margin in all.
        EXPECT_LT(f.width * ps - 20, ps) << ps;
        EXPECT_LT(f.height * ps - 10, ps) << ps;
        // Every pixel centre maps back into the box, and pixelX/pixelY invert the formula;
        // the +z view's map coordinates are x and y.
        for (int x = 0; x < f.width; ++x) {
            const double u = centreU(f, x);
            EXPECT_GT(u + ox, 3) << ps << " x " << x;
            EXPECT_LT(u + ox, 23) << ps << " x " << x;
            EXPECT_NEAR(f.pixelX(u), x + 0.5, 1e-9) << ps << " x " << x;
        }
        for (int y = 0; y < f.height; ++y) {
            const double v = centreV(f, y);
            EXPECT_GT(v + oy, -2) << ps << " y " << y;
            EXPECT_LT(v + oy, 8) << ps << " y " << y;
            EXPECT_NEAR(f.pixelY(v), y + 0.5, 1e-9) << ps << " y " << y;
        }
        // Row 0 is the top (largest v), column 0 the left (smallest u).
        EXPECT_GT(centreV(f, 0), centreV(f, f.height - 1));
        EXPECT_LT(centreU(f, 0), centreU(f, f.width - 1));
        const Vec3 m = f.toMap(Vec3(4.5, 6.25, 0.75));
        EXPECT_EQ(m, Vec3(4.5 - ox, 6.25 - oy, 0.75 - f.origin.z));
    }
}

// ---------------------------------------------------------------------------------------------
// Rasterisation

/// Background pixels whose centre lies strictly inside [0, w] × [0, h] of the patch, with the
/// patch's local coordinates computed by @p toLocal from the pixel centre's 3-D point.
template <class ToLocal>
int gapsInside(const PixelHits& hits, const MapFrame& f, double w, double h, ToLocal toLocal)
{
    int gaps = 0;
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x) {
            const Vec3 p = f.origin + f.axisU * centreU(f, x) + f.axisV * centreV(f, y);
            const Vec3 local = toLocal(p);
            const double eps = 1e-9;
            if (local.x > eps && local.x < w - eps && local.y > eps && local.y < h - eps &&
                hits.triangle[hits.index(x, y)] == PixelHits::kNone)
                ++gaps;
        }
    return gaps;
}

/// Largest distance (pixels) between a covered pixel's centre and the point its triangle and
/// barycentrics give; also checks that the barycentrics are within the triangle.
double barycentricError(const TriMesh& mesh, const MapFrame& f, const PixelHits& hits, int& outside)
{
    double worst = 0;
    outside = 0;
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x) {
            const std::size_t k = hits.index(x, y);
            const std::uint32_t t = hits.triangle[k];
            if (t == PixelHits::kNone) continue;
            const double w1 = hits.b1[k], w2 = hits.b2[k], w0 = 1 - w1 - w2;
            if (w1 < 0 || w2 < 0 || w0 < -1e-6) ++outside;
            const Triangle& tri = mesh.triangles[t];
            const Vec3 m = f.toMap(mesh.points[tri[0]]) * w0 + f.toMap(mesh.points[tri[1]]) * w1 +
                           f.toMap(mesh.points[tri[2]]) * w2;
            const double ex = f.pixelX(m.x) - (x + 0.5), ey = f.pixelY(m.y) - (y + 0.5);
            worst = std::max(worst, std::hypot(ex, ey));
            // The depth is the interpolated height.
            const double dh = std::abs(double(hits.depth[k]) - m.z);
            if (dh > 1e-5 * (1 + std::abs(m.z))) ++outside;
        }
    return worst;
}

TEST(Rasterize, PlaneFromAboveIsFullyCovered)
{
    const TriMesh plane = flatPatch(20, 10, 0.25, 3);
    for (const char* view : {"+z", "-z"}) {  // seen from behind too (both orientations count)
        const MapFrame f = makeMapFrame(plane, viewOptions(view, 0.04));  // 500 x 250
        ASSERT_EQ(f.width, 500);
        ASSERT_EQ(f.height, 250);
        const PixelHits hits = rasterize(plane, f);
        EXPECT_EQ(hits.width, f.width);
        EXPECT_EQ(hits.height, f.height);
        ASSERT_EQ(hits.triangle.size(), std::size_t(f.width) * std::size_t(f.height));
        // Every pixel centre lies strictly inside the rectangle: no background at all.
        EXPECT_EQ(gapsInside(hits, f, 20, 10, [](const Vec3& p) { return p; }), 0) << view;
        EXPECT_EQ(hits.covered, std::size_t(f.width) * std::size_t(f.height)) << view;
        int outside = 0;
        const double err = barycentricError(plane, f, hits, outside);
        EXPECT_LE(err, 1e-4) << view;
        record(std::string("baryError") + view, err);
        EXPECT_EQ(outside, 0) << view;
        for (float d : hits.depth) {
            if (!(d == 0)) {
                ADD_FAILURE() << view << ": depth " << d << " on the plane z = 0";
                break;
            }
        }
    }
}

TEST(Rasterize, RotatedPlaneBestFitHasNoGaps)
{
    // A rotated patch seen along its own normal: non-dyadic coordinates everywhere; the
    // projection is the rectangle, so every pixel centre strictly inside it must be covered.
    const double w = 16, h = 11;
    const test::Rotation rot(normalized(Vec3(0.3, -1, 0.8)), 0.9);
    const Vec3 offset(2.5, -7, 3.25);
    TriMesh mesh = flatPatch(w, h, 0.2, 5);
    for (Vec3& p : mesh.points) p = rot(p) + offset;
    MapFrameOptions o;
    o.longerSidePixels = 480;
    const MapFrame f = makeMapFrame(mesh, o);
    const PixelHits hits = rasterize(mesh, f);
    const test::Rotation back = rot.inverse();
    EXPECT_EQ(gapsInside(hits, f, w, h, [&](const Vec3& p) { return back(p - offset); }), 0);
    int outside = 0;
    const double err = barycentricError(mesh, f, hits, outside);
    EXPECT_LE(err, 1e-4);
    EXPECT_EQ(outside, 0);
    record("baryError", err);
    record("covered", double(hits.covered));
    // The depth (height over the best-fit plane) is 0 on a flat patch.
    float worst = 0;
    for (std::size_t k = 0; k < hits.depth.size(); ++k)
        if (hits.triangle[k] != PixelHits::kNone) worst = std::max(worst, std::abs(hits.depth[k]));
    EXPECT_LE(worst, 1e-6f);
    record("depthWorst", worst);
}

TEST(Rasterize, CentresExactlyOnVerticesAndSharedEdges)
{
    // A regular 4 x 4 grid of unit squares split along the diagonals, and a pixel grid whose
    // centres fall exactly on the vertices, the edges and the diagonals (all dyadic).
    TriMesh mesh;
    const int n = 4;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) mesh.points.push_back(Vec3(i, j, 0));
    const auto id = [&](int i, int j) { return std::uint32_t(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            if ((i + j) % 2 == 0) {
                mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
                mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
            } else {
                mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
                mesh.triangles.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
            }
        }
    MapFrame f;
    f.view = MapView::PlusZ;
    f.axisU = {1, 0, 0}, f.axisV = {0, 1, 0}, f.normal = {0, 0, 1};
    f.pixelSize = 0.5;
    f.width = f.height = 2 * n + 1;  // centres at 0, 0.5, ..., 4
    f.minU = -0.25;
    f.maxV = n + 0.25;
    const PixelHits hits = rasterize(mesh, f);
    // The closed triangles cover every centre in [0, 4]², the border included.
    EXPECT_EQ(hits.covered, std::size_t(f.width * f.height));
    int outside = 0;
    EXPECT_LE(barycentricError(mesh, f, hits, outside), 1e-6);
    EXPECT_EQ(outside, 0);
    // Ties between triangles sharing the centre go to the lower index: the centre (0, 0)
    // (bottom-left, row 2n) is a vertex of triangles 0 and 1 only.
    EXPECT_EQ(hits.triangle[hits.index(0, 2 * n)], 0u);
}

/// Two parallel squares: A = [0, 10]² at z = 0 (triangles first), B = [4, 14] × [3, 13] at z = 1.
TEST(Rasterize, DepthTestShowsTheNearerSurface)
{
    const TriMesh a = flatPatch(10, 10, 0.5, 11);
    TriMesh b = translated(flatPatch(10, 10, 0.5, 12), Vec3(4, 3, 1));
    const TriMesh both = concat(a, b);
    const auto inA = [](std::uint32_t t, const TriMesh& m) { return t < m.numTriangles(); };
    for (const char* view : {"+z", "-z"}) {
        const MapFrame f = makeMapFrame(both, viewOptions(view, 0.1));
        ASSERT_EQ(f.width, 140);
        ASSERT_EQ(f.height, 130);
        const PixelHits hits = rasterize(both, f);
        const bool fromAbove = view[0] == '+';
        const double heightA = float((0.0 - f.origin.z) * f.normal.z), heightB = float((1.0 - f.origin.z) * f.normal.z);
        int checked[3] = {0, 0, 0}, wrong = 0, background = 0;
        for (int y = 0; y < f.height; ++y)
            for (int x = 0; x < f.width; ++x) {
                const Vec3 p = f.origin + f.axisU * centreU(f, x) + f.axisV * centreV(f, y);
                const bool overA = p.x > 0 && p.x < 10 && p.y > 0 && p.y < 10;
                const bool overB = p.x > 4 && p.x < 14 && p.y > 3 && p.y < 13;
                const std::size_t k = hits.index(x, y);
                const std::uint32_t t = hits.triangle[k];
                const double depth = hits.depth[k];
                if (!overA && !overB) {
                    // The corners outside both squares are background (centres 0.05 away).
                    if (t != PixelHits::kNone || !std::isnan(depth)) ++wrong;
                    ++background;
                    continue;
                }
                if (overA && overB) {
                    // From +z B (z = 1) hides A; from −z A (z = 0) hides B. Heights are
                    // measured from the centroid (z = 0.5): ±0.5.
                    const bool ok = t != PixelHits::kNone &&
                                    (fromAbove ? !inA(t, a) && depth == heightB : inA(t, a) && depth == heightA);
                    wrong += !ok;
                    ++checked[0];
                } else if (overA) {
                    wrong += !(t != PixelHits::kNone && inA(t, a) && depth == heightA);
                    ++checked[1];
                } else {
                    wrong += !(t != PixelHits::kNone && !inA(t, a) && depth == heightB);
                    ++checked[2];
                }
            }
        EXPECT_EQ(wrong, 0) << view;
        EXPECT_EQ(checked[0], 60 * 70) << view;  // overlap [4, 10] x [3, 10]
        EXPECT_GT(checked[1], 0);
        EXPECT_GT(checked[2], 0);
        EXPECT_EQ(background, 2 * 40 * 30) << view;  // [0,4]x[10,13] and [10,14]x[0,3]
        EXPECT_EQ(hits.covered, std::size_t(140 * 130 - 2 * 40 * 30)) << view;
    }
}

TEST(Rasterize, TiesGoToTheLowerTriangleIndex)
{
    // The same patch twice: every pixel sees a triangle of the first copy.
    const TriMesh a = flatPatch(10, 6, 0.4, 21);
    const TriMesh twice = concat(a, a);
    const MapFrame f = makeMapFrame(twice, viewOptions("+z", 0.05));
    const PixelHits hits = rasterize(twice, f);
    ASSERT_EQ(hits.covered, std::size_t(f.width) * std::size_t(f.height));
    std::size_t second = 0;
    for (std::uint32_t t : hits.triangle) second += t >= a.numTriangles();
    EXPECT_EQ(second, 0u);
}

TEST(Rasterize, SphereDepthIsTheNearHemisphere)
{
    const double r = 10;
    const TriMesh sphere = sphereMesh(r, 0.3);
    for (const char* view : {"+z", "-x", "1,-2,0.5"}) {
        MapFrameOptions o;
        parseMapView(view, o);
        o.longerSidePixels = 200;
        const MapFrame f = makeMapFrame(sphere, o);
        const PixelHits hits = rasterize(sphere, f);
        double worst = 0;
        int missing = 0;
        for (int y = 0; y < f.height; ++y)
            for (int x = 0; x < f.width; ++x) {
                const double u = centreU(f, x), v = centreV(f, y), rr = std::hypot(u, v);
                if (rr > 0.9 * r) continue;
                const std::size_t k = hits.index(x, y);
                if (hits.triangle[k] == PixelHits::kNone) {
                    ++missing;
                    continue;
                }
                worst = std::max(worst, std::abs(hits.depth[k] - std::sqrt(r * r - rr * rr)));
            }
        EXPECT_EQ(missing, 0) << view;
        EXPECT_LE(worst, 0.02) << view;  // chords of 0.3 mm triangles: below 0.01 here
        record(std::string("depthError") + view, worst);
    }
}

TEST(Rasterize, SameResultWithOneAndTwoThreads)
{
    const TriMesh sphere = sphereMesh(10, 0.3);
    MapFrameOptions o;
    parseMapView("1,2,3", o);
    o.longerSidePixels = 400;
    const MapFrame f = makeMapFrame(sphere, o);
    PixelHits one, two;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = rasterize(sphere, f);
    }
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
        two = rasterize(sphere, f);
    }
    ASSERT_GT(one.covered, 100000u);
    EXPECT_EQ(one.covered, two.covered);
    EXPECT_EQ(one.triangle, two.triangle);
    ASSERT_EQ(one.b1.size(), two.b1.size());
    EXPECT_EQ(std::memcmp(one.b1.data(), two.b1.data(), one.b1.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(one.b2.data(), two.b2.data(), one.b2.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(one.depth.data(), two.depth.data(), one.depth.size() * sizeof(float)), 0);
}

TEST(Rasterize, VertexNormalsAndInterpolate)
{
    TriMesh plane = flatPatch(6, 4, 0.5, 2);
    for (Vec3& p : plane.points) p.z = 0.5 * p.x - 0.25 * p.y;
    const Vec3 n = normalized(Vec3(-0.5, 0.25, 1));
    double worst = 0;
    for (const Vec3& m : vertexNormals(plane)) worst = std::max(worst, maxAbs(m - n));
    EXPECT_LE(worst, 1e-12);
    record("normalError", worst);
    // interpolate() of a linear field (x) gives the pixel centre's x.
    const MapFrame f = makeMapFrame(plane, viewOptions("+z", 0.05));
    const PixelHits hits = rasterize(plane, f);
    ASSERT_EQ(hits.covered, std::size_t(f.width) * std::size_t(f.height));
    std::vector<float> xs;
    for (const Vec3& p : plane.points) xs.push_back(float(p.x));
    double err = 0;
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x)
            err = std::max(err, std::abs(double(hits.interpolate(plane, xs, hits.index(x, y))) - (centreU(f, x) + f.origin.x)));
    EXPECT_LE(err, 1e-5);
    record("interpolateError", err);
}

} // namespace

// A closed mesh with a tiny hole keeps the closed-mesh side rule (the vector area of the hole
// is far below the projected area), and square objects get u along x, not along noise.
TEST(BestFit, ClosedWithTinyHoleAndSquareObjects)
{
    samples::HeightFieldOptions slab;
    slab.kind = samples::HeightFieldKind::Tablet;
    slab.width = 20;
    slab.height = 12;
    slab.spacing = 0.5;
    slab.closed = true;
    slab.thickness = 2;
    TriMesh box = samples::makeHeightField(slab);
    MapFrameOptions o;
    o.longerSidePixels = 64;
    const MapFrame closed = makeMapFrame(box, o);
    box.triangles.pop_back();  // a hole of one triangle
    const MapFrame holed = makeMapFrame(box, o);
    EXPECT_GT(dot(holed.normal, closed.normal), 0.999);  // the same side, not the other
    // A square plane (equal in-plane extents): u is +x whatever the jitter of the lattice.
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        const TriMesh plane = flatPatch(20, 20, 0.5, seed);
        const MapFrame f = makeMapFrame(plane, o);
        expectVecNear(f.axisU, Vec3(1, 0, 0), 1e-9, "square plane u");
    }
}
