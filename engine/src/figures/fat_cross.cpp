#include <msii/figures/fat_cross.h>

#include <msii/core/errors.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace msii {
namespace {

/// A view's axes in terms of the object's: right on the picture (u), up on it
/// (v) and towards its viewer (n), each one of ±right, ±up, ±front (index 0, 1,
/// 2 and a sign).
struct ViewAxes {
    int u, us, v, vs, n, ns;
};
// Folded out from the obverse: the top edge shows its edge with the obverse at
// its bottom, the bottom edge at its top, the left edge at its right, the right
// edge at its left; the reverse is turned about the horizontal axis (right
// stays right, up becomes down).
constexpr std::array<ViewAxes, kSheetViews> kViewAxes = {{
    {0, +1, 1, +1, 2, +1},  // obverse: right, up, front
    {0, +1, 1, -1, 2, -1},  // reverse: right, -up, -front
    {0, +1, 2, -1, 1, +1},  // top: right, -front, up
    {0, +1, 2, +1, 1, -1},  // bottom: right, front, -up
    {2, +1, 1, +1, 0, -1},  // left: front, up, -right
    {2, -1, 1, +1, 0, +1},  // right: -front, up, right
}};

/// The object's extent along right, up and front, from its centroid.
struct Extents {
    Vec3 centroid;
    std::array<Vec3, 3> axis;  ///< right, up, front
    std::array<double, 3> lo{}, hi{};
    double size(int a) const { return hi[std::size_t(a)] - lo[std::size_t(a)]; }
};

Extents extentsOf(const TriMesh& mesh, const SheetOrientation& o, const Vec3& centroid)
{
    Extents e;
    e.centroid = centroid;
    e.axis = {o.right(), o.up, o.front};
    e.lo.fill(std::numeric_limits<double>::max());
    e.hi.fill(-std::numeric_limits<double>::max());
    std::vector<char> used(mesh.numVertices(), 0);
    for (const Triangle& t : mesh.triangles)
        for (std::uint32_t i : t) used[i] = 1;
    for (std::size_t i = 0; i < mesh.numVertices(); ++i) {
        if (!used[i]) continue;
        const Vec3 d = mesh.points[i] - centroid;
        for (std::size_t a = 0; a < 3; ++a) {
            const double c = dot(d, e.axis[a]);
            e.lo[a] = std::min(e.lo[a], c), e.hi[a] = std::max(e.hi[a], c);
        }
    }
    return e;
}

int pixelsFor(double extent, double pixelSize)
{
    return std::max(1, int(std::ceil(extent / pixelSize - 1e-9)));
}

/// Where the views go for one pixel size: boxes, captions and the sheet's size.
struct Placement {
    std::array<int, kSheetViews> x0{}, y0{}, w{}, h{}, captionX{}, captionY{};
    int width = 0, height = 0;
};

Placement place(const Extents& e, double ps, const FatCrossOptions& o)
{
    const int W = pixelsFor(e.size(0), ps), H = pixelsFor(e.size(1), ps), D = pixelsFor(e.size(2), ps);
    const int gap = std::max(2, int(std::lround(o.gap * std::max(W, H))));
    const auto cw = [&](SheetView v) { return o.captionHeight > 0 ? o.captionWidth[std::size_t(v)] : 0; };
    const auto has = [&](SheetView v) { return cw(v) > 0; };
    const int pad = std::max(2, o.captionHeight / 4), band = o.captionHeight + pad;
    const int colL = std::max(D, cw(SheetView::Left)), colR = std::max(D, cw(SheetView::Right));
    const int colC =
        std::max({W, cw(SheetView::Obverse), cw(SheetView::Reverse), cw(SheetView::Top), cw(SheetView::Bottom)});
    const int cx = colL + gap, rx = cx + colC + gap;
    const int capTop = has(SheetView::Top) ? band : 0;
    const int capMid = has(SheetView::Left) || has(SheetView::Obverse) || has(SheetView::Right) ? band : 0;
    const int capBottom = has(SheetView::Bottom) ? band : 0, capReverse = has(SheetView::Reverse) ? band : 0;
    const int yM = capTop + D + gap, yB = yM + H + capMid + gap, yR = yB + D + capBottom + gap;
    Placement p;
    const auto put = [&](SheetView v, int x, int y, int w, int h, int captionX, int captionY) {
        const std::size_t k = std::size_t(v);
        p.x0[k] = x, p.y0[k] = y, p.w[k] = w, p.h[k] = h, p.captionX[k] = captionX, p.captionY[k] = captionY;
    };
    const int centre = cx + (colC - W) / 2, below = pad / 2;
    put(SheetView::Top, centre, capTop, W, D, cx + colC / 2, below);
    put(SheetView::Left, colL - D, yM, D, H, colL / 2, yM + H + below);
    put(SheetView::Obverse, centre, yM, W, H, cx + colC / 2, yM + H + below);
    put(SheetView::Right, rx, yM, D, H, rx + colR / 2, yM + H + below);
    put(SheetView::Bottom, centre, yB, W, D, cx + colC / 2, yB + D + below);
    put(SheetView::Reverse, centre, yR, W, H, cx + colC / 2, yR + H + below);
    p.width = rx + colR;
    p.height = yR + H + capReverse;
    return p;
}

/// The pixel size the options ask for; with a longer side in pixels, the
/// largest whose sheet (views, gaps and captions, which do not scale) fits in
/// it.
double pixelSizeFor(const Extents& e, const FatCrossOptions& o)
{
    const int given = (o.longerSidePixels != 0) + (o.pixelSize != 0) + (o.dpi != 0);
    if (given != 1) throw InvalidInputError("give the scale exactly once: as pixels, as a pixel size or as DPI");
    if (o.longerSidePixels < 0 || !(o.pixelSize >= 0) || !(o.dpi >= 0) || !std::isfinite(o.pixelSize) ||
        !std::isfinite(o.dpi))
        throw InvalidInputError("the scale must be positive");
    if (o.pixelSize > 0) return o.pixelSize;
    if (o.dpi > 0) return 25.4 / o.dpi;
    const double n = o.longerSidePixels;
    // From below (the views alone), up until the gaps, captions and whole pixels
    // fit.
    double ps = std::max(2 * e.size(2) + 2 * e.size(1), 2 * e.size(2) + e.size(0)) / n;
    for (int round = 0; round < 40; ++round) {
        const Placement p = place(e, ps, o);
        const int longer = std::max(p.width, p.height);
        if (longer <= o.longerSidePixels) break;
        ps *= std::max(1.0 + 1e-6, double(longer) / n);
    }
    return ps;
}

}  // namespace

const char* sheetViewName(SheetView view)
{
    static const char* const names[] = {"obverse", "reverse", "top", "bottom", "left", "right"};
    return names[int(view)];
}

const char* sheetViewLabel(SheetView view)
{
    static const char* const labels[] = {"obv.", "rev.", "t.e.", "b.e.", "l.e.", "r.e."};
    return labels[int(view)];
}

ToPixel SheetViewBox::toPixel() const
{
    const MapFrame& f = frame;
    const double ps = f.pixelSize;
    const Vec3 &u = f.axisU, &v = f.axisV, &n = f.normal, &o = f.origin;
    return {{{u.x / ps, u.y / ps, u.z / ps, x0 - (dot(u, o) + f.minU) / ps},
             {-v.x / ps, -v.y / ps, -v.z / ps, y0 + (f.maxV + dot(v, o)) / ps},
             {n.x, n.y, n.z, -dot(n, o)}}};
}

Vec3 SheetViewBox::project(const Vec3& p) const
{
    const ToPixel a = toPixel();
    Vec3 r;
    for (int i = 0; i < 3; ++i) {
        const auto& row = a[std::size_t(i)];
        r[i] = row[0] * p.x + row[1] * p.y + row[2] * p.z + row[3];
    }
    return r;
}

FatCrossLayout layoutFatCross(const TriMesh& mesh, const SheetOrientation& orientation, const FatCrossOptions& options)
{
    if (mesh.empty()) throw InvalidInputError("the mesh is empty: nothing to lay out");
    const Extents e = extentsOf(mesh, orientation, orientation.centre);
    FatCrossLayout layout;
    layout.orientation = orientation;
    layout.pixelSize = pixelSizeFor(e, options);
    layout.size = Vec3(e.size(0), e.size(1), e.size(2));
    const Placement p = place(e, layout.pixelSize, options);
    if (p.width > options.maxSidePixels || p.height > options.maxSidePixels) {
        std::ostringstream s;
        s << "the sheet would be " << p.width << " x " << p.height << " pixels; the largest allowed side is "
          << options.maxSidePixels << " (choose a larger pixel size, a lower DPI or fewer pixels)";
        throw InvalidInputError(s.str());
    }
    layout.width = p.width, layout.height = p.height;
    layout.captionHeight = options.captionHeight;
    for (std::size_t k = 0; k < kSheetViews; ++k) {
        const ViewAxes& a = kViewAxes[k];
        SheetViewBox& box = layout.views[k];
        box.view = SheetView(k);
        box.x0 = p.x0[k], box.y0 = p.y0[k];
        box.captionX = p.captionX[k], box.captionY = p.captionY[k];
        MapFrame& f = box.frame;
        f.view = MapView::Direction;
        f.origin = e.centroid;
        f.axisU = e.axis[std::size_t(a.u)] * double(a.us);
        f.axisV = e.axis[std::size_t(a.v)] * double(a.vs);
        f.normal = e.axis[std::size_t(a.n)] * double(a.ns);
        f.pixelSize = layout.pixelSize;
        f.width = p.w[k], f.height = p.h[k];
        // Centred in its box as makeMapFrame centres a map: the boxes of views that
        // share an axis then line up (the obverse's and the top edge's columns, for
        // example).
        const auto mid = [&](int axis, int sign) {
            return 0.5 * sign * (e.lo[std::size_t(axis)] + e.hi[std::size_t(axis)]);
        };
        f.minU = mid(a.u, a.us) - 0.5 * f.width * f.pixelSize;
        f.maxV = mid(a.v, a.vs) + 0.5 * f.height * f.pixelSize;
    }
    return layout;
}

}  // namespace msii
