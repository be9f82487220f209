#include <msii/terrain/height_field.h>

#include <msii/core/errors.h>
#include <msii/core/stopwatch.h>
#include <msii/invariants/scales.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace msii {
namespace {

constexpr double kPi = 3.14159265358979323846;
/// The pieces of S's discs are this many times finer per axis than V's: S divides the
/// difference of two sums by 2δ (heightFieldSphereStep), which carries their error with it.
constexpr int kSpherePieceFactor = 2;
/// Pieces of cells across a disc's radius, at least: fewer, and the pieces' heights (their
/// centres') miss the terrain's bends within them (docs/method.md, Height fields).
constexpr double kDiscPieces = 40;

/// ∫ from y0 to y1 of √(a² − y²) dy (|y0|, |y1| <= a): ½(y √(a² − y²) + a² asin(y/a)).
double chordIntegral(double a2, double y0, double y1)
{
    const double a = std::sqrt(a2);
    const auto f = [&](double y) {
        const double t = std::clamp(y / a, -1.0, 1.0);
        return 0.5 * (y * std::sqrt(std::max(0.0, a2 - y * y)) + a2 * std::asin(t));
    };
    return f(y1) - f(y0);
}

/// What the column x adds to a cell's A and H: the length of [y0, y1] within the disc,
/// and the integral of h over it.
struct Column {
    double length = 0, integral = 0;
};
Column columnAt(double r2, double x, double y0, double y1)
{
    const double a2 = r2 - x * x;
    if (!(a2 > 0)) return {};
    const double a = std::sqrt(a2), lo = std::max(y0, -a), hi = std::min(y1, a);
    if (!(hi > lo)) return {};
    return {hi - lo, chordIntegral(a2, lo, hi)};
}

/// ∫ from x0 to x1 of columnAt by adaptive Simpson's rule (the integrand has square-root
/// ends where the disc's rim crosses the cell).
struct Simpson {
    double r2, y0, y1, tolerance;
    Column operator()(double x0, double x1) const
    {
        const Column f0 = columnAt(r2, x0, y0, y1), f1 = columnAt(r2, x1, y0, y1),
                     fm = columnAt(r2, 0.5 * (x0 + x1), y0, y1);
        return refine(x0, x1, f0, fm, f1, whole(x0, x1, f0, fm, f1), 0);
    }

private:
    static Column whole(double x0, double x1, const Column& f0, const Column& fm, const Column& f1)
    {
        const double w = (x1 - x0) / 6;
        return {w * (f0.length + 4 * fm.length + f1.length), w * (f0.integral + 4 * fm.integral + f1.integral)};
    }
    Column refine(double x0, double x1, const Column& f0, const Column& fm, const Column& f1, const Column& estimate,
                  int depth) const
    {
        const double xm = 0.5 * (x0 + x1);
        const Column fl = columnAt(r2, 0.5 * (x0 + xm), y0, y1), fr = columnAt(r2, 0.5 * (xm + x1), y0, y1);
        const Column left = whole(x0, xm, f0, fl, fm), right = whole(xm, x1, fm, fr, f1);
        const double change = std::abs(left.integral + right.integral - estimate.integral) +
                              std::abs(left.length + right.length - estimate.length);
        if (depth >= 24 || change <= 15 * tolerance)
            return {left.length + right.length + (left.length + right.length - estimate.length) / 15,
                    left.integral + right.integral + (left.integral + right.integral - estimate.integral) / 15};
        const Column a = refine(x0, xm, f0, fl, fm, left, depth + 1), b = refine(xm, x1, fm, fr, f1, right, depth + 1);
        return {a.length + b.length, a.integral + b.integral};
    }
};

} // namespace

int discSplit(double r, double cellWidth, double cellHeight)
{
    const double cell = std::max(cellWidth, cellHeight);
    return 2 * std::max(1, int(std::ceil(0.5 * kDiscPieces * cell / r)));  // even: pieces of 2 × 2
}

namespace {

/// [x0, x1] clipped to the disc of radius² @p r2 and split at the columns where its rim
/// crosses y0 or y1, ascending in @p cuts: each part is smooth inside and square-root-like
/// at most at its ends. Returns the number of ends (2 to 6).
int rimCuts(double r2, double x0, double x1, double y0, double y1, double (&cuts)[6])
{
    x0 = std::max(x0, -std::sqrt(r2)), x1 = std::min(x1, std::sqrt(r2));
    cuts[0] = x0, cuts[1] = x1;
    int n = 2;
    for (const double y : {y0, y1})
        if (y * y < r2)
            for (const double sign : {-1.0, 1.0}) {
                const double x = sign * std::sqrt(r2 - y * y);
                if (x > x0 && x < x1 && n < 6) cuts[n++] = x;
            }
    for (int i = 1; i < n; ++i)  // insertion sort of at most six
        for (int k = i; k > 0 && cuts[k] < cuts[k - 1]; --k) std::swap(cuts[k], cuts[k - 1]);
    return n;
}

/// The area of [x0, x1] × [y0, y1] inside the disc of radius² @p r2 about the origin, and the
/// integral of h over it.
Column inDisc(double r2, double x0, double x1, double y0, double y1)
{
    const double nearX = x0 > 0 ? x0 : (x1 < 0 ? -x1 : 0), nearY = y0 > 0 ? y0 : (y1 < 0 ? -y1 : 0);
    if (nearX * nearX + nearY * nearY >= r2) return {};
    double cuts[6];
    const int n = rimCuts(r2, x0, x1, y0, y1, cuts);
    x0 = cuts[0], x1 = cuts[n - 1];
    const Simpson simpson{r2, y0, y1, 1e-9 * (x1 - x0) * (y1 - y0) * std::sqrt(r2)};
    Column total;
    for (int k = 0; k + 1 < n; ++k) {
        const Column part = simpson(cuts[k], cuts[k + 1]);
        total.length += part.length, total.integral += part.integral;
    }
    return total;
}

/// The area of [x0, x1] × [y0, y1] inside the disc of radius² @p r2 about the origin, in closed
/// form: between the columns where the rim crosses y0 or y1, the column's length inside is
/// (y1 or √(r² − x²)) − (y0 or −√(r² − x²)), and ∫ √(r² − x²) dx = chordIntegral.
double areaInDisc(double r2, double x0, double x1, double y0, double y1)
{
    const double nearX = x0 > 0 ? x0 : (x1 < 0 ? -x1 : 0), nearY = y0 > 0 ? y0 : (y1 < 0 ? -y1 : 0);
    if (nearX * nearX + nearY * nearY >= r2) return 0;
    const double farX = std::max(std::abs(x0), std::abs(x1)), farY = std::max(std::abs(y0), std::abs(y1));
    if (farX * farX + farY * farY <= r2) return (x1 - x0) * (y1 - y0);
    double cuts[6];
    const int n = rimCuts(r2, x0, x1, y0, y1, cuts);
    double area = 0;
    for (int k = 0; k + 1 < n; ++k) {
        const double p = cuts[k], q = cuts[k + 1], mid = 0.5 * (p + q), a = std::sqrt(std::max(0.0, r2 - mid * mid));
        if (std::min(y1, a) <= std::max(y0, -a)) continue;
        const double rim = chordIntegral(r2, p, q);  // ∫ √(r² − x²) over [p, q]
        area += (y1 < a ? y1 * (q - p) : rim) - (y0 > -a ? y0 * (q - p) : -rim);
    }
    return area;
}

/// Parts per side of a square of four cell centres that the rim cuts, for its hat integrals
/// (even: the square's diagonal runs along the parts' corners).
constexpr int kRimParts = 64;

/// W_o of every cell o for the disc of radius @p r: whole triangles in closed form (a hat
/// function's integral over a triangle of its vertex is a third of its area), the squares the
/// rim cuts in kRimParts² parts, each part's area in the disc at its centre's hat values.
std::map<std::pair<int, int>, double> hatIntegrals(double r, double cw, double ch)
{
    std::map<std::pair<int, int>, double> w;
    const double r2 = r * r, cell = cw * ch;
    const int reachX = int(std::ceil(r / cw)), reachY = int(std::ceil(r / ch));
    for (int rw = -reachY - 1; rw <= reachY; ++rw)
        for (int c = -reachX - 1; c <= reachX; ++c) {
            const double x0 = c * cw, x1 = x0 + cw, y0 = rw * ch, y1 = y0 + ch;
            const double farX = std::max(std::abs(x0), std::abs(x1)), farY = std::max(std::abs(y0), std::abs(y1));
            // The square's corners (c, rw), (c + 1, rw), (c, rw + 1), (c + 1, rw + 1) and
            // its triangles (c, rw), (c + 1, rw), (c, rw + 1) and the other three.
            double& w00 = w[{c, rw}];
            double& w10 = w[{c + 1, rw}];
            double& w01 = w[{c, rw + 1}];
            double& w11 = w[{c + 1, rw + 1}];
            if (farX * farX + farY * farY <= r2) {
                w00 += cell / 6, w11 += cell / 6, w10 += cell / 3, w01 += cell / 3;
                continue;
            }
            const double pw = cw / kRimParts, ph = ch / kRimParts;
            const auto add = [&](double a, double u, double v) {
                if (u + v <= 1)
                    w00 += a * (1 - u - v), w10 += a * u, w01 += a * v;
                else
                    w11 += a * (u + v - 1), w10 += a * (1 - v), w01 += a * (1 - u);
            };
            const auto part = [&](int i, int j, double a) {
                if (!(a > 0)) return;
                if (i + j + 1 == kRimParts) {  // the diagonal halves the part
                    add(0.5 * a, (i + 1.0 / 3) / kRimParts, (j + 1.0 / 3) / kRimParts);
                    add(0.5 * a, (i + 2.0 / 3) / kRimParts, (j + 2.0 / 3) / kRimParts);
                } else {
                    add(a, (i + 0.5) / kRimParts, (j + 0.5) / kRimParts);
                }
            };
            for (int j = 0; j < kRimParts; ++j) {
                const double py0 = y0 + j * ph, py1 = y0 + (j + 1) * ph;
                // The parts [first, last) of the row lie inside the disc with a part to spare
                // on either side: their areas are pw × ph, and the hat values at their centres
                // are linear in i on either side of the diagonal, so that the row's sums over
                // them are sums of arithmetic series. Those outside [from, to) lie outside it
                // with a part to spare (none where the row does). The parts between one by one.
                const double nearY = py0 > 0 ? py0 : (py1 < 0 ? -py1 : 0);
                if (nearY * nearY >= r2) continue;
                const double farY = std::max(std::abs(py0), std::abs(py1)), reachX = std::sqrt(std::max(0.0, r2 - farY * farY));
                const double outX = std::sqrt(r2 - nearY * nearY);
                const int from = std::clamp(int(std::floor((-outX - x0) / pw)) - 1, 0, kRimParts);
                const int to = std::clamp(int(std::ceil((outX - x0) / pw)) + 1, from, kRimParts);
                const int first = std::clamp(int(std::ceil((-reachX - x0) / pw)) + 1, from, to);
                const int last = std::clamp(int(std::floor((reachX - x0) / pw)) - 2, first, to);
                for (int i = from; i < first; ++i) part(i, j, areaInDisc(r2, x0 + i * pw, x0 + (i + 1) * pw, py0, py1));
                const int diagonal = kRimParts - 1 - j;
                const double a = pw * ph, v = (j + 0.5) / kRimParts;
                // Parts [p, q) of one side of the diagonal: their count and Σ u over them.
                const auto run = [&](int p, int q, bool below) {
                    if (q <= p) return;
                    const double n = q - p, su = n * (p + q) / (2.0 * kRimParts);
                    if (below)
                        w00 += a * (n * (1 - v) - su), w10 += a * su, w01 += a * n * v;
                    else
                        w11 += a * (su + n * (v - 1)), w10 += a * n * (1 - v), w01 += a * (n - su);
                };
                run(first, std::min(last, diagonal), true);
                if (diagonal >= first && diagonal < last) part(diagonal, j, a);
                run(std::max(first, diagonal + 1), last, false);
                for (int i = last; i < to; ++i) part(i, j, areaInDisc(r2, x0 + i * pw, x0 + (i + 1) * pw, py0, py1));
            }
        }
    return w;
}

} // namespace

DiscSquares discSquares(double r, double cellWidth, double cellHeight)
{
    DiscSquares squares;
    const int reachX = int(std::ceil(r / cellWidth)), reachY = int(std::ceil(r / cellHeight));
    for (int rw = -reachY - 1; rw <= reachY; ++rw)
        for (int c = -reachX - 1; c <= reachX; ++c) {
            const double a = areaInDisc(r * r, c * cellWidth, (c + 1) * cellWidth, rw * cellHeight, (rw + 1) * cellHeight);
            if (!(a > 0)) continue;
            squares.column.push_back(c), squares.row.push_back(rw), squares.area.push_back(a);
        }
    return squares;
}

DiscSamples discSamples(double r, double cellWidth, double cellHeight, int split)
{
    DiscSamples disc;
    disc.radius = r;
    disc.split = split;
    int reach = 0;
    for (const auto& [cell, weight] : hatIntegrals(r, cellWidth, cellHeight))
        if (weight > 0) {
            disc.cellColumn.push_back(cell.first);
            disc.cellRow.push_back(cell.second);
            disc.cellWeight.push_back(float(weight));
            reach = std::max({reach, std::abs(cell.first), std::abs(cell.second)});
        }
    struct Piece {
        float area, meanHalfChord;
        int col[3], row[3];
        float w[3];
        int sector;
    };
    std::vector<Piece> pieces;
    const double r2 = r * r, pw = cellWidth / split, ph = cellHeight / split;
    const int reachY = int(std::ceil(r / cellHeight + 0.5)), reachX = int(std::ceil(r / cellWidth + 0.5));
    // A piece [x0, x1] × [y0, y1] with its centre at (px, py) in cells from the centre cell.
    const auto add = [&](double x0, double x1, double y0, double y1, double px, double py) {
        const Column total = inDisc(r2, x0, x1, y0, y1);
        if (!(total.length > 1e-12 * pw * ph)) return;
        Piece piece;
        piece.area = float(total.length);
        const double turn = (std::atan2(py * cellHeight, px * cellWidth) + kPi) / (2 * kPi);
        piece.sector = std::clamp(int(turn * kHeightFieldSectors), 0, kHeightFieldSectors - 1);
        piece.meanHalfChord = float(total.integral / total.length);
        // The DEM's triangle under the piece's centre: corners (c, r), (c + 1, r), (c, r + 1)
        // where u + v <= 1, else (c + 1, r + 1), (c + 1, r), (c, r + 1).
        const int c = int(std::floor(px)), rr = int(std::floor(py));
        const double u = px - c, v = py - rr;
        if (u + v <= 1) {
            piece.col[0] = c, piece.row[0] = rr, piece.w[0] = float(1 - u - v);
            piece.col[1] = c + 1, piece.row[1] = rr, piece.w[1] = float(u);
            piece.col[2] = c, piece.row[2] = rr + 1, piece.w[2] = float(v);
        } else {
            piece.col[0] = c + 1, piece.row[0] = rr + 1, piece.w[0] = float(u + v - 1);
            piece.col[1] = c + 1, piece.row[1] = rr, piece.w[1] = float(1 - v);
            piece.col[2] = c, piece.row[2] = rr + 1, piece.w[2] = float(1 - u);
        }
        for (int t = 0; t < 3; ++t) reach = std::max({reach, std::abs(piece.col[t]), std::abs(piece.row[t])});
        pieces.push_back(piece);
    };
    // Pieces of 2 × 2 where h exceeds r/4 everywhere on them (there h changes slowly: a
    // clamp's edge crossing the piece errs less than the rim's finer pieces), split × split
    // per cell elsewhere (docs/method.md, Height fields).
    const int half = split / 2;
    // The pieces of 2 × 2 of a cell that overlap [−r, r] along an axis, and one more on
    // either side against rounding: the others lie outside the disc and add nothing. A disc
    // far smaller than a cell thus costs its own pieces, not the split² of whole cells.
    const auto overlapping = [&](int d, double cellSize, double piece) {
        const double start = (d - 0.5) * cellSize;
        const double lo = std::floor((-r - start) / (2 * piece)) - 1, hi = std::floor((r - start) / (2 * piece)) + 1;
        return std::pair<int, int>(int(std::clamp(lo, 0.0, double(half))), int(std::clamp(hi + 1, 0.0, double(half))));
    };
    for (int dy = -reachY; dy <= reachY; ++dy) {
        const auto [bFirst, bEnd] = overlapping(dy, cellHeight, ph);
        for (int b = bFirst; b < bEnd; ++b) {
            const double y0 = (dy - 0.5) * cellHeight + 2 * b * ph, y1 = y0 + 2 * ph;
            for (int dx = -reachX; dx <= reachX; ++dx) {
                const auto [aFirst, aEnd] = overlapping(dx, cellWidth, pw);
                for (int a = aFirst; a < aEnd; ++a) {
                    const double x0 = (dx - 0.5) * cellWidth + 2 * a * pw, x1 = x0 + 2 * pw;
                    const double farX = std::max(std::abs(x0), std::abs(x1)), farY = std::max(std::abs(y0), std::abs(y1));
                    if (r2 - farX * farX - farY * farY >= r2 / 16) {
                        add(x0, x1, y0, y1, dx - 0.5 + (2 * a + 1.0) / split, dy - 0.5 + (2 * b + 1.0) / split);
                        continue;
                    }
                    for (int j = 0; j < 2; ++j)
                        for (int i = 0; i < 2; ++i)
                            add(x0 + i * pw, x0 + (i + 1) * pw, y0 + j * ph, y0 + (j + 1) * ph,
                                dx - 0.5 + (2 * a + i + 0.5) / split, dy - 0.5 + (2 * b + j + 0.5) / split);
                }
            }
        }
    }
    std::stable_sort(pieces.begin(), pieces.end(), [](const Piece& p, const Piece& q) {
        return p.sector != q.sector ? p.sector < q.sector : p.meanHalfChord < q.meanHalfChord;
    });
    // A square of 2 × 2 cells from (column, row), moved inside the reach.
    const int side = 2 * reach + 1;
    const auto lattice = [&](int v) { return std::clamp(2 * int(std::floor(0.5 * v)), -reach, reach - 1); };
    std::vector<char> named(std::size_t(side) * std::size_t(side));
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        const Piece& piece = pieces[i];
        disc.area.push_back(piece.area);
        disc.meanHalfChord.push_back(piece.meanHalfChord);
        for (std::size_t t = 0; t < 3; ++t) {
            disc.tapColumn[t].push_back(piece.col[t]);
            disc.tapRow[t].push_back(piece.row[t]);
            disc.tapWeight[t].push_back(piece.w[t]);
            const int c = lattice(piece.col[t]), rw = lattice(piece.row[t]);
            char& was = named[std::size_t(rw + reach) * std::size_t(side) + std::size_t(c + reach)];
            if (!was) was = 1, disc.squareColumn.push_back(c), disc.squareRow.push_back(rw);
        }
        const std::size_t q = std::size_t(piece.sector);
        disc.sectorEnd[q] = i + 1;
        disc.squareEnd[q] = disc.squareColumn.size();
        if (i + 1 == pieces.size() || pieces[i + 1].sector != piece.sector) std::fill(named.begin(), named.end(), 0);
    }
    for (std::size_t q = 1; q < std::size_t(kHeightFieldSectors); ++q)
        if (disc.sectorEnd[q] == 0) disc.sectorEnd[q] = disc.sectorEnd[q - 1], disc.squareEnd[q] = disc.squareEnd[q - 1];
    disc.reach = reach;
    return disc;
}

namespace {

/// Lanes of cells computed together: consecutive cells of a row read consecutive heights.
constexpr int kLanes = 8;

/// Eight floats, one per lane (GCC's vector extension: AVX2 registers in the x86-64-v3 clone,
/// two SSE registers in the default one).
typedef float Lanes __attribute__((vector_size(32)));
static_assert(kLanes == 8, "Lanes holds eight cells");

// The helpers return vectors in registers: always inlined, in both clones, so the ABI of a
// vector return (which -Wpsabi warns of, engine/CMakeLists.txt) never applies.
#define MSII_LANES inline __attribute__((always_inline))
MSII_LANES Lanes loadLanes(const float* p)
{
    Lanes v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

/// discSamples at radius @p r, kept for the next call with the same disc: a DEM's windows
/// all ask for the same few (their quadratures take longer than a window's bands do).
std::shared_ptr<const DiscSamples> sharedDisc(double r, double cw, double ch, int split)
{
    static std::mutex mutex;
    static std::map<std::array<double, 4>, std::shared_ptr<const DiscSamples>> kept;
    const std::array<double, 4> key{r, cw, ch, double(split)};
    {
        const std::lock_guard<std::mutex> lock(mutex);
        if (const auto found = kept.find(key); found != kept.end()) return found->second;
    }
    auto disc = std::make_shared<const DiscSamples>(discSamples(r, cw, ch, split));
    const std::lock_guard<std::mutex> lock(mutex);
    if (kept.size() >= 64) kept.clear();  // a bound; the discs in use stay with their users
    kept.emplace(key, disc);
    return disc;
}

/// Eight 64-bit integers and eight doubles, one per lane.
typedef long long LaneInts __attribute__((vector_size(64)));
typedef long long LaneQuads __attribute__((vector_size(32)));
typedef double LaneDoubles __attribute__((vector_size(64)));

/// Heights as integers of 2⁻²³ m (1.2e-7 m) for the sums over whole rows of cells: a row's
/// sum is the difference of two prefix sums, exact in 64 bits, so that a cell's sum is the
/// same in every window whatever the window's first column.
constexpr double kHeightScale = 8388608.0;

/// A disc summed by rows of cells (docs/method.md, Height fields):
/// - the core taps, whose hat functions lie inside the disc (W_o = the cell's area): a run of
///   cells per row, summed from the rows' prefix sums of the heights;
/// - the other taps with their W_o, one by one;
/// - the pieces for C, by sector of their centres' direction, h̄ ascending within a sector;
/// - per sector, the squares of 2 × 2 cells that hold the heights of its pieces and that the
///   discs before it (in ascending radius) do not name for that sector: the largest and
///   smallest height over these and the earlier discs' bound |z_o − z₀| over the sector's
///   pieces.
/// Offsets are into the padded grid of row stride s (row · s + column), and into the prefix
/// sums of row stride s + 1.
struct DiscPlan {
    std::size_t index = 0;  ///< in the discs as summed (SumRadii)
    int reach = 0;  ///< the largest reach of this disc and the smaller ones
    std::vector<std::ptrdiff_t> coreFrom, coreTo;  ///< per row: prefix sums before the run and past it
    double coreCount = 0;                          ///< core taps
    /// A tap that is not core: its offset and W_o.
    struct Tap {
        std::int32_t at;
        float weight;
    };
    std::vector<Tap> rim;
    /// The pieces for C, what the sum of one reads together in 32 bytes.
    struct Piece {
        float halfChord, area;
        float weight[3];
        std::int32_t at[3];  ///< offsets of its heights' cells
    };
    std::vector<Piece> pieces;
    std::uint32_t piecesEnd[kHeightFieldSectors] = {};    ///< sector q's pieces end here (start where q − 1's end)
    std::vector<std::int32_t> squareAt;        ///< the new squares' first cells, sector by sector
    std::uint32_t squaresEnd[kHeightFieldSectors] = {};   ///< sector q's new squares end here
};

struct DiscPlans {
    float coreWeight = 0;  ///< W_o of a core tap: the cell's area
    std::vector<DiscPlan> discs;  ///< ascending radius
};

DiscPlans planDiscs(const std::vector<std::shared_ptr<const DiscSamples>>& discs, double cw, double ch,
                    std::ptrdiff_t stride)
{
    const auto samples = [&](std::size_t k) -> const DiscSamples& { return *discs[k]; };
    DiscPlans plans;
    std::vector<std::size_t> order(discs.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return samples(a).radius < samples(b).radius; });
    // W_o of a tap whose four squares are inside: hatIntegrals adds cell/6, cell/3, cell/3 and
    // cell/6 in that order for every such tap, at every radius.
    const double cell = cw * ch;
    plans.coreWeight = float(((cell / 6 + cell / 3) + cell / 3) + cell / 6);
    const std::ptrdiff_t prefixStride = stride + 1;
    std::map<int, std::pair<int, int>> before;  // the taps of the disc before: row → first and last column
    // Per sector, the squares that the discs so far name (by their first cell, within the
    // largest reach).
    int largestReach = 0;
    for (std::size_t k = 0; k < discs.size(); ++k) largestReach = std::max(largestReach, samples(k).reach);
    const std::size_t side = std::size_t(2 * largestReach + 1);
    std::vector<char> named[kHeightFieldSectors];
    for (std::vector<char>& n : named) n.assign(side * side, 0);
    int reach = 0;
    const auto fail = [] { throw std::logic_error("height field: a disc's taps are not runs of cells nested by radius"); };
    // The offset of cell (row, column) from the centre, in 32 bits (the rim's taps and the
    // pieces are read from few bytes).
    const auto offset32 = [&](int rw, int c) {
        const std::ptrdiff_t at = rw * stride + c;
        if (at != std::ptrdiff_t(std::int32_t(at)))
            throw InvalidInputError("the height grid is too wide for a ball of this radius");
        return std::int32_t(at);
    };
    for (const std::size_t k : order) {
        const DiscSamples& d = samples(k);
        DiscPlan plan;
        plan.index = k;
        reach = std::max(reach, d.reach);
        plan.reach = reach;
        std::map<int, std::vector<std::pair<int, float>>> rows;  // row → (column, W_o), column ascending
        for (std::size_t i = 0; i < d.cellWeight.size(); ++i) rows[d.cellRow[i]].push_back({d.cellColumn[i], d.cellWeight[i]});
        // A tap is core where its squares' farthest corner is inside the disc, by a margin
        // that rounding cannot cross, and its W_o is the core weight.
        const double inside = d.radius * d.radius * (1 - 1e-9);
        std::map<int, std::pair<int, int>> taps;
        for (auto& [rw, cols] : rows) {
            std::sort(cols.begin(), cols.end());
            const int first = cols.front().first, last = cols.back().first;
            if (last - first + 1 != int(cols.size())) fail();
            taps[rw] = {first, last};
            int coreFirst = 1, coreLast = 0;
            for (const auto& [c, w] : cols) {
                const double farX = (std::abs(c) + 1) * cw, farY = (std::abs(rw) + 1) * ch;
                if (farX * farX + farY * farY <= inside && w == plans.coreWeight) {
                    if (coreFirst > coreLast)
                        coreFirst = coreLast = c;
                    else if (c == coreLast + 1)
                        coreLast = c;
                    else
                        fail();
                } else {
                    plan.rim.push_back({offset32(rw, c), w});
                }
            }
            if (coreFirst <= coreLast) {
                plan.coreFrom.push_back(rw * prefixStride + coreFirst);
                plan.coreTo.push_back(rw * prefixStride + coreLast + 1);
                plan.coreCount += coreLast - coreFirst + 1;
            }
            if (const auto previous = before.find(rw); previous != before.end())
                if (previous->second.first < first || previous->second.second > last) fail();
        }
        for (const auto& [rw, run] : before)
            if (!taps.count(rw)) fail();
        before = std::move(taps);
        // The pieces as in DiscSamples (by sector); per sector, the squares no disc before
        // this one named for it.
        for (std::size_t i = 0; i < d.size(); ++i) {
            DiscPlan::Piece piece{d.meanHalfChord[i], d.area[i], {}, {}};
            for (std::size_t t = 0; t < 3; ++t) {
                piece.weight[t] = d.tapWeight[t][i];
                piece.at[t] = offset32(d.tapRow[t][i], d.tapColumn[t][i]);
            }
            plan.pieces.push_back(piece);
        }
        for (int q = 0; q < kHeightFieldSectors; ++q) {
            plan.piecesEnd[q] = std::uint32_t(d.sectorEnd[std::size_t(q)]);
            for (std::size_t j = q == 0 ? 0 : d.squareEnd[std::size_t(q) - 1]; j < d.squareEnd[std::size_t(q)]; ++j) {
                const int c = d.squareColumn[j], rw = d.squareRow[j];
                char& was = named[std::size_t(q)][std::size_t(rw + largestReach) * side + std::size_t(c + largestReach)];
                if (!was) was = 1, plan.squareAt.push_back(offset32(rw, c));
            }
            plan.squaresEnd[q] = std::uint32_t(plan.squareAt.size());
        }
        plans.discs.push_back(std::move(plan));
    }
    return plans;
}

/// What sumDiscs reads, all in the padded grid's rows (the prefix sums one column longer).
struct DiscGrid {
    const float* z;          ///< the first lane's height
    const float* squareHigh; ///< the largest height of the 2 × 2 cells from here
    const float* squareLow;  ///< and the smallest
    const long long* prefix; ///< Σ of the row's heights before here, in 2⁻²³ m
};

/// Sixteen floats, one per lane: one AVX-512 register (sumDiscsWide's AVX-512 variant).
typedef float Lanes16 __attribute__((vector_size(64)));

template <class V>
MSII_LANES V loadAs(const float* p)
{
    V v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
template <class V>
MSII_LANES V maxOf(V a, V b)
{
    return a > b ? a : b;
}
template <class V>
MSII_LANES V minOf(V a, V b)
{
    return a < b ? a : b;
}
/// The largest of the lanes of @p v: halves folded onto each other.
MSII_LANES float largestOf(Lanes v)
{
    v = maxOf(v, __builtin_shufflevector(v, v, 4, 5, 6, 7, 0, 1, 2, 3));
    v = maxOf(v, __builtin_shufflevector(v, v, 2, 3, 0, 1, 6, 7, 4, 5));
    v = maxOf(v, __builtin_shufflevector(v, v, 1, 0, 3, 2, 5, 4, 7, 6));
    return v[0];
}
MSII_LANES float largestOf(Lanes16 v)
{
    return largestOf(maxOf(__builtin_shufflevector(v, v, 0, 1, 2, 3, 4, 5, 6, 7),
                           __builtin_shufflevector(v, v, 8, 9, 10, 11, 12, 13, 14, 15)));
}
/// A float in every lane of a V. A macro, not a helper: GCC 12 lowers a helper's vector for
/// the default target before inlining it into the AVX2 clone, and the AVX2 code then builds
/// it lane by lane (eight inserts) instead of one vbroadcastss.
#define MSII_BROADCAST_AS(V, x) (float(x) - V{})

/// For kLanes · M consecutive cells (lane k at column offset k), M = H · (lanes of V) / kLanes,
/// at heights @p z0lanes, V(r) − ⅔πr³ of the first @p count discs of @p plans, into @p sums
/// (kLanes · M per disc, in that order): Σ_o W_o (z_o − z₀) over the taps, then C over the
/// pieces, sector by sector, whose h̄ is at most the lanes' largest |z_o − z₀| over the
/// sector's squares (past a lane's own bound, |z − z₀| < h̄ there up to the interpolation's
/// rounding: no clamp, nothing to add; each lane sums the pieces its own bound admits, masked,
/// whatever the other lanes admit).
/// The sum of each lane depends on its own cells only, and a disc's on the discs before it
/// only, so that a cell gets the same value in every block, window and tile, whatever the
/// lanes summed together and the number of discs summed: every lane takes the same operations
/// in the same order. Products are fused into their sums (-ffp-contract=fast) in the variants
/// for x86-64-v3 and v4, which have FMA, alike at every vector width (engine/CMakeLists.txt),
/// and in the default one only where the whole build targets FMA; a processor takes its v4
/// blocks only with its v3 single lanes (sumDiscsWide), so that the two round alike.
/// H vectors V side by side share the pieces' offsets, weights and loop.
template <int H, class V>
MSII_LANES void sumDiscsOf(const DiscGrid& g, const DiscPlans& plans, const float* z0lanes, std::size_t count, double* sums)
{
    constexpr int L = int(sizeof(V) / sizeof(float)), W = H * L;
    static_assert(W % kLanes == 0, "whole blocks of eight lanes");
    const V zero = MSII_BROADCAST_AS(V, 0);
    V z0[H];
    for (int h = 0; h < H; ++h) z0[h] = loadAs<V>(z0lanes + h * L);
    const float* z = g.z;
    // Per sector, the largest and smallest height over its squares so far (disc by disc,
    // nested): the largest |z_o − z₀| is the larger of high − z₀ and z₀ − low, rounded alike.
    V high[kHeightFieldSectors][H], low[kHeightFieldSectors][H];
    for (int q = 0; q < kHeightFieldSectors; ++q)
        for (int h = 0; h < H; ++h) high[q][h] = low[q][h] = z0[h];
    for (std::size_t k = 0; k < count; ++k) {
        const DiscPlan& disc = plans.discs[k];
        // The core sums in quarters of four lanes, each a register in the AVX2 variant (a
        // vector of eight lives on the stack there).
        constexpr int Q = W / 4;
        LaneQuads core[Q] = {};
        const std::size_t rows = disc.coreFrom.size();
        for (std::size_t i = 0; i < rows; ++i) {
            const long long *to = g.prefix + disc.coreTo[i], *from = g.prefix + disc.coreFrom[i];
            for (int q = 0; q < Q; ++q) {
                LaneQuads a, b;
                std::memcpy(&a, to + 4 * q, sizeof a);
                std::memcpy(&b, from + 4 * q, sizeof b);
                core[q] += a - b;
            }
        }
        const std::size_t rims = disc.rim.size();
        const DiscPlan::Tap* rim = disc.rim.data();
        V rimEven[H], rimOdd[H];
        for (int h = 0; h < H; ++h) rimEven[h] = rimOdd[h] = zero;
        std::size_t i = 0;
        for (; i + 2 <= rims; i += 2) {
            const V even = MSII_BROADCAST_AS(V, rim[i].weight), odd = MSII_BROADCAST_AS(V, rim[i + 1].weight);
            for (int h = 0; h < H; ++h) {
                rimEven[h] += even * (loadAs<V>(z + rim[i].at + h * L) - z0[h]);
                rimOdd[h] += odd * (loadAs<V>(z + rim[i + 1].at + h * L) - z0[h]);
            }
        }
        if (i < rims)
            for (int h = 0; h < H; ++h)
                rimEven[h] += MSII_BROADCAST_AS(V, rim[i].weight) * (loadAs<V>(z + rim[i].at + h * L) - z0[h]);
        const DiscPlan::Piece* pieces = disc.pieces.data();
        V clamps[H];
        for (int h = 0; h < H; ++h) clamps[h] = zero;
        const std::int32_t* squares = disc.squareAt.data();
        for (int q = 0, j = 0; q < kHeightFieldSectors; ++q) {
            for (const int end = int(disc.squaresEnd[q]); j < end; ++j)
                for (int h = 0; h < H; ++h) {
                    high[q][h] = maxOf(high[q][h], loadAs<V>(g.squareHigh + squares[j] + h * L));
                    low[q][h] = minOf(low[q][h], loadAs<V>(g.squareLow + squares[j] + h * L));
                }
            V reach[H];
            for (int h = 0; h < H; ++h) reach[h] = maxOf(high[q][h] - z0[h], z0[h] - low[q][h]);
            V wide = reach[0];
            for (int h = 1; h < H; ++h) wide = maxOf(wide, reach[h]);
            const float most = largestOf(wide);
            const std::size_t end = disc.piecesEnd[q];
            for (i = q == 0 ? 0 : disc.piecesEnd[q - 1]; i < end && pieces[i].halfChord <= most; ++i) {
                const DiscPlan::Piece& p = pieces[i];
                const V hi = MSII_BROADCAST_AS(V, p.halfChord), w0 = MSII_BROADCAST_AS(V, p.weight[0]),
                        w1 = MSII_BROADCAST_AS(V, p.weight[1]), w2 = MSII_BROADCAST_AS(V, p.weight[2]),
                        area = MSII_BROADCAST_AS(V, p.area), lowest = MSII_BROADCAST_AS(V, -p.halfChord);
                for (int h = 0; h < H; ++h) {
                    const V e = w0 * loadAs<V>(z + p.at[0] + h * L) + w1 * loadAs<V>(z + p.at[1] + h * L) +
                                w2 * loadAs<V>(z + p.at[2] + h * L) - z0[h];
                    const V clamped = minOf(maxOf(e, lowest), hi) - e;
                    const V add = area * clamped;
                    clamps[h] += (hi <= reach[h]) ? add : zero;
                }
            }
        }
        // Per eight lanes, in double.
        float rimSum[W], clampSum[W];
        for (int h = 0; h < H; ++h) {
            const V r = rimEven[h] + rimOdd[h];
            std::memcpy(rimSum + h * L, &r, sizeof r);
            std::memcpy(clampSum + h * L, &clamps[h], sizeof clamps[h]);
        }
        for (int e = 0; e < W / kLanes; ++e) {
            LaneInts coreInts;
            std::memcpy(&coreInts, &core[2 * e], sizeof core[2 * e]);
            std::memcpy(reinterpret_cast<char*>(&coreInts) + sizeof core[2 * e], &core[2 * e + 1], sizeof core[2 * e + 1]);
            const LaneDoubles z0wide = __builtin_convertvector(loadLanes(z0lanes + e * kLanes), LaneDoubles);
            const LaneDoubles coreSum = __builtin_convertvector(coreInts, LaneDoubles) * (1 / kHeightScale) - disc.coreCount * z0wide;
            const LaneDoubles total = double(plans.coreWeight) * coreSum +
                                      __builtin_convertvector(loadLanes(rimSum + e * kLanes), LaneDoubles) +
                                      __builtin_convertvector(loadLanes(clampSum + e * kLanes), LaneDoubles);
            std::memcpy(sums + k * W + e * kLanes, &total, sizeof total);
        }
    }
}

/// sumDiscsOf for kLanes cells. Compiled for x86-64-v3 (AVX2 and FMA) as well, chosen at run
/// time.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void sumDiscs(const DiscGrid& g, const DiscPlans& plans,
                                                                         const float* z0lanes, std::size_t count,
                                                                         double* sums)
{
    sumDiscsOf<1, Lanes>(g, plans, z0lanes, count, sums);
}

/// sumDiscsOf for kWide cells: two vectors of eight (x86-64-v3 and the default) or one of
/// sixteen (x86-64-v4, AVX-512, below).
constexpr int kWide = 2 * kLanes;
__attribute__((target_clones("arch=x86-64-v3", "default"))) void sumDiscsWideOf8(const DiscGrid& g,
                                                                                const DiscPlans& plans,
                                                                                const float* z0lanes,
                                                                                std::size_t count, double* sums)
{
    sumDiscsOf<2, Lanes>(g, plans, z0lanes, count, sums);
}
__attribute__((target("arch=x86-64-v4"))) void sumDiscsWideOf16(const DiscGrid& g, const DiscPlans& plans,
                                                                const float* z0lanes, std::size_t count, double* sums)
{
    sumDiscsOf<1, Lanes16>(g, plans, z0lanes, count, sums);
}
/// The values are the same either way; AVX-512 where the processor and the system have it. A
/// processor of x86-64-v4 has v3 too, so that sumDiscs takes its v3 clone there, with FMA as
/// here.
void sumDiscsWide(const DiscGrid& g, const DiscPlans& plans, const float* z0lanes, std::size_t count, double* sums,
                  int vectorLanes)
{
    static const bool v4 = __builtin_cpu_supports("x86-64-v4");
    (v4 && vectorLanes != kLanes ? sumDiscsWideOf16 : sumDiscsWideOf8)(g, plans, z0lanes, count, sums);
}

/// What one cell of the own rectangle needs: whether every cell of its largest ball has a
/// height (a count of those without, over the square around the ball).
class HeightCoverage {
public:
    explicit HeightCoverage(const HeightGrid& g) : mCols(g.cols), mMissing(std::size_t(g.cols + 1) * (g.rows + 1), 0)
    {
        // The rows' running counts in parallel, then the columns' sums of them in strips.
        tbb::parallel_for(0, g.rows, [&](int r) {
            std::int64_t running = 0;
            for (int c = 0; c < g.cols; ++c) at(c + 1, r + 1) = running += std::isnan(g.at(c, r)) ? 1 : 0;
        });
        constexpr int kStrip = 256;
        tbb::parallel_for(0, (g.cols + kStrip) / kStrip, [&](int strip) {
            const int c0 = strip * kStrip + 1, c1 = std::min(g.cols + 1, c0 + kStrip);
            for (int r = 1; r <= g.rows; ++r)
                for (int c = c0; c < c1; ++c) at(c, r) += at(c, r - 1);
        });
    }
    /// Whether every cell within @p reach columns and rows of (col, row) exists and has a height.
    bool complete(int col, int row, int reach, int rows) const { return complete(col, col, row, reach, rows); }
    /// The same for every cell (col, row) to (last, row).
    bool complete(int col, int last, int row, int reach, int rows) const
    {
        const int c0 = col - reach, c1 = last + reach + 1, r0 = row - reach, r1 = row + reach + 1;
        if (c0 < 0 || r0 < 0 || c1 > mCols || r1 > rows) return false;
        return at(c1, r1) - at(c0, r1) - at(c1, r0) + at(c0, r0) == 0;
    }

private:
    std::int64_t& at(int c, int r) { return mMissing[std::size_t(r) * std::size_t(mCols + 1) + std::size_t(c)]; }
    std::int64_t at(int c, int r) const { return mMissing[std::size_t(r) * std::size_t(mCols + 1) + std::size_t(c)]; }
    int mCols;
    std::vector<std::int64_t> mMissing;
};

/// The radii at which V is summed: V's wanted radii, and r(1 ± δ) for Ŝ's (with pieces
/// kSpherePieceFactor times finer).
struct SumRadii {
    std::vector<double> radius;
    std::vector<int> split;  ///< the pieces per cell axis (discSamples)
    std::vector<int> volumeOf, belowOf, aboveOf;  ///< per radius j: its index, or −1
};

SumRadii sumRadii(const HeightFieldOptions& o)
{
    SumRadii s;
    const std::size_t n = o.radii.size();
    s.volumeOf.assign(n, -1), s.belowOf.assign(n, -1), s.aboveOf.assign(n, -1);
    const double cell = std::max(o.cellWidth, o.cellHeight);
    const auto add = [&](double r, int factor) {
        s.radius.push_back(r);
        s.split.push_back(factor * discSplit(r, o.cellWidth, o.cellHeight));
        return int(s.radius.size()) - 1;
    };
    for (std::size_t j = 0; j < n; ++j) {
        const bool wanted = o.wanted.empty() || std::find(o.wanted.begin(), o.wanted.end(), int(j)) != o.wanted.end();
        if (!wanted) continue;
        if (o.computeVolume) s.volumeOf[j] = add(o.radii[j], 1);
        if (o.computeSphere) {
            const double step = heightFieldSphereStep(o.radii[j], cell);
            s.belowOf[j] = add(o.radii[j] * (1 - step), kSpherePieceFactor);
            s.aboveOf[j] = add(o.radii[j] * (1 + step), kSpherePieceFactor);
        }
    }
    return s;
}

void validate(const HeightGrid& grid, const GridRect& own, const HeightFieldOptions& o)
{
    validateRadii(o.radii);
    if (!(o.cellWidth > 0) || !(o.cellHeight > 0) || !std::isfinite(o.cellWidth) || !std::isfinite(o.cellHeight))
        throw InvalidInputError("the cell size must be positive");
    if (o.vectorLanes != 0 && o.vectorLanes != kLanes && o.vectorLanes != kWide)
        throw InvalidInputError("the height field sums 8 or 16 cells per vector (vectorLanes 0, 8 or 16), not " +
                                std::to_string(o.vectorLanes));
    if (own.col < 0 || own.row < 0 || own.col + own.cols > grid.cols || own.row + own.rows > grid.rows)
        throw InvalidInputError("the cells to compute lie outside the height grid");
    if (grid.z.size() != std::size_t(grid.cols) * std::size_t(grid.rows))
        throw InvalidInputError("the height grid's size does not match its columns and rows");
    // The rows' sums of heights in 2⁻²³ m must fit in 64 bits (sumDiscs).
    float highest = 0;
    for (const float z : grid.z)
        if (!std::isnan(z)) highest = std::max(highest, std::abs(z));
    if (!(double(highest) * kHeightScale * (double(grid.cols) + kLanes + 1) < 0x1p62))
        throw InvalidInputError("heights of " + std::to_string(highest) + " are beyond what the height field sums (at most " +
                                std::to_string(0x1p62 / kHeightScale / (double(grid.cols) + kLanes + 1)) +
                                " in a row of this length)");
}

/// The heights with kLanes columns more on the right, so that a block of lanes past the own
/// cells' last reads within the grid (those lanes are not used), with what the discs' sums
/// read besides: per padded cell the extremes of the square of 2 × 2 cells from it, and per
/// row the prefix sums of the heights.
struct PaddedHeights {
    explicit PaddedHeights(const HeightGrid& g) : stride(g.cols + kLanes), prefixStride(stride + 1) {}
    std::ptrdiff_t stride, prefixStride;
    std::vector<float> z, squareHigh, squareLow;
    std::vector<long long> prefix;
    /// What the sums read from cell (col, row) on.
    DiscGrid at(int row, int col) const
    {
        const std::size_t i = std::size_t(row) * std::size_t(stride) + std::size_t(col);
        return DiscGrid{&z[i], &squareHigh[i], &squareLow[i],
                        &prefix[std::size_t(row) * std::size_t(prefixStride) + std::size_t(col)]};
    }
};

/// Fills @p p from @p grid.
void padHeights(const HeightGrid& grid, PaddedHeights& p)
{
    const std::ptrdiff_t stride = p.stride, prefixStride = p.prefixStride;
    p.z.assign(std::size_t(stride) * std::size_t(grid.rows), 0.0f);
    p.squareHigh.resize(p.z.size()), p.squareLow.resize(p.z.size());
    p.prefix.resize(std::size_t(prefixStride) * std::size_t(grid.rows));
    // Cells without a height take 0 in the padded grid (a disc that reads one gets no
    // value). Per row the prefix sums of the heights in 2⁻²³ m.
    tbb::parallel_for(0, grid.rows, [&](int row) {
        float* z = &p.z[std::size_t(row) * std::size_t(stride)];
        std::copy_n(&grid.z[std::size_t(row) * std::size_t(grid.cols)], grid.cols, z);
        for (std::ptrdiff_t c = 0; c < stride; ++c)
            if (std::isnan(z[c])) z[c] = 0;
        long long* sum = &p.prefix[std::size_t(row) * std::size_t(prefixStride)];
        sum[0] = 0;
        for (std::ptrdiff_t c = 0; c < stride; ++c) sum[c + 1] = sum[c] + std::llrint(double(z[c]) * kHeightScale);
    });
    // Per padded cell, the largest and smallest height of the 2 × 2 cells from it (the
    // last row and column: of the cells there are; no disc's square reaches past them).
    tbb::parallel_for(0, grid.rows, [&](int row) {
        const float* z = &p.z[std::size_t(row) * std::size_t(stride)];
        const float* next = row + 1 < grid.rows ? z + stride : z;
        float* high = &p.squareHigh[std::size_t(row) * std::size_t(stride)];
        float* low = &p.squareLow[std::size_t(row) * std::size_t(stride)];
        for (std::ptrdiff_t c = 0; c < stride; ++c) {
            const std::ptrdiff_t right = std::min(c + 1, stride - 1);
            high[c] = std::max(std::max(z[c], z[right]), std::max(next[c], next[right]));
            low[c] = std::min(std::min(z[c], z[right]), std::min(next[c], next[right]));
        }
    });
}

/// The quadratures of the discs summed (sharedDisc), one disc per task, the largest radii
/// first (their quadratures take longest).
std::vector<std::shared_ptr<const DiscSamples>> discsOf(const SumRadii& sums, const HeightFieldOptions& options)
{
    std::vector<std::shared_ptr<const DiscSamples>> discs(sums.radius.size());
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, discs.size(), 1),
        [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                const std::size_t k = discs.size() - 1 - i;
                discs[k] = sharedDisc(sums.radius[k], options.cellWidth, options.cellHeight, sums.split[k]);
            }
        },
        tbb::simple_partitioner());
    return discs;
}

/// What a wanted radius's values come from: V(r) over the ball's volume, or for Ŝ the
/// difference of V at r(1 ± δ) over that of the balls' volumes (the plans' slots).
struct Stored {
    std::size_t radius;      ///< j
    bool sphere;             ///< Ŝ, else V̂
    std::size_t slot, below; ///< the sum (Ŝ: at r(1 + δ)) and, for Ŝ, the one at r(1 − δ)
    std::size_t needs;       ///< a lane with more discs than this has the value
    double ball;             ///< ⁴⁄₃π r³, or its difference for Ŝ
};

/// The values of the wanted radii, each with the sums it comes from.
std::vector<Stored> storedOf(const HeightFieldOptions& options, const SumRadii& sums, const DiscPlans& plans)
{
    // Where the volume of summed disc s (SumRadii's index) is, in the plans' order.
    const std::size_t discCount = plans.discs.size();
    std::vector<std::size_t> slot(discCount);
    for (std::size_t k = 0; k < discCount; ++k) slot[plans.discs[k].index] = k;
    std::vector<Stored> stored;
    for (std::size_t j = 0; j < options.radii.size(); ++j) {
        const double rj = options.radii[j];
        if (sums.volumeOf[j] >= 0) {
            const std::size_t at = slot[std::size_t(sums.volumeOf[j])];
            stored.push_back({j, false, at, at, at, 4.0 / 3.0 * kPi * rj * rj * rj});
        }
        if (sums.belowOf[j] >= 0 && sums.aboveOf[j] >= 0) {
            const double below = sums.radius[std::size_t(sums.belowOf[j])], above = sums.radius[std::size_t(sums.aboveOf[j])];
            const std::size_t at = slot[std::size_t(sums.aboveOf[j])], under = slot[std::size_t(sums.belowOf[j])];
            stored.push_back({j, true, at, under, std::max(at, under),
                              4.0 / 3.0 * kPi * (above * above * above - below * below * below)});
        }
    }
    return stored;
}

/// Sums the discs of the own rectangle's cells, a block of lanes at a time, and stores V̂
/// and Ŝ from the sums.
class RowSums {
public:
    RowSums(const HeightGrid& grid, const GridRect& own, const HeightFieldOptions& options,
            const HeightCoverage& coverage, const PaddedHeights& heights, const DiscPlans& plans,
            const std::vector<Stored>& stored, HeightFieldResult& result)
        : grid(grid), own(own), options(options), coverage(coverage), heights(heights), plans(plans), stored(stored),
          result(result), discCount(plans.discs.size()), reach(plans.discs.back().reach)
    {
    }

    /// Own rows [begin, end).
    void rows(int begin, int end, RunContext* context) const
    {
        std::vector<double> volume(discCount * kWide), one(discCount * kLanes);
        std::size_t whole[kWide];
        std::fill(whole, whole + kWide, discCount);
        for (int r = begin; r < end; ++r) {
            const int row = own.row + r;
            for (int c = 0; c < own.cols; c += kLanes) {
                // Most runs of kWide cells have every height of their largest discs, and
                // lie farther than R from the grid's edge: summed together.
                if (c + kWide <= own.cols && interior(own.col + c, own.col + c + kWide - 1, row)) {
                    float z0[kWide];
                    for (int k = 0; k < kWide; ++k) z0[k] = grid.at(own.col + c + k, row);
                    sumDiscsWide(heights.at(row, own.col + c), plans, z0, discCount, volume.data(), options.vectorLanes);
                    store(volume.data(), r, c, kWide, kWide, whole);
                    c += kWide - kLanes;
                    continue;
                }
                block(r, c, volume.data(), one.data());
            }
            if (context) context->advance();
        }
    }

private:
    /// The block of kLanes cells at own column c of own row r (fewer at the row's end).
    void block(int r, int c, double* volume, double* one) const
    {
        const int row = own.row + r;
        const int lanes = std::min(kLanes, own.cols - c);
        std::size_t complete[kLanes];  // per lane: the discs, in the nested order, it has every height of
        bool all = true;
        if (!completeDiscs(c, row, lanes, complete, all)) return;
        float z0[kLanes];
        for (int k = 0; k < kLanes; ++k) z0[k] = k < lanes ? grid.at(own.col + c + k, row) : 0.0f;
        const DiscGrid blockGrid = heights.at(row, own.col + c);
        const bool inside = all && own.col + c - reach >= 0 && own.col + c + reach < grid.cols && row - reach >= 0 &&
                            row + reach < grid.rows;
        if (inside) {
            sumDiscs(blockGrid, plans, z0, discCount, volume);
        } else {
            // Near the grid's edge or a gap: each lane alone, over the discs it has
            // every height of, as lane 0 of a block whose other lanes read its
            // neighbours within the padding, unused.
            for (int k = 0; k < lanes; ++k) {
                if (complete[k] == 0) continue;
                float lane0[kLanes];
                std::fill(lane0, lane0 + kLanes, z0[k]);
                const DiscGrid laneGrid{blockGrid.z + k, blockGrid.squareHigh + k, blockGrid.squareLow + k, blockGrid.prefix + k};
                sumDiscs(laneGrid, plans, lane0, complete[k], one);
                for (std::size_t s = 0; s < complete[k]; ++s) volume[s * kLanes + std::size_t(k)] = one[s * kLanes];
            }
        }
        store(volume, r, c, lanes, kLanes, complete);
    }

    /// Per lane of the block at own column c, the discs it has every height of, in the
    /// nested order (@p complete); @p all becomes false where a lane lacks some. Returns
    /// whether any lane has any.
    bool completeDiscs(int c, int row, int lanes, std::size_t* complete, bool& all) const
    {
        // Most blocks have every height of their largest discs: that is tried first.
        if (lanes == kLanes && coverage.complete(own.col + c, own.col + c + kLanes - 1, row, reach, grid.rows)) {
            std::fill(complete, complete + kLanes, discCount);
            return true;
        }
        bool any = false;
        for (int k = 0; k < kLanes; ++k) {
            const auto has = [&](std::size_t m) {
                return coverage.complete(own.col + c + k, row, plans.discs[m].reach, grid.rows);
            };
            std::size_t m = 0;
            if (k < lanes && has(discCount - 1))
                m = discCount;
            else
                while (k < lanes && m + 1 < discCount && has(m)) ++m;
            complete[k] = m;
            all = all && (m == discCount || k >= lanes);
            any = any || m > 0;
        }
        return any;
    }

    /// Whether the cells (col, row) to (last, row) have every height of their largest discs
    /// and lie farther than R from the grid's edge.
    bool interior(int col, int last, int row) const
    {
        return col - reach >= 0 && last + reach < grid.cols && row - reach >= 0 && row + reach < grid.rows &&
               coverage.complete(col, last, row, reach, grid.rows);
    }

    /// The values of lanes [0, lanes) of the block at own column c from its sums (@p width
    /// per disc), radius by radius, where the lane has the discs they need.
    void store(const double* volume, int r, int c, int lanes, std::size_t width, const std::size_t* completeOf) const
    {
        const std::size_t cell = std::size_t(r) * std::size_t(own.cols) + std::size_t(c);
        for (const Stored& o : stored) {
            const double* v = &volume[o.slot * width];
            const double* below = &volume[o.below * width];
            float* out = &(o.sphere ? result.sphere : result.volume)[o.radius][cell];
            for (int k = 0; k < lanes; ++k)
                if (o.needs < completeOf[k]) out[k] = float(0.5 + (o.sphere ? v[k] - below[k] : v[k]) / o.ball);
        }
    }

    const HeightGrid& grid;
    const GridRect& own;
    const HeightFieldOptions& options;
    const HeightCoverage& coverage;
    const PaddedHeights& heights;
    const DiscPlans& plans;
    const std::vector<Stored>& stored;
    HeightFieldResult& result;
    const std::size_t discCount;
    const int reach;
};

} // namespace

HeightFieldResult computeHeightField(const HeightGrid& grid, const GridRect& own, const HeightFieldOptions& options,
                                     RunContext* context)
{
    validate(grid, own, options);
    const Stopwatch clock;
    HeightFieldResult result;
    result.radii = options.radii;
    const std::size_t n = options.radii.size(), cells = std::size_t(own.cols) * std::size_t(own.rows);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const SumRadii sums = sumRadii(options);
    // Columns for the radii wanted only (the others stay empty: a DEM's default bands need
    // four of N).
    if (options.computeVolume) result.volume.resize(n);
    if (options.computeSphere) result.sphere.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
        if (sums.volumeOf[j] >= 0) result.volume[j].assign(cells, nan);
        if (sums.belowOf[j] >= 0) result.sphere[j].assign(cells, nan);
    }
    if (sums.radius.empty() || cells == 0) return result;
    // Three things independent of one another, side by side: the discs' quadratures, which
    // cells have every height of a ball (HeightCoverage), and the padded heights with the
    // extremes of their squares of 2 × 2 cells and the rows' prefix sums.
    std::vector<std::shared_ptr<const DiscSamples>> discs;
    std::optional<HeightCoverage> coverage;
    PaddedHeights heights(grid);
    tbb::parallel_invoke([&] { discs = discsOf(sums, options); }, [&] { coverage.emplace(grid); },
                         [&] { padHeights(grid, heights); });
    const DiscPlans plans = planDiscs(discs, options.cellWidth, options.cellHeight, heights.stride);
    const std::vector<Stored> stored = storedOf(options, sums, plans);
    const RowSums rowSums(grid, own, options, *coverage, heights, plans, stored, result);
    if (context) context->start("V and S from the heights", std::size_t(own.rows));
    tbb::parallel_for(tbb::blocked_range<int>(0, own.rows),
                      [&](const tbb::blocked_range<int>& range) { rowSums.rows(range.begin(), range.end(), context); });
    if (context) context->end();
    result.seconds = clock.seconds();
    return result;
}

} // namespace msii
