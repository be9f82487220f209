/// @file vessels.cpp
/// @brief Vessels, sherds and cylinder seals (vessels.h): a profile loop in the (r, z)
/// half-plane revolved into rings of vertices zipped together; a sherd as a warped cube
/// (around, along and through the wall) whose six faces are the outer and inner wall, the
/// four breaks or the lip.

#include <msii/samples/vessels.h>

#include "lattice.h"

#include <msii/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace msii::samples {

using namespace detail;

namespace {

/// Independent random streams, numbered apart from generators.cpp's, so that one seed never
/// draws the same numbers for both.
enum VesselStream : std::uint64_t {
    kStreamRingPlace = 64,  ///< where the rings sit along the loop
    kStreamRingPhase,       ///< each ring's angular phase
    kStreamRingAngle,       ///< each vertex's angular jitter
    kStreamSurfaceNoise,    ///< roughness
    kStreamMarkPlaces,      ///< the default marks
    kStreamPose,            ///< rotation and translation
    kStreamSherdRows,       ///< the sherd's rows along and through the wall
    kStreamSherdAngle,      ///< jitter along the sherd's rows
    kStreamCapJitter,       ///< the break faces' inner lattice
    kStreamCapDiagonal,     ///< + cap (0, 1)
    kStreamBreak = 96,      ///< + 4 × break + octave
};

/// Arc-length table samples per profile piece (for placing rings; the points themselves
/// are always evaluated on the true curve).
constexpr int kTableSamples = 1024;
/// The foot's outer corner is rounded by this share of min(wall, base); the base's inner
/// corner by this share of the wall.
constexpr double kFootRounding = 0.4;
constexpr double kInnerRounding = 0.5;
/// The seal's edges are rounded by this share of its radius.
constexpr double kSealRounding = 0.05;
/// A sherd's breaks wander by less than this about their nominal place, mm (breakOffset,
/// SherdMap::sideOffset: a sloping wall is up to ~1.4 times wider across in r).
double breakReach(double wall) { return 1.5 + 0.25 * wall; }

// ---------------------------------------------------------------------------------------
// Points of the (r, z) half-plane
// ---------------------------------------------------------------------------------------

struct RZ {
    double r = 0, z = 0;
};
RZ operator+(RZ a, RZ b) { return {a.r + b.r, a.z + b.z}; }
RZ operator-(RZ a, RZ b) { return {a.r - b.r, a.z - b.z}; }
RZ operator*(RZ a, double s) { return {a.r * s, a.z * s}; }
double magnitude(RZ a) { return std::hypot(a.r, a.z); }

/// The point of the half-plane at angle theta in space.
Vec3 revolve(RZ p, double theta) { return {p.r * std::cos(theta), p.r * std::sin(theta), p.z}; }

double distanceToSegment(RZ p, RZ a, RZ b)
{
    const RZ ab = b - a, ap = p - a;
    const double l2 = ab.r * ab.r + ab.z * ab.z;
    const double t = l2 > 0 ? std::clamp((ap.r * ab.r + ap.z * ab.z) / l2, 0.0, 1.0) : 0.0;
    return magnitude(ap - ab * t);
}

// ---------------------------------------------------------------------------------------
// The outer wall r(z)
// ---------------------------------------------------------------------------------------

/// The outer wall as a graph r(z): a straight line (cylinder, cone, the seal's side) or a
/// piecewise cubic Hermite curve through knots with given slopes (vase; C1, and monotone
/// between knots for the slopes chosen, so a knot with slope 0 is a true extremum).
class WallCurve {
public:
    struct Knot {
        double z, r, slope;
    };
    static WallCurve line(double r0, double slope)
    {
        WallCurve w;
        w.mLine = true;
        w.mR0 = r0;
        w.mSlope = slope;
        return w;
    }
    static WallCurve hermite(std::vector<Knot> knots)
    {
        WallCurve w;
        w.mKnots = std::move(knots);
        return w;
    }
    double r(double z) const { return eval(z)[0]; }
    double dr(double z) const { return eval(z)[1]; }
    double ddr(double z) const { return eval(z)[2]; }
    /// r, dr/dz and d²r/dz² at z (the end segments extended beyond the knots).
    std::array<double, 3> eval(double z) const
    {
        if (mLine) return {mR0 + mSlope * z, mSlope, 0.0};
        std::size_t k = std::size_t(std::upper_bound(mKnots.begin(), mKnots.end(), z,
                                                     [](double v, const Knot& n) { return v < n.z; }) -
                                    mKnots.begin());
        k = std::clamp<std::size_t>(k, 1, mKnots.size() - 1);
        const Knot& a = mKnots[k - 1];
        const Knot& b = mKnots[k];
        const double h = b.z - a.z, t = (z - a.z) / h;
        const double ma = a.slope * h, mb = b.slope * h;
        const double r = (2 * t * t * t - 3 * t * t + 1) * a.r + (t * t * t - 2 * t * t + t) * ma +
                         (-2 * t * t * t + 3 * t * t) * b.r + (t * t * t - t * t) * mb;
        const double d = ((6 * t * t - 6 * t) * a.r + (3 * t * t - 4 * t + 1) * ma + (-6 * t * t + 6 * t) * b.r +
                          (3 * t * t - 2 * t) * mb) / h;
        const double dd = ((12 * t - 6) * a.r + (6 * t - 4) * ma + (-12 * t + 6) * b.r + (6 * t - 2) * mb) / (h * h);
        return {r, d, dd};
    }

private:
    bool mLine = false;
    double mR0 = 0, mSlope = 0;
    std::vector<Knot> mKnots;
};

/// The outer wall of @p shape, scaled to end at zTop (where the lip begins).
WallCurve shapeWall(const VesselOptions& o, double zTop)
{
    switch (o.shape) {
    case VesselShape::Cylinder:
        return WallCurve::line(o.radius, 0.0);
    case VesselShape::Cone:
        return WallCurve::line(o.radius, (o.topRadius - o.radius) / zTop);
    case VesselShape::Vase:
        break;
    }
    // Foot, belly (the widest, slope 0), shoulder, neck (the narrowest, slope 0), flaring
    // rim: (share of zTop, share of the radius, slope in radius / zTop).
    static constexpr std::array<std::array<double, 3>, 5> kVase = {{
        {0.0, 0.55, 1.6}, {0.35, 1.0, 0.0}, {0.6, 0.72, -1.5}, {0.8, 0.45, 0.0}, {1.0, 0.6, 1.5}}};
    std::vector<WallCurve::Knot> knots;
    for (const auto& k : kVase) knots.push_back({k[0] * zTop, k[1] * o.radius, k[2] * o.radius / zTop});
    return WallCurve::hermite(std::move(knots));
}

/// The unit inward normal (towards the axis) of the graph r(z), from its slope.
RZ inwardNormal(double slope)
{
    const double l = std::sqrt(1 + slope * slope);
    return {-1 / l, slope / l};
}

// ---------------------------------------------------------------------------------------
// The profile loop
// ---------------------------------------------------------------------------------------

/// A closed profile loop as smooth pieces c(u), u in [u0, u1], each with its derivative and
/// a table of arc length, so that it can be sampled by arc length s along the whole loop.
/// Points are always evaluated on the true curves; only their spacing uses the table.
class ProfileLoop {
public:
    struct Piece {
        std::function<RZ(double)> point, derivative;
        double u0 = 0, u1 = 1;
    };
    /// A place on the loop: the point and the outward unit normal (to the right of the
    /// direction of travel; the material lies to the left).
    struct Place {
        RZ p, normal;
    };

    void add(Piece piece)
    {
        std::vector<double> table(kTableSamples + 1, 0.0);
        RZ previous = piece.point(piece.u0);
        for (int i = 1; i <= kTableSamples; ++i) {
            const RZ p = piece.point(parameterOf(piece, i));
            table[std::size_t(i)] = table[std::size_t(i - 1)] + magnitude(p - previous);
            previous = p;
        }
        if (mStart.empty()) mStart.push_back(0.0);
        mStart.push_back(mStart.back() + table.back());
        mPieces.push_back(std::move(piece));
        mTables.push_back(std::move(table));
    }
    double length() const { return mStart.back(); }
    std::size_t numPieces() const { return mPieces.size(); }
    double start(std::size_t piece) const { return mStart[piece]; }
    double end(std::size_t piece) const { return mStart[piece + 1]; }
    const Piece& piece(std::size_t k) const { return mPieces[k]; }

    /// The loop's arc length at parameter u of @p piece.
    double arcLength(std::size_t piece, double u) const
    {
        const Piece& c = mPieces[piece];
        const double x = std::clamp((u - c.u0) / (c.u1 - c.u0), 0.0, 1.0) * kTableSamples;
        const int i = std::min(int(x), kTableSamples - 1);
        const std::vector<double>& t = mTables[piece];
        return mStart[piece] + t[std::size_t(i)] + (x - i) * (t[std::size_t(i) + 1] - t[std::size_t(i)]);
    }
    /// The parameter of @p piece at loop arc length s (clamped to the piece).
    double parameter(std::size_t piece, double s) const
    {
        const Piece& c = mPieces[piece];
        const std::vector<double>& t = mTables[piece];
        const double local = std::clamp(s - mStart[piece], 0.0, t.back());
        const std::size_t i = std::min<std::size_t>(
            std::size_t(std::upper_bound(t.begin(), t.end(), local) - t.begin()), t.size() - 1);
        const double span = t[i] - t[i - 1];
        const double x = double(i - 1) + (span > 0 ? (local - t[i - 1]) / span : 0.0);
        return c.u0 + (c.u1 - c.u0) * (x / kTableSamples);
    }
    /// The piece at loop arc length s.
    std::size_t pieceAt(double s) const
    {
        const std::size_t k = std::size_t(std::upper_bound(mStart.begin(), mStart.end(), s) - mStart.begin());
        return std::clamp<std::size_t>(k, 1, mPieces.size()) - 1;
    }
    /// The place at loop arc length s; the loop's ends exactly (the poles on the axis).
    Place at(double s) const
    {
        const std::size_t k = pieceAt(s);
        const Piece& c = mPieces[k];
        const double u = s <= 0 ? c.u0 : s >= length() ? c.u1 : parameter(k, s);
        return placeOn(k, u);
    }
    Place placeOn(std::size_t k, double u) const
    {
        const Piece& c = mPieces[k];
        const RZ d = c.derivative(u);
        const double l = magnitude(d);
        return {c.point(u), {d.z / l, -d.r / l}};
    }
    /// Pieces [first, last) as one fine polyline (kVesselProfileTolerance).
    std::vector<std::array<double, 2>> polyline(std::size_t first, std::size_t last) const;
    /// The area of the surface the loop sweeps about the axis, 2π ∫ r ds.
    double revolvedArea() const
    {
        double area = 0;
        for (std::size_t k = 0; k < mPieces.size(); ++k) {
            RZ previous = mPieces[k].point(mPieces[k].u0);
            for (int i = 1; i <= kTableSamples; ++i) {
                const RZ p = mPieces[k].point(parameterOf(mPieces[k], i));
                area += kPi * (p.r + previous.r) * magnitude(p - previous);
                previous = p;
            }
        }
        return area;
    }

private:
    static double parameterOf(const Piece& c, int i)
    {
        return i == kTableSamples ? c.u1 : c.u0 + (c.u1 - c.u0) * (double(i) / kTableSamples);
    }
    std::vector<Piece> mPieces;
    std::vector<std::vector<double>> mTables;
    std::vector<double> mStart;
};

/// Appends the polyline of piece @p c between u0 and u1 (without its first point), halving
/// each interval until its middle lies within half the tolerance of the chord (the chord's
/// largest distance from a smooth arc is about that of its middle).
void refine(const ProfileLoop::Piece& c, double u0, RZ p0, double u1, RZ p1, int depth,
            std::vector<std::array<double, 2>>& out)
{
    const double um = 0.5 * (u0 + u1);
    const RZ pm = c.point(um);
    if (depth < 40 && distanceToSegment(pm, p0, p1) > 0.5 * kVesselProfileTolerance) {
        refine(c, u0, p0, um, pm, depth + 1, out);
        refine(c, um, pm, u1, p1, depth + 1, out);
        return;
    }
    out.push_back({p1.r, p1.z});
}

std::vector<std::array<double, 2>> ProfileLoop::polyline(std::size_t first, std::size_t last) const
{
    std::vector<std::array<double, 2>> out;
    for (std::size_t k = first; k < last; ++k) {
        const Piece& c = mPieces[k];
        RZ p = c.point(c.u0);
        if (out.empty()) out.push_back({p.r, p.z});
        // At least one interval per mm, so that no bend hides between two samples.
        const int n = std::max(4, int(std::ceil(end(k) - start(k))));
        for (int i = 1; i <= n; ++i) {
            const double ua = c.u0 + (c.u1 - c.u0) * (double(i - 1) / n);
            const double ub = i == n ? c.u1 : c.u0 + (c.u1 - c.u0) * (double(i) / n);
            const RZ q = c.point(ub);
            refine(c, ua, p, ub, q, 0, out);
            p = q;
        }
    }
    return out;
}

ProfileLoop::Piece linePiece(RZ a, RZ b)
{
    return {[a, b](double u) { return a + (b - a) * u; }, [a, b](double) { return b - a; }, 0.0, 1.0};
}

/// A circular arc about @p centre from angle phi0 to phi1 (counter-clockwise if phi1 > phi0).
ProfileLoop::Piece arcPiece(RZ centre, double radius, double phi0, double phi1)
{
    return {[=](double u) {
                const double phi = phi0 + (phi1 - phi0) * u;
                return centre + RZ{std::cos(phi), std::sin(phi)} * radius;
            },
            [=](double u) {
                const double phi = phi0 + (phi1 - phi0) * u;
                return RZ{-std::sin(phi), std::cos(phi)} * (radius * (phi1 - phi0));
            },
            0.0, 1.0};
}

/// The outer wall r(z) upwards, z from z0 to z1 (u = z).
ProfileLoop::Piece wallPiece(const WallCurve& w, double z0, double z1)
{
    return {[w](double z) { return RZ{w.r(z), z}; }, [w](double z) { return RZ{w.dr(z), 1.0}; }, z0, z1};
}

// ---------------------------------------------------------------------------------------
// Vessel and seal profiles
// ---------------------------------------------------------------------------------------

/// A profile to revolve: the loop, and its outer wall (the piece marks go on, a graph
/// r(z) with u = z) with the wall's thickness for a vessel.
struct Profile {
    ProfileLoop loop;
    WallCurve wall = WallCurve::line(1, 0);
    std::size_t wallPiece = 0;
    std::size_t outerEnd = 0;   ///< pieces [0, outerEnd): the outer profile (underside, foot, wall)
    std::size_t innerFrom = 0;  ///< pieces [innerFrom, end): the inner profile, reversed
    double zFrom = 0, zTo = 0;  ///< the outer wall's z range (zTo: where the lip begins)
    double thickness = 0;       ///< the vessel's wall; 0 for a seal
    double zInner = 0;          ///< outer-wall z whose inner point begins the base's inner rounding

    RZ outer(double z) const { return {wall.r(z), z}; }
    RZ normalIn(double z) const { return inwardNormal(wall.dr(z)); }
    /// The inner wall's point opposite the outer wall's point at z.
    RZ inner(double z) const { return outer(z) + normalIn(z) * thickness; }
};

/// The root of the increasing function f on [lo, hi] by bisection (f(lo) < 0 < f(hi)).
double bisect(const std::function<double(double)>& f, double lo, double hi)
{
    for (int i = 0; i < 200 && hi - lo > 1e-15 * std::max(1.0, std::abs(hi)); ++i) {
        const double mid = 0.5 * (lo + hi);
        (f(mid) < 0 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

/// The marks, spacing and noise of a vessel's or a seal's options.
template <class Options> void validateMarksAndSampling(const Options& o)
{
    requirePositive(o.markRadius, "mark radius");
    requireNonNegative(o.markDepth, "mark depth");
    requirePositive(o.spacing, "spacing");
    requireNonNegative(o.roughness, "roughness");
}

/// The options that make the mesh rather than the shape (vesselOuterRadius ignores them).
void validateSampling(const VesselOptions& o)
{
    validateMarksAndSampling(o);
    if (!(o.markDepth < o.wall / 2))
        throw InvalidInputError("sample mesh: the marks must be shallower than half the wall.");
    if (!(o.spacing <= o.wall / 2))
        throw InvalidInputError("sample mesh: the spacing (" + formatNumber(o.spacing) +
                                ") must be at most half the wall (" + formatNumber(o.wall) +
                                "), so that the rounded lip gets its rings.");
}

/// The options that make the shape.
void validate(const VesselOptions& o)
{
    requirePositive(o.height, "height");
    requirePositive(o.radius, "radius");
    if (o.shape == VesselShape::Cone) requirePositive(o.topRadius, "top radius");
    requirePositive(o.wall, "wall");
    requirePositive(o.base, "base");
    if (!(o.base <= o.height / 3))
        throw InvalidInputError("sample mesh: the base must be at most a third of the height.");
    const double narrowest = o.shape == VesselShape::Cylinder ? o.radius
                             : o.shape == VesselShape::Cone   ? std::min(o.radius, o.topRadius)
                                                              : 0.45 * o.radius;
    if (!(3 * o.wall <= narrowest))
        throw InvalidInputError("sample mesh: the wall (" + formatNumber(o.wall) +
                                ") must be at most a third of the vessel's narrowest radius (" +
                                formatNumber(narrowest) + ").");
}

/// zTop, where the outer wall meets the lip: the lip's top (its centre plus half the wall)
/// lies at the height. The wall's shape scales with zTop, hence a fixed point.
double lipStart(const VesselOptions& o)
{
    double zTop = o.height - o.wall / 2;
    for (int i = 0; i < 60; ++i) {
        const RZ n = inwardNormal(shapeWall(o, zTop).dr(zTop));
        zTop = o.height - o.wall / 2 - (o.wall / 2) * n.z;
    }
    return zTop;
}

/// Refuses walls whose inner offset (and that of the base's inner rounding) would fold:
/// 1 + (offset) · signed curvature must stay well above 0.
void checkCurvature(const Profile& g, double offset)
{
    for (int i = 0; i <= 4096; ++i) {
        const double z = g.zTo * i / 4096.0;
        const auto e = g.wall.eval(z);
        const double l = std::sqrt(1 + e[1] * e[1]);
        if (1 + offset * e[2] / (l * l * l) < 0.25)
            throw InvalidInputError("sample mesh: the wall (" + formatNumber(g.thickness) +
                                    ") is too thick for the profile's curvature near z = " + formatNumber(z) + ".");
    }
}

/// The centres of the foot's rounding (radius foot, tangent to z = 0 and to the outer wall
/// at g.zFrom) and of the base's inner rounding (radius inner, tangent to the inner wall at
/// the point opposite g.zInner and to z = base); sets zFrom and zInner.
/// @throw InvalidInputError where the wall and the base leave no room for them.
std::array<RZ, 2> roundCorners(Profile& g, double base, double foot, double inner)
{
    g.zFrom = bisect([&](double z) { return z + foot * g.normalIn(z).z - foot; }, 0.0, 0.5 * g.zTo);
    const RZ footCentre = g.outer(g.zFrom) + g.normalIn(g.zFrom) * foot;
    const auto innerCorner = [&](double z) { return g.inner(z).z + inner * g.normalIn(z).z - base - inner; };
    if (!(innerCorner(g.zFrom) < 0))
        throw InvalidInputError("sample mesh: the base (" + formatNumber(base) + ") is too thin for the wall.");
    g.zInner = bisect(innerCorner, g.zFrom, g.zTo);
    const RZ innerCentre = g.inner(g.zInner) + g.normalIn(g.zInner) * inner;
    if (!(footCentre.r > 0 && innerCentre.r > 0 && g.zInner < g.zTo - 2 * g.thickness))
        throw InvalidInputError("sample mesh: the wall and base leave no room inside the vessel.");
    for (int i = 0; i <= 1024; ++i)
        if (!(g.inner(g.zInner + (g.zTo - g.zInner) * i / 1024.0).r > g.thickness / 2))
            throw InvalidInputError("sample mesh: the wall leaves no room inside the vessel.");
    return {footCentre, innerCentre};
}

/// The inner wall downwards, u = −z of the outer wall's point opposite: the outer wall
/// offset by the thickness along its inward normal; its derivative is the outer wall's,
/// stretched by 1 + thickness · curvature.
ProfileLoop::Piece innerWallPiece(const WallCurve& wall, double thickness, double zTop, double zInner)
{
    return {[wall, thickness](double u) { return RZ{wall.r(-u), -u} + inwardNormal(wall.dr(-u)) * thickness; },
            [wall, thickness](double u) {
                const auto e = wall.eval(-u);
                const double l = std::sqrt(1 + e[1] * e[1]);
                const double stretch = 1 + thickness * e[2] / (l * l * l);
                return RZ{-e[1] * stretch, -stretch};
            },
            -zTop, -zInner};
}

/// The vessel's profile loop: base underside, foot rounding, outer wall, lip, inner wall,
/// the base's inner rounding, base top.
/// @throw InvalidInputError for invalid options.
Profile vesselProfile(const VesselOptions& o)
{
    validate(o);
    Profile g;
    g.zTo = lipStart(o);
    g.wall = shapeWall(o, g.zTo);
    g.thickness = o.wall;
    const double foot = kFootRounding * std::min(o.wall, o.base), inner = kInnerRounding * o.wall;
    checkCurvature(g, o.wall + inner);
    const auto [footCentre, innerCentre] = roundCorners(g, o.base, foot, inner);

    g.loop.add(linePiece({0, 0}, {footCentre.r, 0}));
    g.loop.add(arcPiece(footCentre, foot, -kPi / 2, std::atan2(-g.wall.dr(g.zFrom), 1.0)));
    g.wallPiece = g.loop.numPieces();
    g.loop.add(wallPiece(g.wall, g.zFrom, g.zTo));
    g.outerEnd = g.loop.numPieces();
    // The lip: a half circle from the outer wall's top over to the inner wall's.
    const RZ n = g.normalIn(g.zTo), t{n.z, -n.r};  // t: the wall's upward tangent
    const RZ lipCentre = g.outer(g.zTo) + n * (o.wall / 2);
    const double half = o.wall / 2;
    g.loop.add({[=](double phi) { return lipCentre - n * (half * std::cos(phi)) + t * (half * std::sin(phi)); },
                [=](double phi) { return n * (half * std::sin(phi)) + t * (half * std::cos(phi)); }, 0.0, kPi});
    g.innerFrom = g.loop.numPieces();
    g.loop.add(innerWallPiece(g.wall, o.wall, g.zTo, g.zInner));
    g.loop.add(arcPiece(innerCentre, inner, std::atan2(-g.wall.dr(g.zInner), 1.0), -kPi / 2));
    g.loop.add(linePiece({innerCentre.r, o.base}, {0, o.base}));
    return g;
}

/// The seal's outline: bottom, rounded edge, side, rounded edge, top.
Profile sealProfile(const SealOptions& o)
{
    requirePositive(o.radius, "radius");
    requirePositive(o.height, "height");
    validateMarksAndSampling(o);
    if (!(o.markDepth < o.radius / 4))
        throw InvalidInputError("sample mesh: the marks must be shallower than a quarter of the radius.");
    const double edge = kSealRounding * o.radius;
    if (!(o.height > 4 * edge)) throw InvalidInputError("sample mesh: the seal is too short for its radius.");
    Profile g;
    g.wall = WallCurve::line(o.radius, 0.0);
    g.zFrom = edge;
    g.zTo = o.height - edge;
    g.loop.add(linePiece({0, 0}, {o.radius - edge, 0}));
    g.loop.add(arcPiece({o.radius - edge, edge}, edge, -kPi / 2, 0));
    g.wallPiece = g.loop.numPieces();
    g.loop.add(wallPiece(g.wall, g.zFrom, g.zTo));
    g.loop.add(arcPiece({o.radius - edge, o.height - edge}, edge, 0, kPi / 2));
    g.loop.add(linePiece({o.radius - edge, o.height}, {0, o.height}));
    g.outerEnd = g.innerFrom = g.loop.numPieces();
    return g;
}

// ---------------------------------------------------------------------------------------
// Marks
// ---------------------------------------------------------------------------------------

/// A mark on the outer wall: its centre's arc length along the loop and angle.
struct Pit {
    double s, theta, radius, depth;
    VesselMarkPlace place;
};

/// The marks' depth at loop arc length s, angle theta, radius r: the deepest of the pits
/// d (1 − ρ²/R²)², ρ² = Δs² + (r Δθ)² (the distance on the surface, to first order).
double pitDepth(const std::vector<Pit>& pits, double s, double theta, double r)
{
    double depth = 0;
    for (const Pit& m : pits) {
        const double ds = s - m.s;
        if (!(std::abs(ds) < m.radius)) continue;
        const double across = r * std::remainder(theta - m.theta, 2 * kPi);
        const double q = (ds * ds + across * across) / (m.radius * m.radius);
        if (q < 1) depth = std::max(depth, m.depth * (1 - q) * (1 - q));
    }
    return depth;
}

/// @p count places every 360° / count around (jittered), at heights in [zLo, zHi] taken in
/// a shuffled order (3k mod count), so that marks vary in both and stay apart.
std::vector<VesselMarkPlace> spreadMarks(std::size_t count, std::uint64_t seed, double zLo, double zHi)
{
    std::vector<VesselMarkPlace> places;
    const std::size_t step = count % 3 == 0 ? 1 : 3;
    for (std::size_t k = 0; k < count; ++k) {
        const double u = signedUnit(hashKey(seed, kStreamMarkPlaces, k, 0));
        const double v = signedUnit(hashKey(seed, kStreamMarkPlaces, k, 1));
        const double level = double((step * k) % count);
        places.push_back({2 * kPi * (double(k) + 0.5 + 0.3 * u) / double(count),
                          zLo + (zHi - zLo) * (level + 0.5 + 0.3 * v) / double(count)});
    }
    return places;
}

/// The pits of @p places on the profile's outer wall (default places when empty).
/// @throw InvalidInputError for a mark that does not fit on the outer wall.
std::vector<Pit> wallPits(const Profile& g, std::vector<VesselMarkPlace> places, std::size_t count, double radius,
                          double depth, std::uint64_t seed)
{
    std::vector<Pit> pits;
    if (depth == 0) return pits;
    const double s0 = g.loop.start(g.wallPiece), s1 = g.loop.end(g.wallPiece);
    if (places.empty() && count > 0) {
        const double zLo = g.loop.parameter(g.wallPiece, s0 + 1.5 * radius);
        const double zHi = g.loop.parameter(g.wallPiece, s1 - 1.5 * radius);
        if (!(zLo < zHi)) throw InvalidInputError("sample mesh: the marks do not fit on the outer wall.");
        places = spreadMarks(count, seed, zLo, zHi);
    }
    for (const VesselMarkPlace& p : places) {
        const double s = g.loop.arcLength(g.wallPiece, p.height);
        if (!(std::isfinite(p.theta) && p.height > g.zFrom && p.height < g.zTo && s - radius >= s0 && s + radius <= s1))
            throw InvalidInputError("sample mesh: a mark at height " + formatNumber(p.height) +
                                    " does not fit on the outer wall (between z = " + formatNumber(g.zFrom) +
                                    " and " + formatNumber(g.zTo) + ", with its radius " + formatNumber(radius) + ").");
        pits.push_back({s, p.theta, radius, depth, p});
    }
    return pits;
}

/// The mark as made (before the pose).
VesselMark markOf(const Profile& g, const Pit& pit)
{
    VesselMark m;
    m.theta = pit.place.theta;
    m.height = pit.place.height;
    const RZ n = g.normalIn(m.height) * -1.0;
    m.centre = revolve(g.outer(m.height), m.theta);
    m.normal = revolve(n, m.theta);
    m.radius = pit.radius;
    m.depth = pit.depth;
    return m;
}

// ---------------------------------------------------------------------------------------
// Revolving: rings zipped together
// ---------------------------------------------------------------------------------------

/// Triangles between two closed rings, given by their first vertex and count (1 for a
/// pole) with the vertices' angles (increasing within a ring, spanning one turn): walks
/// both rings in the order of their angles. Ring a lies before ring b along the loop, so
/// (a_i, a_i+1, b_j) and (a_i, b_j+1, b_j) face outward. Writes count_a + count_b triangles
/// (a pole counts 0).
void zipRings(std::uint32_t a0, std::uint32_t na, std::uint32_t b0, std::uint32_t nb, const std::vector<double>& angle,
              Triangle* out)
{
    if (na == 1) {
        for (std::uint32_t j = 0; j < nb; ++j) *out++ = {a0, b0 + (j + 1) % nb, b0 + j};
        return;
    }
    if (nb == 1) {
        for (std::uint32_t i = 0; i < na; ++i) *out++ = {a0 + i, a0 + (i + 1) % na, b0};
        return;
    }
    // Periodic angle sequences: element k + m n has angle angle[k] + 2π m.
    const auto alpha = [&](std::int64_t i) {
        const std::int64_t m = i >= 0 ? i / na : -((-i + na - 1) / na);
        return angle[a0 + std::size_t(i - m * na)] + 2 * kPi * double(m);
    };
    const auto beta = [&](std::int64_t j) {
        const std::int64_t m = j >= 0 ? j / nb : -((-j + nb - 1) / nb);
        return angle[b0 + std::size_t(j - m * nb)] + 2 * kPi * double(m);
    };
    const auto vb = [&](std::int64_t j) { return b0 + std::uint32_t(((j % nb) + nb) % nb); };
    // Start at the b vertex just before a_0 in angle.
    std::int64_t j = 0;
    while (beta(j) > alpha(0)) --j;
    while (beta(j + 1) <= alpha(0)) ++j;
    std::int64_t i = 0;
    const std::int64_t jEnd = j + nb;
    while (i < na || j < jEnd) {
        const bool advanceA = j == jEnd || (i < na && alpha(i + 1) <= beta(j + 1));
        if (advanceA) {
            *out++ = {a0 + std::uint32_t(i % na), a0 + std::uint32_t((i + 1) % na), vb(j)};
            ++i;
        } else {
            *out++ = {a0 + std::uint32_t(i % na), vb(j + 1), vb(j)};
            ++j;
        }
    }
}

/// The revolved loop before marks and noise, with what those need per ring.
struct Revolved {
    TriMesh mesh;
    std::vector<double> angle;                 ///< per vertex
    std::vector<double> ringS;                 ///< per ring: loop arc length
    std::vector<ProfileLoop::Place> ringPlace;
    std::vector<std::uint32_t> ringFirst, ringCount;
};

/// Rings every ~spacing along the loop (moved by up to a quarter step along it), each of
/// max(8, 2πr / spacing) vertices at jittered angles from a random phase; poles at the ends.
Revolved placeRings(const ProfileLoop& loop, double spacing, std::uint64_t seed)
{
    requireVertexCount(1.2 * loop.revolvedArea() / (spacing * spacing));
    const double total = loop.length();
    const int rings = std::max(4, int(std::lround(total / spacing)));
    Revolved v;
    v.ringS.resize(std::size_t(rings) + 1);
    v.ringPlace.resize(v.ringS.size());
    v.ringFirst.resize(v.ringS.size());
    v.ringCount.resize(v.ringS.size());
    std::uint32_t first = 0;
    for (int k = 0; k <= rings; ++k) {
        const double jitter =
            k == 0 || k == rings ? 0.0 : kJitter * signedUnit(hashKey(seed, kStreamRingPlace, std::uint64_t(k)));
        const double s = k == 0 ? 0.0 : k == rings ? total : total * (k + jitter) / rings;
        const ProfileLoop::Place place = loop.at(s);
        const std::size_t r = std::size_t(k);
        v.ringS[r] = s;
        v.ringPlace[r] = place;
        v.ringCount[r] =
            k == 0 || k == rings ? 1 : std::uint32_t(std::max(8L, std::lround(2 * kPi * place.p.r / spacing)));
        v.ringFirst[r] = first;
        first += v.ringCount[r];
    }
    v.mesh.points.resize(first);
    v.angle.resize(first);
    return v;
}

Revolved revolveLoop(const ProfileLoop& loop, double spacing, std::uint64_t seed)
{
    Revolved v = placeRings(loop, spacing, seed);
    const std::size_t rings = v.ringS.size();
    tbb::parallel_for(std::size_t(0), rings, [&](std::size_t k) {
        const std::uint32_t n = v.ringCount[k], first = v.ringFirst[k];
        const RZ p = v.ringPlace[k].p;
        if (n == 1) {
            v.mesh.points[first] = {0.0, 0.0, p.z};
            v.angle[first] = 0;
            return;
        }
        const double phase = unitInterval(hashKey(seed, kStreamRingPhase, k));
        for (std::uint32_t i = 0; i < n; ++i) {
            const double jitter = kJitter * signedUnit(hashKey(seed, kStreamRingAngle, k, i));
            const double theta = 2 * kPi * (double(i) + phase + jitter) / double(n);
            v.angle[first + i] = theta;
            v.mesh.points[first + i] = revolve(p, theta);
        }
    });
    std::vector<std::size_t> offset(rings, 0);  // strip k joins rings k and k + 1
    for (std::size_t k = 0; k + 1 < rings; ++k) {
        const auto share = [&](std::size_t r) { return v.ringCount[r] == 1 ? 0 : std::size_t(v.ringCount[r]); };
        offset[k + 1] = offset[k] + share(k) + share(k + 1);
    }
    v.mesh.triangles.resize(offset[rings - 1]);
    tbb::parallel_for(std::size_t(0), rings - 1, [&](std::size_t k) {
        zipRings(v.ringFirst[k], v.ringCount[k], v.ringFirst[k + 1], v.ringCount[k + 1], v.angle,
                 v.mesh.triangles.data() + offset[k]);
    });
    return v;
}

/// Presses the pits into the rings and adds the roughness, along each vertex's normal.
void pressAndRoughen(Revolved& v, const std::vector<Pit>& pits, double roughness, std::uint64_t seed)
{
    tbb::parallel_for(std::size_t(0), v.ringS.size(), [&](std::size_t k) {
        const ProfileLoop::Place& place = v.ringPlace[k];
        bool near = false;
        for (const Pit& m : pits) near = near || std::abs(v.ringS[k] - m.s) < m.radius;
        if (!near && roughness == 0) return;
        for (std::uint32_t i = 0; i < v.ringCount[k]; ++i) {
            const std::uint32_t id = v.ringFirst[k] + i;
            const double theta = v.angle[id];
            double move = near ? -pitDepth(pits, v.ringS[k], theta, place.p.r) : 0.0;
            if (roughness > 0) move += roughness * signedUnit(hashKey(seed, kStreamSurfaceNoise, id));
            if (move != 0) v.mesh.points[id] += revolve(place.normal, theta) * move;
        }
    });
}

// ---------------------------------------------------------------------------------------
// Sherds
// ---------------------------------------------------------------------------------------

/// Seeded value noise in [-1, 1] (quintic fade, C2) of unit wavelength.
double valueNoise(std::uint64_t seed, std::uint64_t stream, double x, double y)
{
    const double ix = std::floor(x), iy = std::floor(y);
    const auto fade = [](double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); };
    const auto value = [&](double i, double j) {
        return signedUnit(hashKey(seed, stream, std::uint64_t(std::int64_t(i)), std::uint64_t(std::int64_t(j))));
    };
    const double sx = fade(x - ix), sy = fade(y - iy);
    const double v0 = value(ix, iy) + sx * (value(ix + 1, iy) - value(ix, iy));
    const double v1 = value(ix, iy + 1) + sx * (value(ix + 1, iy + 1) - value(ix, iy + 1));
    return v0 + sy * (v1 - v0);
}

/// A break's offset from its nominal place, mm, at x mm along it and y mm into the wall:
/// two octaves of value noise (wavelength 15 mm, up to 1.2 mm; 4 mm, up to 0.25 mm) and an
/// obliqueness varying along the break (the break leaning by up to 0.25 mm per mm through
/// the wall), 1.45 mm + 0.125 wall at most (< breakReach). Its slope along the break stays
/// below ~0.6 (value noise of amplitude A and wavelength λ rises at most 3.75 A / λ), so
/// the warped cube cannot fold.
double breakOffset(std::uint64_t seed, int which, double wall, double x, double y)
{
    const std::uint64_t s = kStreamBreak + 4 * std::uint64_t(which);
    return 1.2 * valueNoise(seed, s, x / 15, y / 15) + 0.25 * valueNoise(seed, s + 1, x / 4, y / 4) +
           0.25 * (y - wall / 2) * valueNoise(seed, s + 2, x / 20, 0.5);
}

/// The sherd as a warped cube: a in [0, 1] around the axis (θ), b in [0, 1] up the outer
/// wall (its arc length v), c in [0, 1] through the wall along the profile's normal. The
/// faces c = 0 and c = 1 lie on the true outer and inner wall; b = 0, 1 are the breaks
/// across the wall, each moved along it by its breakOffset over (a, c); a = 0, 1 are the
/// breaks around, each moved around the axis by its offset over the section's plane (a
/// function of the point's (r, z), so that it stays a gentle graph over the section even
/// where a rim sherd's section, with the lip on top, squeezes the cube's corners); each
/// offset is blended linearly across the cube, so the map stays smooth and one-to-one. On a
/// rim sherd b = 1 is the lip, blended in over the top `wall` of the piece.
class SherdMap {
public:
    struct Coords {
        double theta, v;
        RZ s;  ///< the point in the section's half-plane
    };
    SherdMap(const Profile& g, const SherdOptions& o, double v0, double v1)
        : mG(g), mSeed(o.vessel.seed), mRim(o.rim), mWall(o.vessel.wall), mTheta0(o.theta0),
          mAlpha(o.angle * kPi / 180), mV0(v0), mDv(v1 - v0), mTopV(v1)
    {
        mBottomLength = mAlpha * g.wall.r(z(v0));
        mTopLength = mAlpha * g.wall.r(z(v1));
        const RZ top = g.outer(g.zTo);
        mLipNormal = g.normalIn(g.zTo);
        mLipCentre = top + mLipNormal * (mWall / 2);
    }
    /// The outer wall's z at arc length v along it.
    double z(double v) const { return mG.loop.parameter(mG.wallPiece, mG.loop.start(mG.wallPiece) + v); }
    Coords coords(double a, double b, double c) const
    {
        const double y = c * mWall;
        const double bottom = breakOffset(mSeed, 2, mWall, a * mBottomLength, y);
        const double top = mRim ? 0.0 : breakOffset(mSeed, 3, mWall, a * mTopLength, y);
        const double v = mV0 + b * mDv + (1 - b) * bottom + b * top;
        const RZ s = section(v, c);
        const double around = (1 - a) * sideOffset(0, s) + a * sideOffset(1, s);
        return {mTheta0 + mAlpha * a + around / s.r, v, s};
    }
    /// The section point at arc length v and depth c.
    RZ section(double v, double c) const
    {
        const double zv = z(v);
        RZ s = mG.outer(zv) + mG.normalIn(zv) * (c * mWall);
        if (mRim && c > 0 && c < 1) {
            const double blend = std::clamp((v - (mTopV - mWall)) / mWall, 0.0, 1.0);
            if (blend > 0) s = s + lipBump(c) * (blend * blend * (3 - 2 * blend));
        }
        return s;
    }
    Vec3 point(double a, double b, double c) const
    {
        const Coords k = coords(a, b, c);
        return revolve(k.s, k.theta);
    }
    double theta0() const { return mTheta0; }
    double alpha() const { return mAlpha; }
    double v0() const { return mV0; }
    double dv() const { return mDv; }

private:
    /// The offset of break @p which around the axis (mm) at the section point s: as
    /// breakOffset, its obliqueness across the wall measured from the wall's middle at the
    /// point's height (the lip's centre above the lip's start).
    double sideOffset(int which, RZ s) const
    {
        const std::uint64_t stream = kStreamBreak + 4 * std::uint64_t(which);
        const double zc = std::min(s.z, mG.zTo);
        const double middle = mG.outer(zc).r + mG.normalIn(zc).r * (mWall / 2);
        return 1.2 * valueNoise(mSeed, stream, s.r / 15, s.z / 15) +
               0.25 * valueNoise(mSeed, stream + 1, s.r / 4, s.z / 4) +
               0.25 * (s.r - middle) * valueNoise(mSeed, stream + 2, zc / 20, 0.5);
    }
    /// The lip's point at depth c less the straight section's at the lip's start.
    RZ lipBump(double c) const
    {
        const double half = mWall / 2, phi = kPi * c;
        const RZ t{mLipNormal.z, -mLipNormal.r};
        const RZ lip = mLipCentre - mLipNormal * (half * std::cos(phi)) + t * (half * std::sin(phi));
        return lip - (mG.outer(mG.zTo) + mLipNormal * (c * mWall));
    }
    const Profile& mG;
    std::uint64_t mSeed;
    bool mRim;
    double mWall, mTheta0, mAlpha, mV0, mDv, mTopV, mBottomLength = 0, mTopLength = 0;
    RZ mLipNormal, mLipCentre;
};

/// The sherd's lattice: rows of vertices around the axis (a from 0 to 1) at the points
/// (b, c) of the section's loop (up the outer wall, across the top, down the inner wall,
/// across the bottom), zipped together, and the two end breaks (a = 0, 1) as jittered
/// (nw + 1) × (nv + 1) grids whose borders are the rows' first and last vertices.
struct SherdLattice {
    struct Row {
        double b, c;
        std::uint32_t first, count;  ///< vertices first .. first + count (count segments)
    };
    int nv = 2, nw = 2;
    std::vector<double> b, c;  ///< the rows' places along and through the wall
    std::vector<Row> rows;
    std::array<std::uint32_t, 2> capBase{};
    std::uint32_t numPoints = 0;

    /// Vertex (i along c, j along b) of end break @p cap.
    std::uint32_t capIndex(int cap, int i, int j) const
    {
        std::size_t row;
        if (i == 0) row = std::size_t(j);
        else if (i == nw) row = std::size_t(nv + nw + (nv - j));
        else if (j == 0) row = std::size_t(2 * nv + nw + (nw - i));
        else if (j == nv) row = std::size_t(nv + i);
        else return capBase[std::size_t(cap)] + std::uint32_t((j - 1) * (nw - 1) + (i - 1));
        return cap == 0 ? rows[row].first : rows[row].first + rows[row].count;
    }
};

/// Row places 0, ~1/n, ..., 1, the inner ones moved by up to 0.15 of a step.
std::vector<double> rowPlaces(int n, std::uint64_t seed, std::uint64_t which)
{
    std::vector<double> at(std::size_t(n) + 1);
    for (int k = 0; k <= n; ++k)
        at[std::size_t(k)] =
            k == 0   ? 0.0
            : k == n ? 1.0
                     : (k + 0.15 * signedUnit(hashKey(seed, kStreamSherdRows, which, std::uint64_t(k)))) / n;
    return at;
}

SherdLattice sherdLattice(const SherdMap& map, const SherdOptions& o)
{
    const double spacing = o.vessel.spacing, wall = o.vessel.wall;
    SherdLattice L;
    L.nv = std::max(2, int(std::lround(map.dv() / spacing)));
    L.nw = std::max(2, int(std::lround((o.rim ? std::max(wall, kPi * wall / 2) : wall) / spacing)));
    L.b = rowPlaces(L.nv, o.vessel.seed, 0);
    L.c = rowPlaces(L.nw, o.vessel.seed, 1);
    const auto add = [&](double b, double c) {
        const Vec3 mid = map.point(0.5, b, c);
        const double arc = map.alpha() * std::hypot(mid.x, mid.y);
        L.rows.push_back({b, c, 0, std::uint32_t(std::max(2L, std::lround(arc / spacing)))});
    };
    const std::size_t nv = std::size_t(L.nv), nw = std::size_t(L.nw);
    for (std::size_t k = 0; k <= nv; ++k) add(L.b[k], 0.0);
    for (std::size_t j = 1; j < nw; ++j) add(1.0, L.c[j]);
    for (std::size_t k = nv + 1; k-- > 0;) add(L.b[k], 1.0);
    for (std::size_t j = nw - 1; j > 0; --j) add(0.0, L.c[j]);
    double total = 0;
    for (SherdLattice::Row& r : L.rows) total += r.count + 1.0;
    requireVertexCount(total + 2.0 * double(nv) * double(nw));
    for (SherdLattice::Row& r : L.rows) {
        r.first = L.numPoints;
        L.numPoints += r.count + 1;
    }
    for (std::size_t cap = 0; cap < 2; ++cap) {
        L.capBase[cap] = L.numPoints;
        L.numPoints += std::uint32_t((nv - 1) * (nw - 1));
    }
    return L;
}

/// A vertex's place in the sherd's cube.
using CubePlace = std::array<double, 3>;

/// The sherd's points (a row's vertices at jittered a, the end breaks' inner lattice
/// jittered by up to 0.09 of a step each way) and, per vertex, its place in the cube.
void sherdPoints(const SherdMap& map, const SherdLattice& L, std::uint64_t seed, TriMesh& mesh,
                 std::vector<CubePlace>& place)
{
    mesh.points.resize(L.numPoints);
    place.assign(L.numPoints, CubePlace{});
    tbb::parallel_for(std::size_t(0), L.rows.size(), [&](std::size_t r) {
        const SherdLattice::Row& row = L.rows[r];
        for (std::uint32_t i = 0; i <= row.count; ++i) {
            const double a = i == 0 ? 0.0 : i == row.count ? 1.0
                : (i + kJitter * signedUnit(hashKey(seed, kStreamSherdAngle, r, i))) / row.count;
            place[row.first + i] = {a, row.b, row.c};
            mesh.points[row.first + i] = map.point(a, row.b, row.c);
        }
    });
    const int nv = L.nv, nw = L.nw;
    tbb::parallel_for(1, nv, [&](int j) {
        for (int cap = 0; cap < 2; ++cap)
            for (int i = 1; i < nw; ++i) {
                const std::uint32_t id = L.capIndex(cap, i, j);
                const std::uint64_t h = hashKey(seed, kStreamCapJitter, id);
                const double db = 0.09 * signedUnit(h) / nv, dc = 0.09 * signedUnit(mix64(h)) / nw;
                place[id] = {double(cap), L.b[std::size_t(j)] + db, L.c[std::size_t(i)] + dc};
                mesh.points[id] = map.point(place[id][0], place[id][1], place[id][2]);
            }
    });
}

/// Triangles between two open rows (na and nb segments) at increasing a from 0 to 1, walked
/// in the order of a; na + nb triangles facing like zipRings'.
void zipRows(std::uint32_t a0, std::uint32_t na, std::uint32_t b0, std::uint32_t nb,
             const std::vector<CubePlace>& place, Triangle* out)
{
    std::uint32_t i = 0, j = 0;
    while (i < na || j < nb) {
        if (j == nb || (i < na && place[a0 + i + 1][0] <= place[b0 + j + 1][0])) {
            *out++ = {a0 + i, a0 + i + 1, b0 + j};
            ++i;
        } else {
            *out++ = {a0 + i, b0 + j + 1, b0 + j};
            ++j;
        }
    }
}

void sherdTriangles(const SherdLattice& L, const std::vector<CubePlace>& place, std::uint64_t seed, TriMesh& mesh)
{
    const std::size_t rows = L.rows.size();
    std::vector<std::size_t> offset(rows + 1, 0);
    for (std::size_t r = 0; r < rows; ++r) offset[r + 1] = offset[r] + L.rows[r].count + L.rows[(r + 1) % rows].count;
    const std::size_t capTriangles = 2 * std::size_t(L.nv) * std::size_t(L.nw);
    mesh.triangles.resize(offset[rows] + 2 * capTriangles);
    tbb::parallel_for(std::size_t(0), rows, [&](std::size_t r) {
        const SherdLattice::Row &a = L.rows[r], &b = L.rows[(r + 1) % rows];
        zipRows(a.first, a.count, b.first, b.count, place, mesh.triangles.data() + offset[r]);
    });
    // The grid's (i, j) run along c (inwards) and b (upwards): counter-clockwise in them
    // faces +θ, out of the end a = 1; the start a = 0 is reversed.
    for (int cap = 0; cap < 2; ++cap) {
        const auto index = [&](int i, int j) { return L.capIndex(cap, i, j); };
        triangulateGrid(mesh.points, L.nw, L.nv, index, seed, kStreamCapDiagonal + std::uint64_t(cap), cap == 0,
                        mesh.triangles.data() + offset[rows] + std::size_t(cap) * capTriangles);
    }
}

/// Area-weighted vertex normals, summed in triangle order (independent of the threads).
std::vector<Vec3> vertexNormals(const TriMesh& mesh)
{
    std::vector<Vec3> normals(mesh.numVertices(), Vec3{});
    for (const Triangle& t : mesh.triangles) {
        const Vec3 n = cross(mesh.points[t[1]] - mesh.points[t[0]], mesh.points[t[2]] - mesh.points[t[0]]);
        for (std::uint32_t v : t) normals[v] += n;
    }
    for (Vec3& n : normals) n = normalized(n);
    return normals;
}

/// Presses the pits into the outer wall, the wall under them giving way evenly down to the
/// inner wall (a vertex at depth c moves by (1 − c) of the pit's depth above it, so the
/// breaks through a mark show its dent), and adds the roughness along the mesh's normals.
void sherdSurface(const SherdMap& map, const Profile& g, const std::vector<Pit>& pits, double roughness,
                  std::uint64_t seed, const std::vector<CubePlace>& place, TriMesh& mesh)
{
    const double s0 = g.loop.start(g.wallPiece);
    if (!pits.empty())
        tbb::parallel_for(std::size_t(0), mesh.points.size(), [&](std::size_t id) {
            const CubePlace& k = place[id];
            const SherdMap::Coords at = map.coords(k[0], k[1], k[2]);
            const double zv = map.z(at.v);
            const double depth = pitDepth(pits, s0 + at.v, at.theta, g.wall.r(zv)) * (1 - k[2]);
            if (depth > 0) mesh.points[id] += revolve(g.normalIn(zv), at.theta) * depth;
        });
    if (roughness == 0) return;
    const std::vector<Vec3> normals = vertexNormals(mesh);
    tbb::parallel_for(std::size_t(0), mesh.points.size(), [&](std::size_t id) {
        mesh.points[id] += normals[id] * (roughness * signedUnit(hashKey(seed, kStreamSurfaceNoise, id)));
    });
}

/// Whether the outer wall's point (θ, v) lies on the piece: the cube's (a, b) there found by
/// Newton's method on the (nearly affine) map, inside when both lie in (0, 1).
bool onPiece(const SherdMap& map, double theta, double v)
{
    const double turn = std::remainder(theta - map.theta0() - map.alpha() / 2, 2 * kPi) + map.alpha() / 2;
    double a = turn / map.alpha(), b = (v - map.v0()) / map.dv();
    const auto residual = [&](double x, double y) {
        const SherdMap::Coords k = map.coords(x, y, 0.0);
        return std::array<double, 2>{std::remainder(k.theta - theta, 2 * kPi), k.v - v};
    };
    for (int step = 0; step < 30; ++step) {
        const auto f = residual(a, b);
        const double h = 1e-6;
        const auto fa = residual(a + h, b), fb = residual(a, b + h);
        const double j00 = (fa[0] - f[0]) / h, j10 = (fa[1] - f[1]) / h, j01 = (fb[0] - f[0]) / h,
                     j11 = (fb[1] - f[1]) / h;
        const double det = j00 * j11 - j01 * j10;
        if (!(std::abs(det) > 0)) break;
        a -= (j11 * f[0] - j01 * f[1]) / det;
        b -= (-j10 * f[0] + j00 * f[1]) / det;
    }
    return a > 0 && a < 1 && b > 0 && b < 1;
}

/// The piece's extent in z: for fixed (a, c) z rises with b, so its lowest point lies on
/// the bottom break and its highest on the top break (a rim sherd's: the lip's top).
std::array<double, 2> sherdExtent(const SherdMap& map, const SherdOptions& o)
{
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int i = 0; i <= 1024; ++i)
        for (int j = 0; j <= 32; ++j) {
            const double a = i / 1024.0, c = j / 32.0;
            lo = std::min(lo, map.point(a, 0.0, c).z);
            hi = std::max(hi, map.point(a, 1.0, c).z);
        }
    return {lo, o.rim ? o.vessel.height : hi};
}

/// The piece's range of the outer wall's arc length.
/// @throw InvalidInputError for an angle or heights that do not fit on the wall.
std::array<double, 2> sherdRange(const Profile& g, const SherdOptions& o)
{
    if (!(o.angle > 0 && o.angle <= 180))
        throw InvalidInputError("sample mesh: a sherd's angle must be in (0, 180] degrees.");
    if (!std::isfinite(o.theta0)) throw InvalidInputError("sample mesh: a sherd's start angle must be finite.");
    if (!std::isfinite(o.fromHeight) || (!o.rim && !std::isfinite(o.toHeight)))
        throw InvalidInputError("sample mesh: a sherd's heights must be finite.");
    const double s0 = g.loop.start(g.wallPiece);
    const double zLow = std::max(g.zFrom, g.zInner);
    const double vLow = g.loop.arcLength(g.wallPiece, zLow) - s0, vTop = g.loop.end(g.wallPiece) - s0;
    const double v0 = g.loop.arcLength(g.wallPiece, std::clamp(o.fromHeight, g.zFrom, g.zTo)) - s0;
    const double v1 = o.rim ? vTop : g.loop.arcLength(g.wallPiece, std::clamp(o.toHeight, g.zFrom, g.zTo)) - s0;
    const double reach = breakReach(o.vessel.wall);
    const double zHigh = g.loop.parameter(g.wallPiece, g.loop.end(g.wallPiece) - reach);
    if (!(o.fromHeight >= g.zFrom && v0 - reach >= vLow))
        throw InvalidInputError(
            "sample mesh: a sherd must start above the base's inner corner and its breaks' wander (from z = " +
            formatNumber(g.loop.parameter(g.wallPiece, s0 + vLow + reach)) + ").");
    if (!o.rim && !(o.toHeight <= g.zTo && v1 + reach <= vTop))
        throw InvalidInputError(
            "sample mesh: a sherd without rim must end below the lip and its breaks' wander (up to z = " +
            formatNumber(zHigh) + "), or take the rim.");
    if (!(v1 - v0 >= 2 * reach + (o.rim ? o.vessel.wall : 1.0)))
        throw InvalidInputError("sample mesh: a sherd's height range is too small for its breaks.");
    double narrowest = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= 256; ++i)
        narrowest = std::min(narrowest, g.inner(g.loop.parameter(g.wallPiece, s0 + v0 + (v1 - v0) * i / 256.0)).r);
    if (!(o.angle * kPi / 180 * narrowest >= 4 * reach))
        throw InvalidInputError("sample mesh: a sherd's angle is too small for its breaks at that radius.");
    return {v0, v1};
}

// ---------------------------------------------------------------------------------------
// Pose and truth
// ---------------------------------------------------------------------------------------

/// A rotation (matrix rows) and a translation.
struct RigidMotion {
    std::array<Vec3, 3> rows{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    Vec3 shift{};
    Vec3 rotate(const Vec3& v) const { return {dot(rows[0], v), dot(rows[1], v), dot(rows[2], v)}; }
    Vec3 operator()(const Vec3& p) const { return rotate(p) + shift; }
};

/// A rotation uniform over all rotations (a uniform unit quaternion, Shoemake's method) and
/// a translation uniform in the ball of radius 1000 mm.
RigidMotion poseMotion(std::uint64_t poseSeed)
{
    const auto u = [&](std::uint64_t k) { return unitInterval(hashKey(poseSeed, kStreamPose, k)); };
    const double u1 = u(0), u2 = u(1), u3 = u(2);
    const double x = std::sqrt(1 - u1) * std::sin(2 * kPi * u2), y = std::sqrt(1 - u1) * std::cos(2 * kPi * u2);
    const double z = std::sqrt(u1) * std::sin(2 * kPi * u3), w = std::sqrt(u1) * std::cos(2 * kPi * u3);
    RigidMotion m;
    m.rows = {{{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
               {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
               {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}}};
    for (std::uint64_t attempt = 0;; ++attempt) {
        const Vec3 t{2 * u(3 + 3 * attempt) - 1, 2 * u(4 + 3 * attempt) - 1, 2 * u(5 + 3 * attempt) - 1};
        if (squaredNorm(t) <= 1) {
            m.shift = t * 1000.0;
            return m;
        }
    }
}

void applyPose(Vessel& v, std::uint64_t poseSeed)
{
    if (poseSeed == 0) return;
    const RigidMotion m = poseMotion(poseSeed);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, v.mesh.points.size(), 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) v.mesh.points[i] = m(v.mesh.points[i]);
                      });
    for (VesselMark& mark : v.marks) {
        mark.centre = m(mark.centre);
        mark.normal = m.rotate(mark.normal);
    }
    v.axisPoint = m(v.axisPoint);
    v.axisDirection = m.rotate(v.axisDirection);
}

/// The profiles of @p g into @p v (inner reversed: from the base's centre upwards).
void setProfiles(Vessel& v, const Profile& g)
{
    const std::size_t pieces = g.loop.numPieces();
    v.outerProfile = g.loop.polyline(0, g.outerEnd);
    if (g.thickness > 0) {
        v.innerProfile = g.loop.polyline(g.innerFrom, pieces);
        std::reverse(v.innerProfile.begin(), v.innerProfile.end());
    }
    v.section = g.loop.polyline(0, pieces);
}

/// A revolved profile with its marks, noise and pose.
Vessel revolvedObject(const Profile& g, const std::vector<Pit>& pits, double spacing, double roughness,
                      std::uint64_t seed, std::uint64_t poseSeed)
{
    Revolved surface = revolveLoop(g.loop, spacing, seed);
    pressAndRoughen(surface, pits, roughness, seed);
    Vessel v;
    v.mesh = std::move(surface.mesh);
    for (const Pit& p : pits) v.marks.push_back(markOf(g, p));
    setProfiles(v, g);
    v.axisPoint = {0, 0, 0};
    v.axisDirection = {0, 0, 1};
    applyPose(v, poseSeed);
    return v;
}

} // namespace

const char* vesselShapeName(VesselShape shape)
{
    switch (shape) {
    case VesselShape::Cylinder:
        return "cylinder";
    case VesselShape::Cone:
        return "cone";
    case VesselShape::Vase:
        break;
    }
    return "vase";
}

Vessel makeVessel(const VesselOptions& o)
{
    const Profile g = vesselProfile(o);
    validateSampling(o);
    const std::vector<Pit> pits = wallPits(g, o.marks, o.markCount, o.markRadius, o.markDepth, o.seed);
    Vessel v = revolvedObject(g, pits, o.spacing, o.roughness, o.seed, o.poseSeed);
    v.rimDiameter = 2 * g.wall.r(g.zTo);
    v.height = o.height;
    return v;
}

double vesselOuterRadius(const VesselOptions& o, double z)
{
    const Profile g = vesselProfile(o);
    if (!(z >= 0 && z <= g.zTo)) return std::numeric_limits<double>::quiet_NaN();
    if (z >= g.zFrom) return g.wall.r(z);
    // The foot's rounding: the circle about its centre, on its outer side.
    const double foot = kFootRounding * std::min(o.wall, o.base);
    const RZ centre = g.outer(g.zFrom) + g.normalIn(g.zFrom) * foot;
    const double dz = z - centre.z;
    return centre.r + std::sqrt(std::max(0.0, foot * foot - dz * dz));
}

Vessel makeSherd(const SherdOptions& o)
{
    const Profile g = vesselProfile(o.vessel);
    validateSampling(o.vessel);
    const std::array<double, 2> range = sherdRange(g, o);
    const VesselOptions& vo = o.vessel;
    const std::vector<Pit> pits = wallPits(g, vo.marks, vo.markCount, vo.markRadius, vo.markDepth, vo.seed);
    const SherdMap map(g, o, range[0], range[1]);
    const SherdLattice lattice = sherdLattice(map, o);
    Vessel v;
    std::vector<CubePlace> place;
    sherdPoints(map, lattice, vo.seed, v.mesh, place);
    sherdTriangles(lattice, place, vo.seed, v.mesh);
    sherdSurface(map, g, pits, vo.roughness, vo.seed, place, v.mesh);
    const double s0 = g.loop.start(g.wallPiece);
    for (const Pit& p : pits)
        if (onPiece(map, p.theta, p.s - s0)) v.marks.push_back(markOf(g, p));
    setProfiles(v, g);
    const std::array<double, 2> extent = sherdExtent(map, o);
    v.height = extent[1] - extent[0];
    v.rimDiameter = o.rim ? 2 * g.wall.r(g.zTo) : 0.0;
    v.axisPoint = {0, 0, 0};
    v.axisDirection = {0, 0, 1};
    applyPose(v, vo.poseSeed);
    return v;
}

Vessel makeCylinderSeal(const SealOptions& o)
{
    const Profile g = sealProfile(o);
    const std::vector<Pit> pits = wallPits(g, o.marks, o.markCount, o.markRadius, o.markDepth, o.seed);
    Vessel v = revolvedObject(g, pits, o.spacing, o.roughness, o.seed, o.poseSeed);
    v.height = o.height;
    return v;
}

} // namespace msii::samples
