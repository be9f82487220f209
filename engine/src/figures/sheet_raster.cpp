#include <msii/figures/sheet_raster.h>

#include <msii/core/errors.h>

#include "../featuremap/raster_bands.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace msii {
namespace {

/// A pixel's interpolated vertex normal (not normalised).
Vec3 normalAt(const TriMesh& mesh, const std::vector<Vec3>& normals, const PixelHits& hits, std::size_t k)
{
    const Triangle& tri = mesh.triangles[hits.triangle[k]];
    const double w1 = hits.b1[k], w2 = hits.b2[k], w0 = 1.0 - w1 - w2;
    return normals[tri[0]] * w0 + normals[tri[1]] * w1 + normals[tri[2]] * w2;
}

/// Facing the viewer: the normal within 75° of the view's direction.
constexpr double kFacingCosine = 0.26;

/// splitmix64's finaliser: a vertex's random 64-bit name.
std::uint64_t hashOf(std::uint64_t z)
{
    z += 0x9e3779b97f4a7c15ULL;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/// The triangles a view needs to draw. A closed surface whose faces agree in orientation
/// hides the faces that turn away from the viewer, in every view: only those facing it
/// (outward, positive volume) or away (inward) are drawn. Any other surface draws all: an open
/// scan seen from behind, a scan with flipped faces. Agreement is checked per vertex: over
/// its triangles, the names of the corners after it less those before it sum to zero when
/// every edge is met once each way (a border or a flipped face leaves a sum, but for a chance
/// of 2⁻⁶⁴).
RasterFaces facesToDraw(const TriMesh& mesh, const SheetOrientation& orientation)
{
    if (!orientation.closed) return RasterFaces::Both;
    std::vector<std::uint64_t> star(mesh.numVertices(), 0);
    double volume = 0;
    for (const Triangle& t : mesh.triangles) {
        const std::uint64_t h0 = hashOf(t[0]), h1 = hashOf(t[1]), h2 = hashOf(t[2]);
        star[t[0]] += h1 - h2, star[t[1]] += h2 - h0, star[t[2]] += h0 - h1;
        const Vec3& c = orientation.centre;
        volume += dot(mesh.points[t[0]] - c, cross(mesh.points[t[1]] - c, mesh.points[t[2]] - c));
    }
    for (const std::uint64_t sum : star)
        if (sum != 0) return RasterFaces::Both;
    return volume > 0 ? RasterFaces::Towards : RasterFaces::Away;
}

/// A view's axes as the object's (0 right, 1 up, 2 front) and their signs.
struct ViewAxes {
    std::size_t u, v, n;
    double us, vs, ns;
};

/// Which of the object's axes @p axis (right, up, front) each of the view's is, and its sign
/// (the layout builds the views' axes from them, so they match exactly).
ViewAxes viewAxes(const SheetViewBox& box, const std::array<Vec3, 3>& axis)
{
    ViewAxes a{};
    const auto find = [&](const Vec3& w, std::size_t& index, double& sign) {
        for (std::size_t k = 0; k < 3; ++k) {
            if (w == axis[k] || w == -axis[k]) {
                index = k, sign = w == axis[k] ? 1.0 : -1.0;
                return;
            }
        }
        throw InvalidInputError("a view's axes are not the object's right, up and front");
    };
    find(box.frame.axisU, a.u, a.us);
    find(box.frame.axisV, a.v, a.vs);
    find(box.frame.normal, a.n, a.ns);
    return a;
}

}  // namespace

ViewHits rasterizeViews(const TriMesh& mesh, const FatCrossLayout& layout, RunContext* progress)
{
    using namespace raster;
    const RasterFaces faces = facesToDraw(mesh, layout.orientation);
    // Each vertex along right, up and front from the centre: every view's coordinates are
    // these, signed and shifted, as its frame's toMap gives them (featuremap/map_frame.h).
    const SheetOrientation& o = layout.orientation;
    const std::array<Vec3, 3> axis = {o.right(), o.up, o.front};
    std::vector<std::array<double, 3>> along(mesh.numVertices());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, along.size()), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 d = mesh.points[i] - o.centre;
            along[i] = {dot(d, axis[0]), dot(d, axis[1]), dot(d, axis[2])};
        }
    });
    std::array<ViewAxes, kSheetViews> va;
    std::array<int, kSheetViews> numBands;
    std::array<double, kSheetViews> left, top;  // minU and maxV in pixels
    const double perPixel = 1.0 / layout.pixelSize;
    for (std::size_t v = 0; v < kSheetViews; ++v) {
        const MapFrame& f = layout.views[v].frame;
        va[v] = viewAxes(layout.views[v], axis);
        numBands[v] = (f.height + kBandRows - 1) / kBandRows;
        left[v] = f.minU * perPixel, top[v] = f.maxV * perPixel;
    }
    // The band lists of the six views in one pass over the triangles: each triangle's extent
    // along the three axes gives its box in every view.
    const std::array<Bands, kSheetViews> bands = listBands(mesh.numTriangles(), numBands, [&](std::size_t t) {
        const Triangle& tri = mesh.triangles[t];
        const std::array<double, 3>&a = along[tri[0]], &b = along[tri[1]], &c = along[tri[2]];
        std::array<double, 3> lo, hi, normal;
        for (std::size_t k = 0; k < 3; ++k) lo[k] = std::min({a[k], b[k], c[k]}), hi[k] = std::max({a[k], b[k], c[k]});
        for (std::size_t k = 0; k < 3; ++k) {
            const std::size_t i = (k + 1) % 3, j = (k + 2) % 3;
            normal[k] = (b[i] - a[i]) * (c[j] - a[j]) - (b[j] - a[j]) * (c[i] - a[i]);
        }
        std::array<BandRange, kSheetViews> ranges;
        for (std::size_t v = 0; v < kSheetViews; ++v) {
            const ViewAxes& x = va[v];
            const double facing = x.ns * normal[x.n];
            if (faces != RasterFaces::Both && !(faces == RasterFaces::Towards ? facing > 0 : facing < 0)) {
                ranges[v] = kNoBands;
                continue;
            }
            const double u0 = x.us > 0 ? lo[x.u] : -hi[x.u], u1 = x.us > 0 ? hi[x.u] : -lo[x.u];
            const double v0 = x.vs > 0 ? lo[x.v] : -hi[x.v], v1 = x.vs > 0 ? hi[x.v] : -lo[x.v];
            const MapFrame& f = layout.views[v].frame;
            ranges[v] = bandsOfWiderBox(u0 * perPixel - left[v], u1 * perPixel - left[v], top[v] - v1 * perPixel,
                                        top[v] - v0 * perPixel, f.width, f.height);
        }
        return ranges;
    });
    ViewHits views;
    if (progress) progress->start("rasterising the views", std::size_t(kSheetViews));
    std::vector<Projected> p(mesh.numVertices());
    for (std::size_t v = 0; v < kSheetViews; ++v) {
        const ViewAxes& x = va[v];
        const MapFrame& f = layout.views[v].frame;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, p.size()), [&](const auto& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const std::array<double, 3>& c = along[i];
                p[i] = {f.pixelX(x.us * c[x.u]), f.pixelY(x.vs * c[x.v]), x.ns * c[x.n]};
            }
        });
        views[v] = emptyHits(f.width, f.height);
        drawBands(mesh, p, bands[v], views[v], nullptr);
        if (progress) progress->advance();
    }
    if (progress) progress->end();
    return views;
}

SheetSides sheetSides(const TriMesh& mesh, const std::vector<Vec3>& normals, const FatCrossLayout& layout,
                      const ViewHits& views)
{
    if (normals.size() != mesh.numVertices()) throw InvalidInputError("the vertex normals do not match the mesh");
    SheetSides sides;
    sides.closed = layout.orientation.closed;
    if (sides.closed) return sides;  // every side is there to see
    for (std::size_t v = 0; v < kSheetViews; ++v) {
        const PixelHits& hits = views[v];
        const Vec3& towards = layout.views[v].frame.normal;
        std::size_t covered = 0, facing = 0;
        for (std::size_t k = 0; k < hits.triangle.size(); ++k) {
            if (hits.triangle[k] == PixelHits::kNone) continue;
            ++covered;
            const Vec3 n = normalAt(mesh, normals, hits, k);
            facing += dot(n, towards) >= kFacingCosine * norm(n);
        }
        sides.facingShare[v] = covered > 0 ? double(facing) / double(covered) : 0.0;
        sides.scanned[v] = covered > 0 && 2 * facing >= covered;
    }
    return sides;
}

void markScanned(FatCrossLayout& layout, const SheetSides& sides)
{
    for (std::size_t k = 0; k < kSheetViews; ++k) layout.views[k].scanned = sides.scanned[k];
}

SheetPixels composeSheet(const FatCrossLayout& layout, const ViewHits& views)
{
    SheetPixels sheet;
    PixelHits& s = sheet.hits;
    s.width = layout.width, s.height = layout.height;
    const std::size_t n = std::size_t(s.width) * std::size_t(s.height);
    s.triangle.assign(n, PixelHits::kNone);
    s.b1.assign(n, 0.0f);
    s.b2.assign(n, 0.0f);
    s.depth.assign(n, std::numeric_limits<float>::quiet_NaN());
    sheet.view.assign(n, -1);
    for (std::size_t k = 0; k < kSheetViews; ++k) {
        const SheetViewBox& box = layout.views[k];
        const PixelHits& view = views[k];
        if (view.width != box.frame.width || view.height != box.frame.height)
            throw InvalidInputError("a view's pixels do not fit its box on the sheet");
        for (int y = 0; y < view.height; ++y) {
            const std::size_t from = view.index(0, y), to = s.index(box.x0, box.y0 + y);
            const auto w = std::ptrdiff_t(view.width), f = std::ptrdiff_t(from), t = std::ptrdiff_t(to);
            std::fill_n(sheet.view.begin() + t, w, std::int8_t(k));
            if (!box.scanned) continue;
            std::copy_n(view.triangle.begin() + f, w, s.triangle.begin() + t);
            std::copy_n(view.b1.begin() + f, w, s.b1.begin() + t);
            std::copy_n(view.b2.begin() + f, w, s.b2.begin() + t);
            std::copy_n(view.depth.begin() + f, w, s.depth.begin() + t);
        }
        if (box.scanned) s.covered += view.covered;
    }
    return sheet;
}

std::array<std::vector<float>, 3> sheetNormals(const TriMesh& mesh, const std::vector<Vec3>& normals,
                                               const FatCrossLayout& layout, const SheetPixels& pixels)
{
    const PixelHits& hits = pixels.hits;
    const std::size_t n = hits.triangle.size();
    std::array<std::vector<float>, 3> out;
    for (auto& c : out) c.assign(n, std::numeric_limits<float>::quiet_NaN());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            if (hits.triangle[k] == PixelHits::kNone) continue;
            const Vec3 normal = normalAt(mesh, normals, hits, k);
            const MapFrame& f = layout.views[std::size_t(pixels.view[k])].frame;
            out[0][k] = float(dot(normal, f.axisU));
            out[1][k] = float(dot(normal, f.axisV));
            out[2][k] = float(dot(normal, f.normal));
        }
    });
    return out;
}

}  // namespace msii
