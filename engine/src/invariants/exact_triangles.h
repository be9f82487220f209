#pragma once
/// @file exact_triangles.h
/// @brief The triangle ∩ ball integrals of the exact mode (msii/invariants/exact.h): a
/// triangle's area, arc and solid angle inside a ball about a point, in closed form over the
/// signed sectors of its edges, and the grid that finds the triangles near a point. Shared by
/// the exact mode (exact.cpp) and the fast mode's exact sums where its kernels blur
/// (patch_line_exact.cpp). Private to the engine.

#include <msii/core/vec3.h>
#include <msii/mesh/trimesh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace msii::detail {

constexpr double kPi = 3.14159265358979323846;

inline double sign(double x) { return x > 0 ? 1.0 : (x < 0 ? -1.0 : 0.0); }

/// Integrals over one triangle ∩ B_r (TriangleBallMeasures without the distance).
struct Measures {
    double area = 0, arcLength = 0, solidAngle = 0;
};

// ---------------------------------------------------------------------------------------
// Sector integrals (docs/method.md, Exact identities and Per triangle). In the triangle's
// plane, with the foot point c of p as origin, the triangle is the signed sum of the
// sectors (c, A, B) of its directed edges, sign σ = sign((A − c) × (B − c)). Within one
// sector, polar coordinates (s, φ) about c, φ measured from the perpendicular onto the
// edge's line (distance e): the region is s <= m(φ) = min(ρ, e / cos φ), where the disc
// bounds it for |φ| > φ* = arccos(e/ρ) (everywhere if e >= ρ) and the line elsewhere. A
// point of the line at coordinate t along the edge (t = 0 at the perpendicular's foot) has
// tan φ = t/e, so the pieces are split at t = ±t*, t* = sqrt(ρ² − e²), and integrated in
// closed form:
//   area  ∫∫ s ds dφ:            disc ½ρ²Δφ,  line ½e²Δ tan φ = ½eΔt;
//   arc   d area / dρ:           disc ρΔφ,    line 0;
//   solid ∫∫ d s/(d² + s²)^{3/2} ds dφ:  disc (sgn d − d/r)Δφ,
//                                line sgn d·[Δφ − Δ asin(|d| sin φ / sqrt(d² + e²))],
// with asin(|d| sin φ / sqrt(d² + e²)) = atan2(|d| t, e·sqrt(d² + e² + t²)) (atan2 keeps
// full precision where the asin argument nears 1).

/// Adds σ × the integrals of the sector (0, a, b) ∩ disc(ρ) to @p m (2D coordinates).
void addSector(double ax, double ay, double bx, double by, double rho, double d, double r,
               bool solid, Measures& m);

/// Distance from the origin to the 2D triangle (x, y), counter-clockwise.
double originTriangleDistance2D(const double x[3], const double y[3]);

/// Per-triangle constants, computed once for the mesh.
struct TriangleFrame {
    Vec3 n, t1, t2;  // unit normal and an orthonormal frame of the plane, t1 × t2 = n
    double area = 0;
    Vec3 centroid;   // with boundingRadius: a sphere around the triangle, to skip far ones fast
    double boundingRadius = 0;
};

TriangleFrame makeFrame(const Vec3& a, const Vec3& b, const Vec3& c);

/// A complex number, for sums of angles as arguments of products (one atan2 for many).
struct Complex {
    double re = 1, im = 0;
    void multiply(double r, double i)
    {
        const double t = re * r - im * i;
        im = re * i + im * r;
        re = t;
    }
    double arg() const { return std::atan2(im, re); }
};

/// Van Oosterom and Strackee's formula for the solid angle Ω of the triangle q (corners
/// relative to p, at distances la, lb, lc): Ω/2 = arg(|a||b||c| + (a·b)|c| + (a·c)|b| +
/// (b·c)|a| + i a·(b×c)) (a·(b×c) = 2·area·d, so Ω has the sign of d).
inline Complex vanOosterom(const std::array<Vec3, 3>& q, double la, double lb, double lc)
{
    const Vec3 &a = q[0], &b = q[1], &c = q[2];
    return {la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la, dot(a, cross(b, c))};
}

/// One triangle as seen from p: everything that does not depend on the radius.
class LocalTriangle {
public:
    LocalTriangle(const Vec3& p, const std::array<Vec3, 3>& corners, const TriangleFrame& frame)
        : LocalTriangle({corners[0] - p, corners[1] - p, corners[2] - p}, frame)
    {
    }

    /// @p q: the corners relative to p.
    LocalTriangle(const std::array<Vec3, 3>& q, const TriangleFrame& frame) : mQ(q), mArea(frame.area)
    {
        int nearest = 0;
        double far2 = 0, near2 = std::numeric_limits<double>::infinity();
        for (int i = 0; i < 3; ++i) {
            const double q2 = squaredNorm(q[i]);
            if (q2 < near2) near2 = q2, nearest = i;
            far2 = std::max(far2, q2);
            // c − p is along n, so coordinates relative to p are those relative to c.
            mX[i] = dot(q[i], frame.t1);
            mY[i] = dot(q[i], frame.t2);
        }
        // From the nearest corner: least rounding, and exactly 0 when p is a corner
        // (the triangles at p must not contribute to Σ Ω_t; their part is Ω_p).
        mD = dot(q[nearest], frame.n);
        mFar = std::sqrt(far2);
        const double inPlane = originTriangleDistance2D(mX, mY);
        mNear = std::sqrt(mD * mD + inPlane * inPlane);
    }

    double distance() const { return mD; }
    double nearestDistance() const { return mNear; }  ///< distance from p to the triangle
    double farthestDistance() const { return mFar; }  ///< distance from p to its farthest corner

    /// The whole triangle (inside the ball): area, no arc, solid angle (vanOosterom()).
    Measures whole(bool solid) const
    {
        Measures m;
        m.area = mArea;
        if (solid && mD != 0) m.solidAngle = 2.0 * vanOosterom(mQ, norm(mQ[0]), norm(mQ[1]), norm(mQ[2])).arg();
        return m;
    }

    /// The triangle ∩ B_r for any r, by the sector decomposition.
    Measures sectors(double r, bool solid) const
    {
        Measures m;
        const double ad = std::abs(mD);
        if (!(r > ad)) return m;
        const double rho = std::sqrt((r - ad) * (r + ad));
        for (int i = 0; i < 3; ++i) {
            const int k = (i + 1) % 3;
            addSector(mX[i], mY[i], mX[k], mY[k], rho, mD, r, solid, m);
        }
        return m;
    }

    /// The triangle ∩ B_r: nothing, the whole triangle, or the sectors.
    Measures measure(double r, bool solid) const
    {
        if (r <= mNear) return {};
        if (r >= mFar) return whole(solid);
        return sectors(r, solid);
    }

private:
    std::array<Vec3, 3> mQ;
    double mArea;
    double mX[3], mY[3];
    double mD, mNear, mFar;
};

// ---------------------------------------------------------------------------------------
// Uniform grid of triangles by centroid: a query box grown by the largest centroid-corner
// distance finds every triangle that meets a ball. computeExact() keeps the triangles much
// larger than a cell in a second grid, so that a few long triangles (a scan's walls and
// bottom, a hole's fill) do not widen every query.

class TriangleGrid {
public:
    /// A grid of @p triangles (indices into @p frames), sorted by cell.
    TriangleGrid(const std::vector<TriangleFrame>& frames, const std::vector<std::uint32_t>& triangles,
                 double cellSize);

    std::size_t size() const { return mTriangles.size(); }
    /// The triangle in slot @p s: slots run cell by cell, so a cell's triangles lie together.
    std::uint32_t triangleAt(std::size_t s) const { return mTriangles[s]; }

    /// Calls @p visit(slot) for the slots of every cell that may hold a triangle meeting
    /// B_radius(p), each once, in an order that depends only on p and the radius.
    template <class Visit> void forEachNear(const Vec3& p, double radius, Visit&& visit) const
    {
        const double reach = radius + mReach;
        // Cells are culled by their distance to p (with a margin for rounding in the binning).
        const double cellReach = reach + 1e-6 * mCell, cellReach2 = cellReach * cellReach;
        std::int64_t lo[3], hi[3];
        for (int i = 0; i < 3; ++i) {
            lo[i] = clampIndex(i, (p[i] - reach - mOrigin[i]) / mCell);
            hi[i] = clampIndex(i, (p[i] + reach - mOrigin[i]) / mCell);
        }
        for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
            const double gx = gap(0, x, p.x);
            for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
                const double gy = gap(1, y, p.y), gxy = gx * gx + gy * gy;
                if (gxy > cellReach2) continue;
                // A column's cells are consecutive keys: one search, then a walk.
                const std::uint64_t column = key(x, y, 0), last = column + std::uint64_t(hi[2]);
                auto it = std::lower_bound(mKeys.begin(), mKeys.end(), column + std::uint64_t(lo[2]));
                for (; it != mKeys.end() && *it <= last; ++it) {
                    const double gz = gap(2, std::int64_t(*it - column), p.z);
                    if (gxy + gz * gz > cellReach2) continue;
                    const std::size_t cell = std::size_t(it - mKeys.begin());
                    for (std::uint32_t s = mFirst[cell]; s < mFirst[cell + 1]; ++s) visit(s);
                }
            }
        }
    }

private:
    /// Distance along @p axis from @p coordinate to the cells of index @p index.
    double gap(int axis, std::int64_t index, double coordinate) const
    {
        const double lo = mOrigin[axis] + double(index) * mCell, hi = lo + mCell;
        return coordinate < lo ? lo - coordinate : (coordinate > hi ? coordinate - hi : 0.0);
    }
    std::int64_t clampIndex(int axis, double coordinate) const
    {
        if (!(coordinate > 0)) return 0;  // also NaN
        if (coordinate >= double(mCount[axis] - 1)) return mCount[axis] - 1;
        return std::int64_t(std::floor(coordinate));
    }
    std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) const
    {
        return (std::uint64_t(x) * std::uint64_t(mCount[1]) + std::uint64_t(y)) * std::uint64_t(mCount[2]) +
               std::uint64_t(z);
    }

    Vec3 mOrigin;
    double mCell = 1, mReach = 0;
    std::int64_t mCount[3] = {1, 1, 1};
    std::vector<std::uint64_t> mKeys;
    std::vector<std::uint32_t> mFirst, mTriangles;
};

// ---------------------------------------------------------------------------------------
// The per-vertex sums. Every triangle near p adds to the radii whose sphere it straddles
// (sectors) and, once, to the first radius whose ball holds it whole: a difference array
// over the radii, summed at the end. The formulas are LocalTriangle's, arranged so that
// most triangles cost no transcendental call:
// - whole triangles: the solid angles Ω_t of one radius are summed as arguments of a
//   product of Van Oosterom's complex numbers (vanOosterom()), one atan2 for many
//   triangles. A triangle inside a sphere of radius ρ_t at distance D from p subtends at
//   most 2π(1 − sqrt(1 − ρ_t²/D²)) <= 2πρ_t²/D², and the product is resolved before these
//   bounds of its half-angles reach π/2, so its argument is never wrapped;
// - straddled triangles: the signed sector angles of the three edges add up to Φ = 2π if
//   the foot point c lies inside the triangle and 0 if outside, so the disc pieces
//   together span Φ − Σ σΔφ over the line pieces (edge inside the disc), and only those
//   are evaluated. Over the line pieces, Σ σΔφ/2 is the argument of a product of
//   half-angle numbers |X1||X2| + X1·X2 + i X1×X2, and their solid angle Σ σ sgn(d)(Δφ −
//   Δψ) is twice the argument of a product of Van Oosterom's numbers for the triangles
//   (c, X1, X2). Both sums lie in [0, 2π) (c inside) or (−π, π) (c outside: the pieces
//   lie within the triangle's angle at c, less than π), so the halved arguments are
//   recovered exactly, with one unwrap near π when c is inside. At a piece's end the
//   distance to p is r (cut by the sphere) or the corner's distance. When c is close to
//   an edge's line these products lose precision (X1 and X2 nearly opposite), and
//   LocalTriangle's sectors are used instead.

/// A triangle with what the per-vertex loop needs, stored in grid-slot order; its bounding
/// sphere, which every visited triangle is tested against, is kept apart (SlotBound).
struct SlotTriangle {
    Vec3 corner[3];
    Vec3 n;
    double area;
    Vec3 t1, t2;
    // Edge i → i + 1 in the frame (t1, t2) with corner 0 as origin: unit direction u, the
    // start's coordinates across (corner_i × u) and along (corner_i · u), and the length.
    double ux[3], uy[3], across[3], along[3], length[3];
};
struct SlotBound {
    Vec3 centroid;
    double radius;
};

SlotTriangle makeSlot(const TriMesh& mesh, const TriangleFrame& f, std::uint32_t t);


/// How many of the first n radii lie below a distance, from a table over the squared
/// distance (a start that is never too high, and within a step or two) and a short walk.
class RadiusCounter {
public:
    explicit RadiusCounter(const std::vector<double>& radii);
    double squared(std::size_t j) const { return mRadii2[j]; }  ///< r_j²
    /// count(r_j² < x2) over j < n.
    std::size_t below(double x2, std::size_t n) const
    {
        std::size_t j = std::min<std::size_t>(start(x2), n);
        while (j < n && mRadii2[j] < x2) ++j;
        return j;
    }
    /// count(r_j² <= x2) over j < n.
    std::size_t atMost(double x2, std::size_t n) const
    {
        std::size_t j = std::min<std::size_t>(start(x2), n);
        while (j < n && mRadii2[j] <= x2) ++j;
        return j;
    }

private:
    std::uint32_t start(double x2) const
    {
        const double b = x2 * mScale;
        return b < double(mStart.size() - 1) ? mStart[std::size_t(b)] : mStart.back();
    }
    std::vector<double> mRadii2;
    std::vector<std::uint32_t> mStart;
    double mScale = 1;
};

/// A triangle whose spheres about p it may straddle: its edges in its plane, origin c.
struct Straddler {
    double d = 0, near2 = 0;
    double e[3], sigma[3], tA[3], tB[3], distance2[3];
    bool inside = false, precise = true;  ///< c inside; fastMeasures() is accurate

    Straddler(const SlotTriangle& s, const std::array<Vec3, 3>& q, const double q2[3], int nearest)
        : distance2{q2[0], q2[1], q2[2]}
    {
        // c relative to corner 0; LocalTriangle computes the corners' coordinates from p
        // instead, so that they are exactly 0 at p, which matters only when c is near an
        // edge's line, where this falls back to it anyway (precise).
        const double x0 = dot(q[0], s.t1), y0 = dot(q[0], s.t2);
        d = dot(q[nearest], s.n);
        const double far2 = std::max({q2[0], q2[1], q2[2]});
        int positive = 0;
        double inPlane2 = std::numeric_limits<double>::infinity();
        for (int i = 0; i < 3; ++i) {
            const double h = x0 * s.uy[i] - y0 * s.ux[i] + s.across[i];
            sigma[i] = h > 0 ? 1.0 : -1.0;
            positive += h > 0;
            e[i] = std::abs(h);
            tA[i] = x0 * s.ux[i] + y0 * s.uy[i] + s.along[i];
            tB[i] = tA[i] + s.length[i];
            // The angles at c lose ~ 1e-16 far / e: keep e above 1e-4 of the corners' reach.
            if (!(e[i] * e[i] > 1e-8 * far2)) precise = false;
            const double along = tA[i] > 0 ? tA[i] : (tB[i] < 0 ? tB[i] : 0.0);
            inPlane2 = std::min(inPlane2, e[i] * e[i] + along * along);
        }
        inside = positive == 3;  // counter-clockwise: c inside iff left of every edge
        near2 = d * d + (inside ? 0.0 : inPlane2);
    }

    /// triangle ∩ B_r (module comment above); requires precise.
    Measures fastMeasures(double r, bool solid) const
    {
        Measures m;
        const double ad = std::abs(d);
        if (!(r > ad)) return m;
        const double rho2 = (r - ad) * (r + ad), rho = std::sqrt(rho2);
        const double sd = sign(d);
        double lineArea = 0;
        Complex angle, omega;
        for (int i = 0; i < 3; ++i) {
            if (e[i] >= rho) continue;
            const double ts = std::sqrt((rho - e[i]) * (rho + e[i]));
            const bool cutA = tA[i] < -ts, cutB = tB[i] > ts;
            const double t1 = cutA ? -ts : tA[i], t2 = cutB ? ts : tB[i];
            if (!(t2 > t1)) continue;
            const double e2 = e[i] * e[i];
            const double crossX = sigma[i] * e[i] * (t2 - t1), dotX = e2 + t1 * t2;  // X1 × X2, X1 · X2
            lineArea += 0.5 * crossX;
            angle.multiply(std::sqrt((e2 + t1 * t1) * (e2 + t2 * t2)) + dotX, crossX);
            if (solid && d != 0) {
                const double l1 = cutA ? r : std::sqrt(distance2[i]), l2 = cutB ? r : std::sqrt(distance2[(i + 1) % 3]);
                // Van Oosterom for (c, X1, X2) seen from p, divided by |d|.
                omega.multiply(l1 * l2 + ad * (l1 + l2) + dotX + d * d, sd * crossX);
            }
        }
        double half = angle.arg();  // Σ σΔφ / 2
        if (inside && half < -0.5 * kPi) half += 2 * kPi;
        const double disc = (inside ? 2 * kPi : 0.0) - 2 * half;
        m.area = 0.5 * rho2 * disc + lineArea;
        m.arcLength = rho * disc;
        if (solid && d != 0) {
            double halfOmega = omega.arg();
            if (inside && sd * halfOmega < -0.5 * kPi) halfOmega += sd * 2 * kPi;
            m.solidAngle = (sd - d / r) * disc + 2 * halfOmega;
        }
        return m;
    }
};

std::vector<TriangleFrame> triangleFrames(const TriMesh& mesh);

/// The triangles of one grid, with what the per-vertex loop reads of them in slot order.
struct TriangleSet {
    TriangleGrid grid;
    std::vector<SlotTriangle> slots;
    std::vector<SlotBound> bounds;
};

/// The triangles that may meet the balls of radius up to @p R about @p vertices, in cell
/// order, in two grids: those within a cell (R/4) of their centroid, and the larger ones
/// (module comment of TriangleGrid). Grids without triangles are left out.
std::vector<TriangleSet> triangleSets(const TriMesh& mesh, const std::vector<TriangleFrame>& frames,
                                      const std::vector<std::uint32_t>& vertices, double R);

} // namespace msii::detail
