#include "mesh_distance.h"

#include <array>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>

#include <cmath>
#include <limits>

namespace msii::detail {

namespace {

// Features of a triangle (a, b, c) that can hold the closest point.
enum Feature { kFace, kVertexA, kVertexB, kVertexC, kEdgeAB, kEdgeBC, kEdgeCA };

/// Closest point on triangle (a, b, c) to p and the feature it lies on (Voronoi regions,
/// as in Ericson, Real-Time Collision Detection, 5.1.5).
Vec3 closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                            int& feature)
{
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) { feature = kVertexA; return a; }
    const Vec3 bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) { feature = kVertexB; return b; }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) { feature = kEdgeAB; return a + ab * (d1 / (d1 - d3)); }
    const Vec3 cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) { feature = kVertexC; return c; }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) { feature = kEdgeCA; return a + ac * (d2 / (d2 - d6)); }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        feature = kEdgeBC;
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    feature = kFace;
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

} // namespace

MeshDistance::MeshDistance(const TriMesh& mesh) : mMesh(mesh)
{
    const std::size_t nv = mesh.numVertices(), nf = mesh.numTriangles();
    mFaceNormal.resize(nf);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf), [&](const auto& r) {
        for (std::size_t f = r.begin(); f < r.end(); ++f) {
            const auto& t = mesh.triangles[f];
            mFaceNormal[f] = normalized(cross(mesh.points[t[1]] - mesh.points[t[0]],
                                              mesh.points[t[2]] - mesh.points[t[0]]));
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

double MeshDistance::faceDistance(const Vec3& x, std::uint32_t f, Vec3& closest, int& feature) const
{
    const auto& t = mMesh.triangles[f];
    closest = closestPointOnTriangle(x, mMesh.points[t[0]], mMesh.points[t[1]],
                                     mMesh.points[t[2]], feature);
    return squaredNorm(x - closest);
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

double MeshDistance::signedDistance(const Vec3& x, std::int64_t startVertex,
                                    std::uint32_t& face, bool* onBorder) const
{
    double best = std::numeric_limits<double>::infinity();
    Vec3 closest, bestPoint;
    int feature = kFace, bestFeature = kFace;
    std::uint32_t bestFace = face;
    const auto tryFacesOf = [&](std::uint32_t v) {
        bool improved = false;
        for (auto i = mFirst[v]; i < mFirst[v + 1]; ++i) {
            const auto g = mFaces[i];
            const double d = faceDistance(x, g, closest, feature);
            if (d < best) {
                best = d;
                bestFace = g;
                bestPoint = closest;
                bestFeature = feature;
                improved = true;
            }
        }
        return improved;
    };
    // Descend: look at every triangle sharing a vertex with the current closest one; the
    // triangles of a vertex are looked at once (a few vertices are remembered).
    std::array<std::uint32_t, 32> expanded;
    std::size_t numExpanded = 0;
    const auto expand = [&](std::uint32_t v) {
        for (std::size_t i = 0; i < numExpanded; ++i)
            if (expanded[i] == v) return false;
        if (numExpanded < expanded.size()) expanded[numExpanded++] = v;
        return tryFacesOf(v);
    };
    if (startVertex >= 0) {
        expand(std::uint32_t(startVertex));
    } else {
        best = faceDistance(x, face, bestPoint, bestFeature);
    }
    for (int step = 0; step < 256; ++step) {
        const auto t = mMesh.triangles[bestFace];
        bool improved = false;
        for (auto v : t) improved = expand(v) || improved;
        if (!improved) break;
    }
    face = bestFace;
    return signedFromClosest(x, Closest{best, bestPoint, bestFace, bestFeature}, onBorder);
}

MeshDistance::Closest MeshDistance::closestOnFace(const Vec3& x, std::uint32_t f) const
{
    Closest c;
    c.face = f;
    c.squaredDistance = faceDistance(x, f, c.point, c.feature);
    return c;
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

std::uint64_t MeshDistance::cellKey(std::int64_t x, std::int64_t y, std::int64_t z) const
{
    const std::uint64_t m = (1u << 21) - 1;
    return (std::uint64_t(x) & m) << 42 | (std::uint64_t(y) & m) << 21 | (std::uint64_t(z) & m);
}

void MeshDistance::buildGrid(double cellSize) const
{
    mCell = cellSize;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> entries;
    const auto cellOf = [&](double v) { return std::int64_t(std::floor(v / mCell)); };
    for (std::size_t f = 0; f < mMesh.numTriangles(); ++f) {
        const auto& t = mMesh.triangles[f];
        Vec3 lo = mMesh.points[t[0]], hi = lo;
        for (int k = 1; k < 3; ++k)
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], mMesh.points[t[k]][a]);
                hi[a] = std::max(hi[a], mMesh.points[t[k]][a]);
            }
        for (auto x = cellOf(lo.x); x <= cellOf(hi.x); ++x)
            for (auto y = cellOf(lo.y); y <= cellOf(hi.y); ++y)
                for (auto z = cellOf(lo.z); z <= cellOf(hi.z); ++z)
                    entries.emplace_back(cellKey(x, y, z), std::uint32_t(f));
    }
    tbb::parallel_sort(entries.begin(), entries.end());
    mCellTris.resize(entries.size());
    for (std::size_t i = 0; i < entries.size(); ++i) {
        if (i == 0 || entries[i].first != entries[i - 1].first) {
            mCellKeys.push_back(entries[i].first);
            mCellFirst.push_back(std::uint32_t(i));
        }
        mCellTris[i] = entries[i].second;
    }
    mCellFirst.push_back(std::uint32_t(entries.size()));
}

double MeshDistance::exactSignedDistance(const Vec3& x, std::int64_t startVertex,
                                         double cellSize) const
{
    std::call_once(mGridOnce, [&] { buildGrid(cellSize); });
    std::uint32_t face = 0;
    const double bound = std::abs(signedDistance(x, startVertex, face));
    double best = std::numeric_limits<double>::infinity();
    Vec3 closest, bestPoint;
    int feature = kFace, bestFeature = kFace;
    std::uint32_t bestFace = face;
    const auto cellOf = [&](double v) { return std::int64_t(std::floor(v / mCell)); };
    const double reach = bound * (1 + 1e-9) + 1e-12;
    for (auto cx = cellOf(x.x - reach); cx <= cellOf(x.x + reach); ++cx)
        for (auto cy = cellOf(x.y - reach); cy <= cellOf(x.y + reach); ++cy)
            for (auto cz = cellOf(x.z - reach); cz <= cellOf(x.z + reach); ++cz) {
                const auto it = std::lower_bound(mCellKeys.begin(), mCellKeys.end(), cellKey(cx, cy, cz));
                if (it == mCellKeys.end() || *it != cellKey(cx, cy, cz)) continue;
                const std::size_t c = std::size_t(it - mCellKeys.begin());
                for (auto i = mCellFirst[c]; i < mCellFirst[c + 1]; ++i) {
                    const double d = faceDistance(x, mCellTris[i], closest, feature);
                    // Ties (the same point reached through several faces) keep the lowest
                    // face index, so the sign does not depend on the visiting order.
                    if (d < best || (d == best && mCellTris[i] < bestFace)) {
                        best = d;
                        bestFace = mCellTris[i];
                        bestPoint = closest;
                        bestFeature = feature;
                    }
                }
            }
    if (!std::isfinite(best)) return signedDistance(x, startVertex, face);
    const double d = std::sqrt(best);
    return dot(x - bestPoint, pseudoNormal(bestFace, bestFeature)) < 0 ? -d : d;
}

} // namespace msii::detail
