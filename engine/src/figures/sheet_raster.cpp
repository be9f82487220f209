#include <msii/figures/sheet_raster.h>

#include <msii/core/errors.h>
#include <msii/mesh/principal_axes.h>

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

}  // namespace

ViewHits rasterizeViews(const TriMesh& mesh, const FatCrossLayout& layout, RunContext* progress)
{
    ViewHits views;
    if (progress) progress->start("rasterising the views", std::size_t(kSheetViews));
    for (std::size_t k = 0; k < kSheetViews; ++k) {
        views[k] = rasterize(mesh, layout.views[k].frame);
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
    const SurfaceMoments m = surfaceMoments(mesh, false);
    sides.closed = !(norm(m.vectorArea) > 0.01 * m.area);
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
        if (!sides.closed) sides.scanned[v] = covered > 0 && 2 * facing >= covered;
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
