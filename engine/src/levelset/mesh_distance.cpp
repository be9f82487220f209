#include "mesh_distance.h"

#include <msii/mesh/mesh_stats.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace msii::detail {

MeshDistance::MeshDistance(const TriMesh& mesh) : mMesh(mesh)
{
    const std::size_t nv = mesh.numVertices(), nf = mesh.numTriangles();
    mFaceNormal.resize(nf);
    mBoundingSphere.resize(nf);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf), [&](const auto& r) {
        for (std::size_t f = r.begin(); f < r.end(); ++f) {
            const auto& t = mesh.triangles[f];
            mFaceNormal[f] = normalized(cross(mesh.points[t[1]] - mesh.points[t[0]],
                                              mesh.points[t[2]] - mesh.points[t[0]]));
            const Vec3 c = (mesh.points[t[0]] + mesh.points[t[1]] + mesh.points[t[2]]) / 3.0;
            double r2 = 0;
            for (auto v : t) r2 = std::max(r2, squaredNorm(mesh.points[v] - c));
            mBoundingSphere[f] = {c, std::sqrt(r2) * (1 + 1e-9)};
        }
    });
    mFirst.assign(nv + 1, 0);
    for (const auto& t : mesh.triangles)
        for (auto v : t) ++mFirst[v + 1];
    for (std::size_t v = 0; v < nv; ++v) mFirst[v + 1] += mFirst[v];
    mFaces.resize(mFirst[nv]);
    std::vector<std::uint32_t> fill(mFirst.begin(), mFirst.end() - 1);
    for (std::size_t f = 0; f < nf; ++f)
        for (auto v : mesh.triangles[f]) mFaces[fill[v]++] = std::uint32_t(f);
    // Border vertices: ends of edges with one incident face.
    mBorderVertex.assign(nv, 0);
    for (std::size_t f = 0; f < nf; ++f) {
        const auto& t = mesh.triangles[f];
        for (int k = 0; k < 3; ++k) {
            const auto u = t[k], v = t[(k + 1) % 3];
            int count = 0;
            for (auto i = mFirst[u]; i < mFirst[u + 1]; ++i) {
                const auto& s = mesh.triangles[mFaces[i]];
                count += (s[0] == v || s[1] == v || s[2] == v) ? 1 : 0;
            }
            if (count == 1) mBorderVertex[u] = mBorderVertex[v] = 1;
        }
    }
    // Angle-weighted vertex pseudo-normals (Baerentzen & Aanaes 2005).
    mVertexNormal.assign(nv, Vec3{});
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
        for (std::size_t v = r.begin(); v < r.end(); ++v) {
            Vec3 n{};
            for (auto i = mFirst[v]; i < mFirst[v + 1]; ++i) {
                const auto f = mFaces[i];
                const auto& t = mesh.triangles[f];
                const int k = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
                const Vec3 e1 = mesh.points[t[(k + 1) % 3]] - mesh.points[v];
                const Vec3 e2 = mesh.points[t[(k + 2) % 3]] - mesh.points[v];
                n += mFaceNormal[f] * std::atan2(norm(cross(e1, e2)), dot(e1, e2));
            }
            const double len = norm(n);
            mVertexNormal[v] = len > 0 ? n / len : n;  // only the direction is used
        }
    });
}

Vec3 MeshDistance::pseudoNormal(std::uint32_t f, int feature) const
{
    const auto& t = mMesh.triangles[f];
    const auto edgeNormal = [&](std::uint32_t u, std::uint32_t v) {
        Vec3 n = mFaceNormal[f];
        for (auto i = mFirst[u]; i < mFirst[u + 1]; ++i) {
            const auto g = mFaces[i];
            if (g == f) continue;
            const auto& s = mMesh.triangles[g];
            if (s[0] == v || s[1] == v || s[2] == v) n += mFaceNormal[g];
        }
        return n;
    };
    switch (feature) {
    case kVertexA: return mVertexNormal[t[0]];
    case kVertexB: return mVertexNormal[t[1]];
    case kVertexC: return mVertexNormal[t[2]];
    case kEdgeAB: return edgeNormal(t[0], t[1]);
    case kEdgeBC: return edgeNormal(t[1], t[2]);
    case kEdgeCA: return edgeNormal(t[2], t[0]);
    default: return mFaceNormal[f];
    }
}

MeshDistance::Closest MeshDistance::descend(const Vec3& x, std::uint32_t startVertex) const
{
    Closest best;
    best.squaredDistance = std::numeric_limits<double>::infinity();
    Vec3 closest;
    int feature = kFace;
    const auto tryFacesOf = [&](std::uint32_t v) {
        bool improved = false;
        for (auto i = mFirst[v]; i < mFirst[v + 1]; ++i) {
            const auto g = mFaces[i];
            const double d = faceDistance(x, g, closest, feature);
            if (d < best.squaredDistance) {
                best = Closest{d, closest, g, feature};
                improved = true;
            }
        }
        return improved;
    };
    // Look at every triangle sharing a vertex with the current closest one; the triangles
    // of a vertex are looked at once (a few vertices are remembered).
    std::array<std::uint32_t, 32> expanded;
    std::size_t numExpanded = 0;
    const auto expand = [&](std::uint32_t v) {
        for (std::size_t i = 0; i < numExpanded; ++i)
            if (expanded[i] == v) return false;
        if (numExpanded < expanded.size()) expanded[numExpanded++] = v;
        return tryFacesOf(v);
    };
    expand(startVertex);
    for (int step = 0; step < 256; ++step) {
        const auto t = mMesh.triangles[best.face];
        bool improved = false;
        for (auto v : t) improved = expand(v) || improved;
        if (!improved) break;
    }
    return best;
}

double MeshDistance::signedFromClosest(const Vec3& x, const Closest& c, bool* onBorder) const
{
    const double d = std::sqrt(c.squaredDistance);
    const Vec3 n = pseudoNormal(c.face, c.feature);
    const double along = dot(x - c.point, n);
    if (onBorder) {
        // Beyond the border: the closest feature is on it and x lies off to the side rather
        // than in front of or behind it (the side is then a guess).
        const auto& t = mMesh.triangles[c.face];
        bool border = false;
        switch (c.feature) {
        case kVertexA: border = mBorderVertex[t[0]]; break;
        case kVertexB: border = mBorderVertex[t[1]]; break;
        case kVertexC: border = mBorderVertex[t[2]]; break;
        case kEdgeAB: border = mBorderVertex[t[0]] && mBorderVertex[t[1]]; break;
        case kEdgeBC: border = mBorderVertex[t[1]] && mBorderVertex[t[2]]; break;
        case kEdgeCA: border = mBorderVertex[t[2]] && mBorderVertex[t[0]]; break;
        default: break;
        }
        *onBorder = border && std::abs(along) < 0.7 * d * norm(n);
    }
    return along < 0 ? -d : d;
}

void MeshDistance::buildGrid(double cellSize) const
{
    const std::size_t nf = mMesh.numTriangles();
    const BoundingBox box = boundingBox(mMesh.points);
    const Vec3 &lo = box.min, &hi = box.max;
    mCell = cellSize;
    const auto dims = [&] {
        std::array<std::int64_t, 3> d;
        for (int a = 0; a < 3; ++a) d[a] = std::int64_t(std::floor((hi[a] - lo[a]) / mCell)) + 1;
        return d;
    };
    while (double(dims()[0]) * double(dims()[1]) * double(dims()[2]) > double(1 << 25)) mCell *= 1.25;
    mGridDims = dims();
    mGridOrigin = lo;

    std::vector<std::array<std::int64_t, 6>> range(nf);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf), [&](const auto& r) {
        for (std::size_t f = r.begin(); f < r.end(); ++f) {
            const auto& t = mMesh.triangles[f];
            for (int a = 0; a < 3; ++a) {
                double tlo = mMesh.points[t[0]][a], thi = tlo;
                for (int k = 1; k < 3; ++k) {
                    tlo = std::min(tlo, mMesh.points[t[k]][a]);
                    thi = std::max(thi, mMesh.points[t[k]][a]);
                }
                range[f][a] = std::clamp<std::int64_t>(std::int64_t(std::floor((tlo - lo[a]) / mCell)), 0, mGridDims[a] - 1);
                range[f][a + 3] = std::clamp<std::int64_t>(std::int64_t(std::floor((thi - lo[a]) / mCell)), 0, mGridDims[a] - 1);
            }
        }
    });
    mCellFirst.assign(std::size_t(mGridDims[0] * mGridDims[1] * mGridDims[2]) + 1, 0);
    for (std::size_t f = 0; f < nf; ++f)
        for (auto x = range[f][0]; x <= range[f][3]; ++x)
            for (auto y = range[f][1]; y <= range[f][4]; ++y)
                for (auto z = range[f][2]; z <= range[f][5]; ++z) ++mCellFirst[cellIndex(x, y, z) + 1];
    for (std::size_t c = 1; c < mCellFirst.size(); ++c) mCellFirst[c] += mCellFirst[c - 1];
    mCellTris.resize(mCellFirst.back());
    std::vector<std::uint32_t> fill(mCellFirst.begin(), mCellFirst.end() - 1);
    for (std::size_t f = 0; f < nf; ++f)  // ascending face index within every cell
        for (auto x = range[f][0]; x <= range[f][3]; ++x)
            for (auto y = range[f][1]; y <= range[f][4]; ++y)
                for (auto z = range[f][2]; z <= range[f][5]; ++z)
                    mCellTris[fill[cellIndex(x, y, z)]++] = std::uint32_t(f);
}

double MeshDistance::exactSignedDistance(const Vec3& x, std::uint32_t startVertex,
                                         double cellSize) const
{
    std::call_once(mGridOnce, [&] { buildGrid(cellSize); });
    Closest best = descend(x, startVertex);  // an upper bound
    double bestDistance = std::sqrt(best.squaredDistance);
    std::array<std::int64_t, 6> cells;
    for (int a = 0; a < 3; ++a) {
        const double reach = bestDistance * (1 + 1e-9) + 1e-12;
        cells[a] = std::max<std::int64_t>(0, std::int64_t(std::floor((x[a] - reach - mGridOrigin[a]) / mCell)));
        cells[a + 3] = std::min<std::int64_t>(mGridDims[a] - 1, std::int64_t(std::floor((x[a] + reach - mGridOrigin[a]) / mCell)));
    }
    for (auto cx = cells[0]; cx <= cells[3]; ++cx)
        for (auto cy = cells[1]; cy <= cells[4]; ++cy)
            for (auto cz = cells[2]; cz <= cells[5]; ++cz) {
                const std::size_t c = cellIndex(cx, cy, cz);
                for (auto i = mCellFirst[c]; i < mCellFirst[c + 1]; ++i) {
                    const std::uint32_t f = mCellTris[i];
                    const BoundingSphere& s = mBoundingSphere[f];
                    const double dx = x.x - s.centre.x, dy = x.y - s.centre.y, dz = x.z - s.centre.z;
                    const double limit = bestDistance + s.radius;
                    const double centre2 = dx * dx + dy * dy + dz * dz;
                    if (centre2 > limit * limit) continue;
                    // Tighter: the distance to the triangle's plane and, within the plane,
                    // the gap to its bounding circle.
                    const Vec3& n = mFaceNormal[f];
                    const double plane = dx * n.x + dy * n.y + dz * n.z;
                    const double plane2 = plane * plane, lateral2 = centre2 - plane2;
                    const double gap =
                        lateral2 > s.radius * s.radius ? std::sqrt(lateral2) - s.radius : 0.0;
                    if (plane2 + gap * gap > best.squaredDistance) continue;
                    const Closest c2 = closestOnFace(x, f);
                    // Ties (the same point reached through several faces) keep the lowest
                    // face index, so the sign does not depend on the visiting order.
                    if (c2.squaredDistance < best.squaredDistance ||
                        (c2.squaredDistance == best.squaredDistance && f < best.face)) {
                        best = c2;
                        bestDistance = std::sqrt(best.squaredDistance);
                    }
                }
            }
    return signedFromClosest(x, best);
}

} // namespace msii::detail
