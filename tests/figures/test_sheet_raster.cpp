/// @file test_sheet_raster.cpp
/// @brief Tests of figures/sheet_raster.h: each view sees its own side (every
/// mark of the generated tablet lands in its side's view, within its box, and
/// the surface seen there is the mark's floor, its depth below the rim: hidden
/// surfaces removed); the sides a surface shows (a closed tablet all six, a
/// one-sided scan one, the one its normals face); the sheet's pixels and views
/// put together; normals in each view's frame.

#include <msii/core/errors.h>
#include <msii/figures/sheet_raster.h>
#include <msii/mesh/vertex_normals.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace msii;
using namespace msii::samples;

namespace {

struct Sheet {
    FatCrossLayout layout;
    ViewHits views;
    SheetSides sides;
    SheetPixels pixels;
};

Sheet sheetOf(const TriMesh& mesh, const SheetOrientationOptions& orientation, double pixelSize)
{
    Sheet s;
    FatCrossOptions o;
    o.pixelSize = pixelSize;
    s.layout = layoutFatCross(mesh, orientSheet(mesh, orientation), o);
    s.views = rasterizeViews(mesh, s.layout);
    s.sides = sheetSides(mesh, vertexNormals(mesh), s.layout, s.views);
    markScanned(s.layout, s.sides);
    s.pixels = composeSheet(s.layout, s.views);
    return s;
}

SheetOrientationOptions straight()
{
    SheetOrientationOptions given;
    given.front = Vec3(0, 0, 1);
    given.up = Vec3(0, 1, 0);
    return given;
}

/// The view of each tablet side under the straight orientation (sides and views
/// share their order: obverse, reverse, top, bottom, left, right).
SheetView viewOf(TabletSide side)
{
    return SheetView(int(side));
}

}  // namespace

TEST(SheetRaster, EveryMarkIsSeenInItsSidesViewAtItsFloor)
{
    RoundedTabletOptions o;
    o.spacing = 0.25;
    o.roughness = 0.003;
    const RoundedTablet t = makeRoundedTablet(o);
    const Sheet s = sheetOf(t.mesh, straight(), 0.05);
    EXPECT_TRUE(s.sides.closed);
    std::size_t checked = 0;
    for (const TabletMark& m : t.marks) {
        SCOPED_TRACE(tabletSideName(m.side));
        const SheetViewBox& b = s.layout.views[std::size_t(viewOf(m.side))];
        const Vec3 q = b.project(m.centre);
        ASSERT_GE(q.x, b.x0);
        ASSERT_LT(q.x, b.x0 + b.frame.width);
        ASSERT_GE(q.y, b.y0);
        ASSERT_LT(q.y, b.y0 + b.frame.height);
        const std::size_t k = s.pixels.hits.index(int(q.x), int(q.y));
        ASSERT_NE(s.pixels.hits.triangle[k], PixelHits::kNone);
        EXPECT_EQ(s.pixels.view[k], std::int8_t(b.view));
        // The surface seen is the mark's floor: its depth below the rim (to within
        // the lattice's and the noise's share), not another side of the tablet.
        EXPECT_NEAR(q.z - s.pixels.hits.depth[k], m.depth, 0.08 * m.depth + o.roughness);
        ++checked;
    }
    EXPECT_EQ(checked, 21u);
}

TEST(SheetRaster, AClosedTabletShowsAllSidesAndAOneSidedScanOne)
{
    RoundedTabletOptions o;
    o.spacing = 0.4;
    const Sheet closed = sheetOf(makeRoundedTablet(o).mesh, {}, 0.2);
    for (bool scanned : closed.sides.scanned) EXPECT_TRUE(scanned);

    HeightFieldOptions h;  // a tablet's obverse scanned alone, facing +z, with its wedges
    h.width = 16;
    h.height = 12;
    h.spacing = 0.05;
    h.roughness = 0.004;
    TriMesh scan = makeHeightField(h);
    Sheet open = sheetOf(scan, {}, 0.1);
    EXPECT_FALSE(open.sides.closed);
    for (int k = 0; k < kSheetViews; ++k)
        EXPECT_EQ(open.sides.scanned[std::size_t(k)], k == int(SheetView::Obverse)) << k;
    // Blank views see nothing on the sheet.
    for (std::size_t k = 0; k < open.pixels.hits.triangle.size(); ++k)
        if (open.pixels.hits.triangle[k] != PixelHits::kNone) {
            ASSERT_EQ(open.pixels.view[k], std::int8_t(SheetView::Obverse));
        }
    // Told that its front is the other way, the scan is the reverse.
    SheetOrientationOptions back;
    back.front = Vec3(0, 0, -1);
    open = sheetOf(scan, back, 0.1);
    for (int k = 0; k < kSheetViews; ++k)
        EXPECT_EQ(open.sides.scanned[std::size_t(k)], k == int(SheetView::Reverse)) << k;
}

TEST(SheetRaster, NormalsAreInEachViewsFrame)
{
    RoundedTabletOptions o;
    o.spacing = 0.4;
    o.marks = {0, 0, 0, 0, 0, 0};
    const RoundedTablet t = makeRoundedTablet(o);
    const Sheet s = sheetOf(t.mesh, straight(), 0.2);
    const std::array<std::vector<float>, 3> n = sheetNormals(t.mesh, vertexNormals(t.mesh), s.layout, s.pixels);
    // At each view's centre the surface faces its viewer: z up in the frame.
    for (const SheetViewBox& b : s.layout.views) {
        const std::size_t k = s.pixels.hits.index(b.x0 + b.frame.width / 2, b.y0 + b.frame.height / 2);
        const double len = std::sqrt(n[0][k] * n[0][k] + n[1][k] * n[1][k] + n[2][k] * n[2][k]);
        EXPECT_GT(n[2][k] / len, 0.97) << sheetViewName(b.view);
    }
    // A box's outside (gaps) has no view and no normal.
    const std::size_t gap = s.pixels.hits.index(0, 0);
    EXPECT_EQ(s.pixels.view[gap], -1);
    EXPECT_TRUE(std::isnan(n[0][gap]));
}

TEST(SheetRaster, ViewsMustFitTheirBoxes)
{
    RoundedTabletOptions o;
    o.spacing = 0.5;
    const RoundedTablet t = makeRoundedTablet(o);
    Sheet s = sheetOf(t.mesh, straight(), 0.2);
    s.views[0] = PixelHits{};
    EXPECT_THROW(composeSheet(s.layout, s.views), InvalidInputError);
    EXPECT_THROW(sheetSides(t.mesh, {}, s.layout, s.views), InvalidInputError);
}

TEST(SheetRaster, FacesTurnedWrongStillShow)
{
    // A closed surface draws only the faces turned towards each view, when its faces agree;
    // flipped faces or a surface turned inside out must not leave holes.
    RoundedTabletOptions o;
    o.spacing = 0.5;
    o.marks = {0, 0, 0, 0, 0, 0};
    const TriMesh outward = makeRoundedTablet(o).mesh;
    const Sheet reference = sheetOf(outward, straight(), 0.25);
    const auto covered = [](const Sheet& s) {
        std::vector<bool> c(s.pixels.hits.triangle.size());
        for (std::size_t k = 0; k < c.size(); ++k) c[k] = s.pixels.hits.triangle[k] != PixelHits::kNone;
        return c;
    };
    TriMesh inward = outward;
    for (Triangle& t : inward.triangles) std::swap(t[1], t[2]);
    EXPECT_EQ(covered(sheetOf(inward, straight(), 0.25)), covered(reference));
    // One face flipped in the middle of the obverse (and a few more elsewhere).
    TriMesh flipped = outward;
    const SheetViewBox& obverse = reference.layout.views[std::size_t(SheetView::Obverse)];
    const std::size_t centre =
        reference.pixels.hits.index(obverse.x0 + obverse.frame.width / 2, obverse.y0 + obverse.frame.height / 2);
    const std::uint32_t seen = reference.pixels.hits.triangle[centre];
    for (std::uint32_t t : {seen, 7u, 1000u, 20000u}) std::swap(flipped.triangles[t][1], flipped.triangles[t][2]);
    const Sheet s = sheetOf(flipped, straight(), 0.25);
    EXPECT_EQ(s.pixels.hits.triangle[centre], seen);
    EXPECT_EQ(covered(s), covered(reference));
}
