/// @file test_fat_cross.cpp
/// @brief Tests of figures/fat_cross.h: the views' boxes have the object's
/// extents at the sheet's scale and sit where cuneiformists put them (the edges
/// folded out around the obverse, the reverse below the bottom edge), apart;
/// each view's matrix sends the object's extreme points to its box's edges,
/// consistently with its frame; the scale given as DPI, pixel size or the
/// sheet's longer side; captions widen the columns.

#include <msii/core/errors.h>
#include <msii/figures/fat_cross.h>
#include <msii/samples/generators.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

using namespace msii;
using namespace msii::samples;

namespace {

RoundedTablet tablet()
{
    RoundedTabletOptions o;
    o.spacing = 0.4;
    return makeRoundedTablet(o);
}

SheetOrientation straight(const TriMesh& mesh)
{
    SheetOrientationOptions given;
    given.front = Vec3(0, 0, 1);
    given.up = Vec3(0, 1, 0);
    return orientSheet(mesh, given);
}

const SheetViewBox& box(const FatCrossLayout& l, SheetView v)
{
    return l.views[std::size_t(v)];
}
int right(const SheetViewBox& b)
{
    return b.x0 + b.frame.width;
}
int bottom(const SheetViewBox& b)
{
    return b.y0 + b.frame.height;
}

}  // namespace

TEST(FatCross, ViewsHaveTheObjectsExtentsAndSitWhereTheyBelong)
{
    const RoundedTablet t = tablet();
    FatCrossOptions o;
    o.dpi = 300;
    const FatCrossLayout l = layoutFatCross(t.mesh, straight(t.mesh), o);
    EXPECT_DOUBLE_EQ(l.pixelSize, 25.4 / 300);
    // The extents along right (x), up (y) and front (z): 24 × 32 × (10 + the
    // bulges).
    EXPECT_NEAR(l.size.x, 24.0, 0.05);
    EXPECT_NEAR(l.size.y, 32.0, 0.05);
    EXPECT_NEAR(l.size.z, 10.0 + 0.1 + 1.5, 0.05);
    const int W = int(std::ceil(l.size.x / l.pixelSize)), H = int(std::ceil(l.size.y / l.pixelSize)),
              D = int(std::ceil(l.size.z / l.pixelSize));
    const SheetViewBox &obv = box(l, SheetView::Obverse), &rev = box(l, SheetView::Reverse),
                       &top = box(l, SheetView::Top), &bot = box(l, SheetView::Bottom), &lft = box(l, SheetView::Left),
                       &rgt = box(l, SheetView::Right);
    for (const SheetViewBox* b : {&obv, &rev})
        EXPECT_EQ(std::make_pair(b->frame.width, b->frame.height), std::make_pair(W, H));
    for (const SheetViewBox* b : {&top, &bot})
        EXPECT_EQ(std::make_pair(b->frame.width, b->frame.height), std::make_pair(W, D));
    for (const SheetViewBox* b : {&lft, &rgt})
        EXPECT_EQ(std::make_pair(b->frame.width, b->frame.height), std::make_pair(D, H));
    // The cross: top above the obverse, bottom below it, reverse below the
    // bottom, left and right beside it, a small gap apart, the columns and rows
    // lined up.
    const int gap = obv.y0 - bottom(top);
    EXPECT_GE(gap, 2);
    EXPECT_LT(gap, 0.1 * H);
    EXPECT_EQ(top.x0, obv.x0);
    EXPECT_EQ(bot.x0, obv.x0);
    EXPECT_EQ(rev.x0, obv.x0);
    EXPECT_EQ(bot.y0 - bottom(obv), gap);
    EXPECT_EQ(rev.y0 - bottom(bot), gap);
    EXPECT_EQ(obv.x0 - right(lft), gap);
    EXPECT_EQ(rgt.x0 - right(obv), gap);
    EXPECT_EQ(lft.y0, obv.y0);
    EXPECT_EQ(rgt.y0, obv.y0);
    EXPECT_EQ(lft.x0, 0);
    EXPECT_EQ(top.y0, 0);
    EXPECT_EQ(l.width, right(rgt));
    EXPECT_EQ(l.height, bottom(rev));
}

TEST(FatCross, EachViewIsFoldedOutFromTheObverse)
{
    // Through each view's matrix, a point's column and row: the obverse sees x
    // right and y up; the top edge has the obverse's side (z high) at its bottom,
    // the bottom edge at its top; the left edge (seen from -x) has it at its
    // right, the right edge at its left; the reverse is turned about the
    // horizontal axis, x still right, y down.
    const RoundedTablet t = tablet();
    FatCrossOptions o;
    o.pixelSize = 0.1;
    const FatCrossLayout l = layoutFatCross(t.mesh, straight(t.mesh), o);
    const Vec3 c(0, 0, 0), dx(1, 0, 0), dy(0, 1, 0), dz(0, 0, 1);
    const auto moves = [&](SheetView v, const Vec3& d) { return box(l, v).project(c + d) - box(l, v).project(c); };
    EXPECT_GT(moves(SheetView::Obverse, dx).x, 0);
    EXPECT_LT(moves(SheetView::Obverse, dy).y, 0);
    EXPECT_GT(moves(SheetView::Obverse, dz).z, 0);  // depth towards the viewer
    EXPECT_GT(moves(SheetView::Top, dz).y, 0);
    EXPECT_GT(moves(SheetView::Top, dy).z, 0);
    EXPECT_LT(moves(SheetView::Bottom, dz).y, 0);
    EXPECT_GT(moves(SheetView::Left, dz).x, 0);
    EXPECT_LT(moves(SheetView::Right, dz).x, 0);
    EXPECT_GT(moves(SheetView::Reverse, dx).x, 0);
    EXPECT_GT(moves(SheetView::Reverse, dy).y, 0);
    EXPECT_LT(moves(SheetView::Reverse, dz).z, 0);
    // The matrix agrees with the frame: pixel centres at frame.pixelX/Y + the
    // box's corner.
    for (const SheetViewBox& b : l.views) {
        const Vec3 p(3.0, -7.0, 2.5), m = b.frame.toMap(p), q = b.project(p);
        EXPECT_NEAR(q.x, b.x0 + b.frame.pixelX(m.x), 1e-9);
        EXPECT_NEAR(q.y, b.y0 + b.frame.pixelY(m.y), 1e-9);
        EXPECT_NEAR(q.z, m.z, 1e-12);
    }
}

TEST(FatCross, TheObjectFillsEachBoxToItsEdges)
{
    const RoundedTablet t = tablet();
    FatCrossOptions o;
    o.dpi = 200;
    const FatCrossLayout l = layoutFatCross(t.mesh, straight(t.mesh), o);
    for (const SheetViewBox& b : l.views) {
        SCOPED_TRACE(sheetViewName(b.view));
        double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
        for (const Vec3& p : t.mesh.points) {
            const Vec3 q = b.project(p);
            x0 = std::min(x0, q.x), x1 = std::max(x1, q.x), y0 = std::min(y0, q.y), y1 = std::max(y1, q.y);
        }
        EXPECT_GE(x0, b.x0 - 1e-9);
        EXPECT_LE(x1, b.x0 + b.frame.width + 1e-9);
        EXPECT_GE(y0, b.y0 - 1e-9);
        EXPECT_LE(y1, b.y0 + b.frame.height + 1e-9);
        EXPECT_LT(b.frame.width - (x1 - x0),
                  1.0 + 1e-9);  // centred: less than a pixel to spare
        EXPECT_LT(b.frame.height - (y1 - y0), 1.0 + 1e-9);
    }
}

TEST(FatCross, TheScaleIsGivenOnce)
{
    const RoundedTablet t = tablet();
    for (const int n : {300, 1000, 2048}) {
        FatCrossOptions o;
        o.longerSidePixels = n;
        const FatCrossLayout l = layoutFatCross(t.mesh, straight(t.mesh), o);
        EXPECT_LE(std::max(l.width, l.height), n);
        EXPECT_GE(std::max(l.width, l.height), n - 3 - n / 200);
    }
    FatCrossOptions none;
    EXPECT_THROW(layoutFatCross(t.mesh, straight(t.mesh), none), InvalidInputError);
    FatCrossOptions two;
    two.dpi = 300, two.pixelSize = 0.1;
    EXPECT_THROW(layoutFatCross(t.mesh, straight(t.mesh), two), InvalidInputError);
    FatCrossOptions negative;
    negative.pixelSize = -0.1;
    EXPECT_THROW(layoutFatCross(t.mesh, straight(t.mesh), negative), InvalidInputError);
    FatCrossOptions huge;
    huge.pixelSize = 1e-4;
    EXPECT_THROW(layoutFatCross(t.mesh, straight(t.mesh), huge), InvalidInputError);
}

TEST(FatCross, CaptionsHaveRoomUnderTheirViews)
{
    const RoundedTablet t = tablet();
    FatCrossOptions o;
    o.pixelSize = 0.2;
    const FatCrossLayout plain = layoutFatCross(t.mesh, straight(t.mesh), o);
    o.captionHeight = 18;
    o.captionWidth = {40, 40, 40, 40, 300, 40};  // a long caption for the left edge
    const FatCrossLayout l = layoutFatCross(t.mesh, straight(t.mesh), o);
    const SheetViewBox &left = box(l, SheetView::Left), &obv = box(l, SheetView::Obverse),
                       &top = box(l, SheetView::Top);
    EXPECT_GE(left.captionX - 150, 0);  // the caption fits in its column
    EXPECT_EQ(obv.x0 - (left.x0 + left.frame.width),
              obv.y0 - (top.y0 + top.frame.height));  // still the gap
    EXPECT_GE(top.y0, 18);  // the top edge's caption above it
    EXPECT_GE(box(l, SheetView::Bottom).y0 - (obv.y0 + obv.frame.height), 18);
    EXPECT_GT(l.height, plain.height);
    EXPECT_EQ(l.captionHeight, 18);
}
