#include "exact_triangles.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <unordered_set>
#include <utility>

namespace msii::detail {

void addSector(double ax, double ay, double bx, double by, double rho, double d, double r,
               bool solid, Measures& m)
{
    const double wx = bx - ax, wy = by - ay;
    const double len = std::sqrt(wx * wx + wy * wy);
    if (!(len > 0)) return;
    const double ux = wx / len, uy = wy / len;
    const double h = ax * uy - ay * ux;  // signed distance of the edge's line from c
    if (h == 0) return;                  // c on the line: the sector has no area
    const double sigma = h > 0 ? 1.0 : -1.0, e = std::abs(h);
    const double tA = ax * ux + ay * uy, tB = bx * ux + by * uy;
    const double sd = sign(d), ad = std::abs(d);

    // Angle between the rays to the line points t1 <= t2 (always in [0, π)).
    const auto dphi = [&](double t1, double t2) { return std::atan2(e * (t2 - t1), e * e + t1 * t2); };
    const auto psi = [&](double t) { return std::atan2(ad * t, e * std::sqrt(d * d + e * e + t * t)); };

    double area = 0, arc = 0, omega = 0;
    const auto disc = [&](double t1, double t2) {
        if (!(t2 > t1)) return;
        const double phi = dphi(t1, t2);
        area += 0.5 * rho * rho * phi;
        arc += rho * phi;
        if (solid) omega += (sd - d / r) * phi;
    };
    const auto line = [&](double t1, double t2) {
        if (!(t2 > t1)) return;
        area += 0.5 * e * (t2 - t1);
        if (solid && d != 0) omega += sd * (dphi(t1, t2) - (psi(t2) - psi(t1)));
    };
    if (e >= rho) {
        disc(tA, tB);
    } else {
        const double ts = std::sqrt((rho - e) * (rho + e));
        disc(tA, std::min(tB, -ts));
        line(std::max(tA, -ts), std::min(tB, ts));
        disc(std::max(tA, ts), tB);
    }
    m.area += sigma * area;
    m.arcLength += sigma * arc;
    m.solidAngle += sigma * omega;
}

double originTriangleDistance2D(const double x[3], const double y[3])
{
    bool inside = true;
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
        const int k = (i + 1) % 3;
        const double wx = x[k] - x[i], wy = y[k] - y[i];
        if (wx * (-y[i]) - wy * (-x[i]) < 0) inside = false;  // origin right of the edge
        const double w2 = wx * wx + wy * wy;
        const double t = w2 > 0 ? std::clamp(-(x[i] * wx + y[i] * wy) / w2, 0.0, 1.0) : 0.0;
        const double fx = x[i] + t * wx, fy = y[i] + t * wy;
        best = std::min(best, std::sqrt(fx * fx + fy * fy));
    }
    return inside ? 0.0 : best;
}

TriangleFrame makeFrame(const Vec3& a, const Vec3& b, const Vec3& c)
{
    TriangleFrame f;
    const Vec3 nn = cross(b - a, c - a);
    f.area = 0.5 * norm(nn);
    f.n = normalized(nn);
    f.t1 = normalized(b - a);
    f.t2 = cross(f.n, f.t1);
    f.centroid = (a + b + c) / 3.0;
    f.boundingRadius = std::sqrt(std::max({squaredNorm(a - f.centroid), squaredNorm(b - f.centroid),
                                           squaredNorm(c - f.centroid)}));
    return f;
}


TriangleGrid::TriangleGrid(const std::vector<TriangleFrame>& frames, const std::vector<std::uint32_t>& triangles,
                           double cellSize)
{
    const std::size_t nt = triangles.size();
    Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (const std::uint32_t t : triangles) {
        mReach = std::max(mReach, frames[t].boundingRadius);
        for (int i = 0; i < 3; ++i) {
            lo[i] = std::min(lo[i], frames[t].centroid[i]);
            hi[i] = std::max(hi[i], frames[t].centroid[i]);
        }
    }
    if (nt == 0) lo = hi = Vec3(0, 0, 0);
    mOrigin = lo;
    // At most ~1e6 cells per axis, so the packed keys cannot overflow.
    const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    mCell = std::max({cellSize, extent * 1e-6, std::numeric_limits<double>::min()});
    for (int i = 0; i < 3; ++i) mCount[i] = std::int64_t(std::floor((hi[i] - lo[i]) / mCell)) + 1;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(nt);
    for (std::size_t s = 0; s < nt; ++s) {
        const Vec3& centroid = frames[triangles[s]].centroid;
        std::int64_t c[3];
        for (int i = 0; i < 3; ++i) c[i] = clampIndex(i, (centroid[i] - mOrigin[i]) / mCell);
        keyed[s] = {key(c[0], c[1], c[2]), triangles[s]};
    }
    std::sort(keyed.begin(), keyed.end());
    mTriangles.resize(nt);
    for (std::size_t s = 0; s < nt; ++s) {
        mTriangles[s] = keyed[s].second;
        if (s == 0 || keyed[s].first != keyed[s - 1].first) {
            mKeys.push_back(keyed[s].first);
            mFirst.push_back(std::uint32_t(s));
        }
    }
    mFirst.push_back(std::uint32_t(nt));
}

SlotTriangle makeSlot(const TriMesh& mesh, const TriangleFrame& f, std::uint32_t t)
{
    SlotTriangle s;
    for (int i = 0; i < 3; ++i) s.corner[i] = mesh.points[mesh.triangles[t][i]];
    s.n = f.n;
    s.area = f.area;
    s.t1 = f.t1;
    s.t2 = f.t2;
    double x[3], y[3];
    for (int i = 0; i < 3; ++i) {
        x[i] = dot(s.corner[i] - s.corner[0], f.t1);
        y[i] = dot(s.corner[i] - s.corner[0], f.t2);
    }
    for (int i = 0; i < 3; ++i) {
        const int k = (i + 1) % 3;
        const double wx = x[k] - x[i], wy = y[k] - y[i];
        s.length[i] = std::sqrt(wx * wx + wy * wy);
        s.ux[i] = wx / s.length[i];
        s.uy[i] = wy / s.length[i];
        s.across[i] = x[i] * s.uy[i] - y[i] * s.ux[i];
        s.along[i] = x[i] * s.ux[i] + y[i] * s.uy[i];
    }
    return s;
}

RadiusCounter::RadiusCounter(const std::vector<double>& radii) : mRadii2(radii.size())
{
    double gap = std::numeric_limits<double>::infinity(), previous = 0;
    for (std::size_t j = 0; j < radii.size(); ++j) {
        mRadii2[j] = radii[j] * radii[j];
        gap = std::min(gap, mRadii2[j] - previous);
        previous = mRadii2[j];
    }
    // Bins of half the smallest gap between squared radii, at most 2^16 of them.
    const double bins = std::clamp(std::ceil(2 * mRadii2.back() / gap), 1.0, 65536.0);
    mScale = bins / mRadii2.back();
    mStart.resize(std::size_t(bins) + 2);
    for (std::size_t b = 0; b < mStart.size(); ++b) {
        const double x2 = double(b) / mScale * (1 - 1e-12);
        mStart[b] = std::uint32_t(std::lower_bound(mRadii2.begin(), mRadii2.end(), x2) - mRadii2.begin());
    }
}

std::vector<TriangleFrame> triangleFrames(const TriMesh& mesh)
{
    std::vector<TriangleFrame> frames(mesh.numTriangles());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, frames.size()), [&](const auto& range) {
        for (std::size_t t = range.begin(); t < range.end(); ++t) {
            const auto& tri = mesh.triangles[t];
            frames[t] = makeFrame(mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]]);
        }
    });
    return frames;
}

std::vector<TriangleSet> triangleSets(const TriMesh& mesh, const std::vector<TriangleFrame>& frames,
                                      const std::vector<std::uint32_t>& vertices, double R)
{
    const double cell = 0.25 * R;
    // With a few chosen vertices of a large mesh, only the triangles that may meet their
    // balls: a triangle no larger than R whose centroid lies within 2 R of a vertex, found
    // through cells of size R around the vertices (a hash of the cell; a collision only
    // keeps a triangle more).
    std::unordered_set<std::uint64_t> near;
    const auto cellKey = [R](const Vec3& x, int dx, int dy, int dz) {
        const auto index = [R](double c, int d) { return std::uint64_t(std::int64_t(std::floor(c / R)) + d); };
        return index(x.x, dx) * 0x9E3779B97F4A7C15ULL ^ index(x.y, dy) * 0xC2B2AE3D27D4EB4FULL ^
               index(x.z, dz) * 0x165667B19E3779F9ULL;
    };
    const bool someVertices = 4 * vertices.size() < mesh.numVertices();
    if (someVertices)
        for (const std::uint32_t v : vertices)
            for (int dx = -2; dx <= 2; ++dx)
                for (int dy = -2; dy <= 2; ++dy)
                    for (int dz = -2; dz <= 2; ++dz) near.insert(cellKey(mesh.points[v], dx, dy, dz));
    std::vector<std::uint32_t> small, large;
    for (std::uint32_t t = 0; t < frames.size(); ++t) {
        if (someVertices && frames[t].boundingRadius <= R && near.count(cellKey(frames[t].centroid, 0, 0, 0)) == 0)
            continue;
        (frames[t].boundingRadius <= cell ? small : large).push_back(t);
    }
    std::vector<TriangleSet> sets;
    for (const auto* subset : {&small, &large}) {
        if (subset->empty()) continue;
        double largest = 0;
        for (const std::uint32_t t : *subset) largest = std::max(largest, frames[t].boundingRadius);
        TriangleSet set{TriangleGrid(frames, *subset, std::max(cell, largest)), {}, {}};
        set.slots.resize(subset->size());
        set.bounds.resize(subset->size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, subset->size()), [&](const auto& range) {
            for (std::size_t s = range.begin(); s < range.end(); ++s) {
                const std::uint32_t t = set.grid.triangleAt(s);
                set.slots[s] = makeSlot(mesh, frames[t], t);
                set.bounds[s] = {frames[t].centroid, frames[t].boundingRadius};
            }
        });
        sets.push_back(std::move(set));
    }
    return sets;
}


} // namespace msii::detail
