#include <msii/featuremap/rasterize.h>

#include "raster_bands.h"

#include <msii/mesh/vertex_normals.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace msii {

std::array<std::vector<float>, 3> vertexNormalsInFrame(const TriMesh& mesh, const MapFrame& frame)
{
    const std::vector<Vec3> n = vertexNormals(mesh);
    std::array<std::vector<float>, 3> out;
    for (auto& c : out) c.resize(n.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n.size()), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            out[0][i] = float(dot(n[i], frame.axisU));
            out[1][i] = float(dot(n[i], frame.axisV));
            out[2][i] = float(dot(n[i], frame.normal));
        }
    });
    return out;
}

std::vector<float> interpolateToPixels(const TriMesh& mesh, const PixelHits& hits, const std::vector<float>& perVertex)
{
    std::vector<float> out(hits.triangle.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.size()), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) out[k] = hits.interpolate(mesh, perVertex, k);
    });
    return out;
}

std::vector<float> coverageMask(const PixelHits& hits)
{
    std::vector<float> mask(hits.triangle.size());
    for (std::size_t k = 0; k < mask.size(); ++k) mask[k] = hits.triangle[k] != PixelHits::kNone ? 1.0f : 0.0f;
    return mask;
}

namespace raster {

PixelHits emptyHits(int width, int height)
{
    PixelHits hits;
    hits.width = width;
    hits.height = height;
    const std::size_t numPixels = std::size_t(width) * std::size_t(height);
    hits.triangle.assign(numPixels, PixelHits::kNone);
    hits.b1.assign(numPixels, 0.0f);
    hits.b2.assign(numPixels, 0.0f);
    hits.depth.assign(numPixels, std::numeric_limits<float>::quiet_NaN());
    return hits;
}

void drawBands(const TriMesh& mesh, const std::vector<Projected>& p, const Bands& bands, PixelHits& hits,
               RunContext* progress)
{
    if (progress) progress->start("rasterising", bands.start.size() - 1);
    tbb::parallel_for(tbb::blocked_range<int>(0, int(bands.start.size()) - 1), [&](const auto& range) {
        for (int band = range.begin(); band < range.end(); ++band) {
            const int rowLo = band * kBandRows, rowHi = std::min(hits.height, rowLo + kBandRows) - 1;
            // Triangles in index order, so that ties in height go to the lower index.
            for (std::size_t k = bands.start[std::size_t(band)]; k < bands.start[std::size_t(band) + 1]; ++k) {
                const std::uint32_t t = bands.triangles[k];
                const Triangle& tri = mesh.triangles[t];
                const Projected &a = p[tri[0]], &b = p[tri[1]], &c = p[tri[2]];
                // The pixel centres it may cover first: most triangles of a fine mesh cover none.
                const int y0 = std::max(rowLo, int(std::ceil(std::min({a.y, b.y, c.y}) - 0.5)));
                const int y1 = std::min(rowHi, int(std::floor(std::max({a.y, b.y, c.y}) - 0.5)));
                const int x0 = std::max(0, int(std::ceil(std::min({a.x, b.x, c.x}) - 0.5)));
                const int x1 = std::min(hits.width - 1, int(std::floor(std::max({a.x, b.x, c.x}) - 0.5)));
                if (y0 > y1 || x0 > x1) continue;
                const double area = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
                if (area == 0 || !std::isfinite(area)) continue;
                const double inv = 1.0 / area;
                // Edge functions from each edge's endpoints in a fixed order (lower vertex
                // index first), negated as needed: two triangles sharing an edge compute the
                // same number for it, so a pixel centre on the edge is never missed by both.
                // Edge k is the one opposite corner k; its set-up is per triangle.
                struct Edge {
                    double x, y, dx, dy, sign;
                };
                const auto setUp = [&](std::uint32_t i, std::uint32_t j) {
                    const bool forward = i < j;
                    const Projected& from = p[forward ? i : j];
                    const Projected& to = p[forward ? j : i];
                    return Edge{from.x, from.y, to.x - from.x, to.y - from.y, forward ? 1.0 : -1.0};
                };
                const Edge edges[3] = {setUp(tri[1], tri[2]), setUp(tri[2], tri[0]), setUp(tri[0], tri[1])};
                const auto edge = [](const Edge& e, double px, double py) {
                    return e.sign * (e.dx * (py - e.y) - e.dy * (px - e.x));
                };
                for (int y = y0; y <= y1; ++y) {
                    const double py = y + 0.5;
                    for (int x = x0; x <= x1; ++x) {
                        const double px = x + 0.5;
                        // Barycentric weights: each vertex's opposite edge over the whole.
                        const double w0 = edge(edges[0], px, py) * inv;
                        const double w1 = edge(edges[1], px, py) * inv;
                        const double w2 = edge(edges[2], px, py) * inv;
                        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
                        const double sum = w0 + w1 + w2;
                        const double h = (w0 * a.h + w1 * b.h + w2 * c.h) / sum;
                        const std::size_t i = hits.index(x, y);
                        if (hits.triangle[i] != PixelHits::kNone && !(h > hits.depth[i])) continue;
                        hits.triangle[i] = t;
                        hits.b1[i] = float(w1 / sum);
                        hits.b2[i] = float(w2 / sum);
                        hits.depth[i] = float(h);
                    }
                }
            }
            if (progress) progress->advance();
        }
    });
    if (progress) progress->end();
    for (std::uint32_t t : hits.triangle) hits.covered += t != PixelHits::kNone;
}

} // namespace raster

PixelHits rasterize(const TriMesh& mesh, const MapFrame& frame, RunContext* progress, RasterFaces faces)
{
    using namespace raster;
    PixelHits hits = emptyHits(frame.width, frame.height);
    std::vector<Projected> p(mesh.numVertices());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, p.size()), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 m = frame.toMap(mesh.points[i]);
            p[i] = {frame.pixelX(m.x), frame.pixelY(m.y), m.z};
        }
    });
    const std::array<int, 1> numBands{(frame.height + kBandRows - 1) / kBandRows};
    const std::array<Bands, 1> bands = listBands(mesh.numTriangles(), numBands, [&](std::size_t t) {
        const Triangle& tri = mesh.triangles[t];
        const Projected &a = p[tri[0]], &b = p[tri[1]], &c = p[tri[2]];
        if (!drawn(faces, (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y))) return std::array<BandRange, 1>{kNoBands};
        return std::array<BandRange, 1>{bandsOfBox(std::min({a.x, b.x, c.x}), std::max({a.x, b.x, c.x}),
                                                   std::min({a.y, b.y, c.y}), std::max({a.y, b.y, c.y}), frame.width,
                                                   frame.height)};
    });
    drawBands(mesh, p, bands[0], hits, progress);
    return hits;
}

} // namespace msii
