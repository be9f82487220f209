#include <msii/invariants/exact.h>

#include <msii/core/errors.h>
#include <msii/invariants/scales.h>

#include "exact_triangles.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <unordered_set>
#include <utility>

namespace msii {
namespace {

using namespace detail;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------------------
// The cone at a vertex (S/r² = Ω_p − Σ Ω_t needs Ω_p, the limit of S(ε)/ε²).

/// Triangles incident to each vertex (CSR), with the corner at which the vertex sits.
struct VertexFaces {
    std::vector<std::uint32_t> first;                       // numVertices + 1
    std::vector<std::pair<std::uint32_t, std::uint8_t>> faces;  // (triangle, corner)
};

VertexFaces vertexFaces(const TriMesh& mesh)
{
    VertexFaces vf;
    vf.first.assign(mesh.numVertices() + 1, 0);
    for (const Triangle& t : mesh.triangles)
        for (int i = 0; i < 3; ++i) ++vf.first[t[i] + 1];
    for (std::size_t v = 0; v < mesh.numVertices(); ++v) vf.first[v + 1] += vf.first[v];
    vf.faces.resize(vf.first.back());
    std::vector<std::uint32_t> fill(vf.first.begin(), vf.first.end() - 1);
    for (std::size_t t = 0; t < mesh.numTriangles(); ++t)
        for (int i = 0; i < 3; ++i)
            vf.faces[fill[mesh.triangles[t][i]]++] = {std::uint32_t(t), std::uint8_t(i)};
    return vf;
}

/// Solid angle of the solid's cone at vertex v. On the unit sphere about v the cone is a
/// spherical polygon with a geodesic side per incident triangle and a corner per incident
/// edge e, where its interior angle is the solid's interior dihedral angle δ_e at e (π flat,
/// < π convex, > π concave). Girard: Ω = Σ_e δ_e − (k − 2)π over the k edges (flat 2π,
/// convex cube corner π/2). NaN if an edge at v has no second triangle (border), or if the
/// triangles at v fold over one another.
double coneSolidAngle(const TriMesh& mesh, const std::vector<TriangleFrame>& frames,
                      const VertexFaces& vf, std::uint32_t v)
{
    const std::uint32_t begin = vf.first[v], end = vf.first[v + 1];
    const std::size_t k = end - begin;
    if (k < 3) return kNaN;
    double sum = 0;
    for (std::uint32_t f = begin; f < end; ++f) {
        const auto [t, i] = vf.faces[f];
        // Edge v → q of triangle t; its twin q → v lies in the triangle where q precedes v.
        const std::uint32_t q = mesh.triangles[t][(i + 1) % 3];
        std::uint32_t twin = UINT32_MAX;
        for (std::uint32_t g = begin; g < end; ++g) {
            const auto [u, j] = vf.faces[g];
            if (mesh.triangles[u][(j + 2) % 3] == q) {
                twin = u;
                break;
            }
        }
        if (twin == UINT32_MAX) return kNaN;
        const Vec3& n1 = frames[t].n;
        const Vec3& n2 = frames[twin].n;
        const Vec3 e = normalized(mesh.points[q] - mesh.points[v]);
        // The normals turn by θ about e (positive: convex fold); δ = π − θ.
        sum += kPi - std::atan2(dot(cross(n1, n2), e), dot(n1, n2));
    }
    // A cone is a simple closed curve on the unit sphere, enclosing 0 < Ω < 4π. Outside
    // that range the triangles at v fold over one another (a crumpled patch of a scan), the
    // curve crosses itself and the solid is not defined at v: NaN.
    const double omega = sum - double(k - 2) * kPi;
    return omega > 0 && omega < 4 * kPi ? omega : kNaN;
}

/// Per-radius sums of one vertex.
class BallSums {
public:
    explicit BallSums(std::size_t numRadii)
        : mArea(numRadii), mArc(numRadii), mOmega(numRadii), mDArea(numRadii), mWholeArea(numRadii),
          mWholeOmega(numRadii), mWholeDArea(numRadii), mWhole(numRadii)
    {
    }

    void clear()
    {
        for (auto* v : {&mArea, &mArc, &mOmega, &mDArea, &mWholeArea, &mWholeOmega, &mWholeDArea})
            std::fill(v->begin(), v->end(), 0.0);
        std::fill(mWhole.begin(), mWhole.end(), AngleProduct{});
        mSumArea = mSumOmega = mSumDArea = 0;
    }

    void addStraddled(std::size_t j, const Measures& m, double d)
    {
        mArea[j] += m.area;
        mArc[j] += m.arcLength;
        mOmega[j] += m.solidAngle;
        mDArea[j] += d * m.area;
    }

    /// A triangle whole in B_r for radius j and beyond. @p halfBound bounds |Ω_t|/2.
    void addWhole(std::size_t j, double area, double d, const Complex* solid, double halfBound)
    {
        mWholeArea[j] += area;
        mWholeDArea[j] += d * area;
        if (!solid) return;
        if (halfBound >= 0.25 * kPi) {
            mWholeOmega[j] += 2 * solid->arg();
            return;
        }
        mWhole[j].add(*solid, halfBound, mWholeOmega[j]);
    }

    /// Totals at radius j (call with j = 0, 1, ... in order): area, arc, Σ Ω_t, Σ d_t area_t.
    Measures total(std::size_t j, double& dArea)
    {
        mWhole[j].resolve(mWholeOmega[j]);
        mSumArea += mWholeArea[j];
        mSumOmega += mWholeOmega[j];
        mSumDArea += mWholeDArea[j];
        dArea = mDArea[j] + mSumDArea;
        Measures m;
        m.area = mArea[j] + mSumArea;
        m.arcLength = mArc[j];
        m.solidAngle = mOmega[j] + mSumOmega;
        return m;
    }

private:
    /// A sum of angles kept as the product of complex numbers whose arguments are their
    /// halves, resolved (one atan2) before the bounds of the halves reach π/2.
    struct AngleProduct {
        Complex product;
        double budget = 0;
        int factors = 0;
        void add(const Complex& half, double halfBound, double& sum)
        {
            if (budget + halfBound >= 0.5 * kPi || factors == kMaxFactors) resolve(sum);
            product.multiply(half.re, half.im);
            budget += halfBound;
            ++factors;
        }
        void resolve(double& sum)
        {
            if (factors > 0) sum += 2 * product.arg();
            *this = AngleProduct{};
        }
    };
    // Factors lie within ~[1, 4] in magnitude (vanOosterom() over la·lb·lc, for a triangle
    // that subtends little): 4^64 stays finite.
    static constexpr int kMaxFactors = 64;

    std::vector<double> mArea, mArc, mOmega, mDArea;          // straddled, per radius
    std::vector<double> mWholeArea, mWholeOmega, mWholeDArea;  // whole, at their first radius
    std::vector<AngleProduct> mWhole;
    double mSumArea = 0, mSumOmega = 0, mSumDArea = 0;
};

void validate(const TriMesh& mesh, const ExactOptions& options)
{
    const auto& radii = options.radii;
    validateRadii(radii);
    for (const std::uint32_t v : options.vertices)
        if (v >= mesh.numVertices()) {
            std::ostringstream msg;
            msg << "vertex index " << v << " is out of range (the mesh has " << mesh.numVertices()
                << " vertices)";
            throw InvalidInputError(msg.str());
        }
    if (!options.borderDistance.empty() && options.borderDistance.size() != mesh.numVertices()) {
        std::ostringstream msg;
        msg << "the border distances hold " << options.borderDistance.size()
            << " values, but the mesh has " << mesh.numVertices() << " vertices";
        throw InvalidInputError(msg.str());
    }
}

/// The result before any value: the radii, the vertices to compute (all if none are
/// chosen), and NaN for every value asked for.
ExactResult unsetResult(const TriMesh& mesh, const ExactOptions& options)
{
    ExactResult result;
    result.radii = options.radii;
    const std::size_t nr = result.radii.size();
    if (options.vertices.empty()) {
        result.vertices.resize(mesh.numVertices());
        for (std::size_t v = 0; v < mesh.numVertices(); ++v) result.vertices[v] = std::uint32_t(v);
    } else {
        result.vertices = options.vertices;
    }
    const std::size_t nk = result.vertices.size();
    if (options.computeVolumeSphere) {
        result.volume.assign(nr, std::vector<double>(nk, kNaN));
        result.sphere.assign(nr, std::vector<double>(nk, kNaN));
    }
    if (options.computePatchLine) {
        result.patch.assign(nr, std::vector<double>(nk, kNaN));
        result.line.assign(nr, std::vector<double>(nk, kNaN));
    }
    return result;
}

/// unmasked radii [0, jEnd).
struct VertexBall {
    const Vec3& p;
    double reach;  ///< the largest unmasked radius
    std::size_t jEnd;
    const std::vector<double>& radii;
    const RadiusCounter& counter;
    bool wantVS;
    BallSums& sums;

    /// Adds the triangle in @p slot of @p set (nothing if it lies beyond reach).
    void add(const TriangleSet& set, std::uint32_t slot) const
    {
        const SlotBound& bound = set.bounds[slot];
        const double slack = reach + bound.radius;
        const double centroid2 = squaredNorm(bound.centroid - p);
        if (centroid2 >= slack * slack) return;
        const SlotTriangle& tri = set.slots[slot];
        const std::array<Vec3, 3> q{tri.corner[0] - p, tri.corner[1] - p, tri.corner[2] - p};
        const double q2[3] = {squaredNorm(q[0]), squaredNorm(q[1]), squaredNorm(q[2])};
        // The first radius whose ball holds the whole triangle.
        const std::size_t jWhole = counter.below(std::max({q2[0], q2[1], q2[2]}), jEnd);
        double d;
        // Straddled radii lie between the distances to the triangle and to its
        // farthest corner. Most triangles straddle none, which shows without the
        // distance to the triangle: for x = Σ λ_i corner_i in it, |x − p|² = Σ λ_i
        // |corner_i − p|² − Σ λ_i |corner_i − x|² >= (nearest corner)² − ρ_t², as the
        // weighted mean x minimises the last sum (<= its value about the centroid).
        const double nearest2 = std::min({q2[0], q2[1], q2[2]});
        if (jWhole > 0 && nearest2 - bound.radius * bound.radius < counter.squared(jWhole - 1)) {
            // Corner nearest to p (the first of equals), as in LocalTriangle.
            const int nearest = q2[0] <= q2[1] ? (q2[0] <= q2[2] ? 0 : 2) : (q2[1] <= q2[2] ? 1 : 2);
            const Straddler straddler(tri, q, q2, nearest);
            d = straddler.d;
            std::size_t j = counter.atMost(straddler.near2, jEnd);
            if (j < jWhole && !straddler.precise) {
                TriangleFrame frame;
                frame.n = tri.n;
                frame.t1 = tri.t1;
                frame.t2 = tri.t2;
                frame.area = tri.area;
                const LocalTriangle local(q, frame);
                for (; j < jWhole; ++j) sums.addStraddled(j, local.sectors(radii[j], wantVS), d);
            }
            for (; j < jWhole; ++j) sums.addStraddled(j, straddler.fastMeasures(radii[j], wantVS), d);
        } else {
            // A triangle at p has d = 0 exactly, and no solid angle (its part is Ω_p);
            // otherwise any corner gives d up to rounding.
            d = nearest2 == 0 ? 0.0 : dot(q[0], tri.n);
        }
        if (jWhole >= jEnd) return;
        if (!wantVS || d == 0) {
            sums.addWhole(jWhole, tri.area, d, nullptr, 0);
            return;
        }
        const double la = std::sqrt(q2[0]), lb = std::sqrt(q2[1]), lc = std::sqrt(q2[2]);
        Complex solid = vanOosterom(q, la, lb, lc);
        const double lengths = la * lb * lc, inverse = 1.0 / (lengths * centroid2);
        const double scale = inverse * centroid2;
        solid.re *= scale;
        solid.im *= scale;
        const double x = bound.radius * bound.radius * lengths * inverse;  // ρ_t² / D²
        sums.addWhole(jWhole, tri.area, d, &solid, x < 1 ? kPi * x : kPi);
    }
};

/// The values of the @p k-th vertex of @p result for the radii [0, jEnd) from its ball sums
/// and the solid angle @p omegaP of the solid's cone at it.
void storeVertex(BallSums& sums, double omegaP, std::size_t jEnd, std::size_t k, bool wantVS, bool wantPL,
                 ExactResult& result)
{
    for (std::size_t j = 0; j < jEnd; ++j) {
        double dArea = 0;
        const Measures m = sums.total(j, dArea);
        const double r = result.radii[j];
        if (wantPL) {
            result.patch[j][k] = m.area / (kPi * r * r);
            result.line[j][k] = m.arcLength / (2 * kPi * r);
        }
        if (wantVS) {
            // S/r² = Ω_p − Σ Ω_t;  3V = Σ d_t area_t + r S  (module comment).
            const double s = (omegaP - m.solidAngle) * r * r;
            const double vol = (dArea + r * s) / 3.0;
            result.sphere[j][k] = s / (4 * kPi * r * r);
            result.volume[j][k] = vol / (4.0 / 3.0 * kPi * r * r * r);
        }
    }
}

} // namespace

TriangleBallMeasures triangleBallMeasures(const Vec3& p, const Vec3& a, const Vec3& b,
                                          const Vec3& c, double r)
{
    const LocalTriangle local(p, {a, b, c}, makeFrame(a, b, c));
    const Measures m = local.measure(r, true);
    TriangleBallMeasures out;
    out.area = m.area;
    out.arcLength = m.arcLength;
    out.solidAngle = m.solidAngle;
    out.distance = local.distance();
    return out;
}

// V of paper Eq. 1 and the four domains V, S, P, L of Eq. 2, normalised as in
// docs/method.md, Definitions and normalisations; per vertex from sums over the triangles
// near it (identities: header).
ExactResult computeExact(const TriMesh& mesh, const ExactOptions& options, RunContext* progress)
{
    validate(mesh, options);
    ExactResult result = unsetResult(mesh, options);
    const auto& radii = result.radii;
    const std::size_t nr = radii.size();
    const std::size_t nk = result.vertices.size();
    const bool wantVS = options.computeVolumeSphere, wantPL = options.computePatchLine;
    if (nk == 0 || mesh.numTriangles() == 0 || !(wantVS || wantPL)) return result;

    const std::vector<TriangleFrame> frames = triangleFrames(mesh);
    const VertexFaces vf = wantVS ? vertexFaces(mesh) : VertexFaces{};
    const std::vector<TriangleSet> sets = triangleSets(mesh, frames, result.vertices, radii.back());
    const RadiusCounter counter(radii);

    if (progress) progress->start("exact invariants", nk);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nk, 1), [&](const auto& range) {
        BallSums sums(nr);
        for (std::size_t k = range.begin(); k < range.end(); ++k) {
            const std::uint32_t v = result.vertices[k];
            const Vec3& p = mesh.points[v];
            // Radii [0, jEnd) are unmasked (ascending radii, r >= borderDistance is masked).
            std::size_t jEnd = nr;
            if (!options.borderDistance.empty())
                jEnd = std::size_t(std::lower_bound(radii.begin(), radii.end(), options.borderDistance[v]) -
                                   radii.begin());
            if (jEnd == 0) continue;
            sums.clear();
            const VertexBall ball{p, radii[jEnd - 1], jEnd, radii, counter, wantVS, sums};
            for (const TriangleSet& set : sets)
                set.grid.forEachNear(p, ball.reach, [&](std::uint32_t slot) { ball.add(set, slot); });
            const double omegaP = wantVS ? coneSolidAngle(mesh, frames, vf, v) : 0.0;
            storeVertex(sums, omegaP, jEnd, k, wantVS, wantPL, result);
        }
        if (progress) progress->advance(range.size());
    });
    if (progress) progress->end();
    return result;
}

} // namespace msii