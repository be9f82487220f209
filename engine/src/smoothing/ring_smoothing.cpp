/// @file ring_smoothing.cpp
/// @brief Fast 1-ring smoothing (paper §3.2, Eq. 12–17), set up once per mesh.
///
/// Construction scans every vertex's ring twice (first to size the arrays, then to fill them,
/// so each vertex writes its own slice and the layout does not depend on the thread count)
/// and keeps, per vertex:
/// - a CSR row over the ring's neighbours: the neighbour's index, its Eq. 16 coefficient c_j
///   (all triangles that contain it merged) and its edge factor b_j = a_j/3 = Δ/(3|p_j − p0|);
/// - the ring's usable triangles: the two corners (as positions in the row) and the
///   normalised weight ω_t = w_t/A.
/// A mean pass is then one sparse matrix-vector product, a median pass one small sort per
/// vertex. Both are Jacobi iterations over two buffers of doubles (the float input is
/// rounded only once, at the end).

#include <msii/smoothing/ring_smoothing.h>

#include <msii/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace msii {

namespace {

constexpr double kPi = 3.14159265358979323846;
/// α is clamped below π so that the Balanced weight tan(α/2) stays finite.
constexpr double kMaxAngle = kPi - 1e-6;
/// Cumulative weights this close to 1/2 count as exactly 1/2 (Eq. 17's tie case): the
/// normalised weights of equal angles do not sum to exactly 1/2 in floating point.
constexpr double kTieTolerance = 1e-12;
/// Rings up to this many triangles are sorted in a stack array (regular meshes have 6).
constexpr std::size_t kSmallRing = 16;

/// A usable triangle of a ring as it is stored: its corners p_i, p_{i+1} as positions in the
/// vertex's CSR row, and ω_t = w_t/A.
struct RingTriangle {
    std::uint32_t i = 0, j = 0;
    double weight = 0;
};

/// A usable triangle while a ring is analysed.
struct UsableTriangle {
    std::uint32_t i, j;  ///< vertex indices of p_i, p_{i+1}
    double di, dj;       ///< |p_i − p0|, |p_{i+1} − p0|
    double alpha;        ///< angle at p0, in (0, kMaxAngle]
};

/// Per-thread-chunk buffers for analysing rings, so the scan allocates per chunk, not per
/// vertex.
struct RingScratch {
    std::vector<std::uint32_t> neighbours;  ///< unique ring neighbours, ascending
    std::vector<UsableTriangle> triangles;  ///< in incident-triangle order
    std::vector<std::uint32_t> usable;      ///< unique corners of usable triangles, ascending
};

/// What a ring scan found besides the scratch contents.
struct RingSummary {
    bool border = false;
    double ringMin = std::numeric_limits<double>::infinity();  ///< Eq. 12 (non-zero edges)
    std::size_t numEdgesAbove = 0;  ///< unique edges to neighbours with a larger index
};

/// Vertex → incident triangles, as CSR (triangles in ascending index order).
struct Incidence {
    std::vector<std::size_t> start;
    std::vector<std::uint32_t> triangles;
};

Incidence buildIncidence(const TriMesh& mesh)
{
    const std::size_t n = mesh.numVertices();
    Incidence inc;
    inc.start.assign(n + 1, 0);
    // A triangle with an out-of-range corner cannot be placed and is left out; a corner
    // repeated within a triangle is counted once.
    const auto valid = [&](const Triangle& t) {
        return t[0] < n && t[1] < n && t[2] < n;
    };
    const auto forEachCorner = [](const Triangle& t, auto&& body) {
        body(t[0]);
        if (t[1] != t[0]) body(t[1]);
        if (t[2] != t[0] && t[2] != t[1]) body(t[2]);
    };
    for (const Triangle& t : mesh.triangles)
        if (valid(t)) forEachCorner(t, [&](std::uint32_t v) { ++inc.start[v + 1]; });
    for (std::size_t v = 0; v < n; ++v) inc.start[v + 1] += inc.start[v];
    inc.triangles.resize(inc.start[n]);
    std::vector<std::size_t> fill(inc.start.begin(), inc.start.end() - 1);
    for (std::size_t f = 0; f < mesh.numTriangles(); ++f) {
        const Triangle& t = mesh.triangles[f];
        if (valid(t))
            forEachCorner(t, [&](std::uint32_t v) { inc.triangles[fill[v]++] = std::uint32_t(f); });
    }
    return inc;
}

/// The angle between two edges at p0, robust near 0 and π (unlike acos of the dot product).
double edgeAngle(const Vec3& ei, const Vec3& ej)
{
    return std::atan2(norm(cross(ei, ej)), dot(ei, ej));
}

/// Scans the ring of @p v: its neighbours, border flag, shortest non-zero edge (Eq. 12)
/// and usable triangles. A triangle is usable when both edges at p0 have a finite non-zero
/// length and the angle between them is non-zero; with @p keepBorder a border vertex gets
/// none (it keeps its value).
RingSummary scanRing(const TriMesh& mesh, const Incidence& inc, std::uint32_t v, bool keepBorder,
                     RingScratch& s)
{
    s.neighbours.clear();
    s.triangles.clear();
    s.usable.clear();
    RingSummary summary;
    const std::vector<Vec3>& points = mesh.points;
    const Vec3& p0 = points[v];
    const bool p0Finite = isFinite(p0);

    for (std::size_t k = inc.start[v]; k < inc.start[v + 1]; ++k) {
        const Triangle& t = mesh.triangles[inc.triangles[k]];
        // Rotate the triangle so that p0 comes first; its winding then gives (p_i, p_{i+1}).
        const int c = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
        const std::uint32_t i = t[(c + 1) % 3], j = t[(c + 2) % 3];
        if (i != v) s.neighbours.push_back(i);
        if (j != v && j != i) s.neighbours.push_back(j);
        if (i == v || j == v || !p0Finite) continue;  // a zero-length edge at p0
        if (!isFinite(points[i]) || !isFinite(points[j])) continue;
        const Vec3 ei = points[i] - p0, ej = points[j] - p0;
        const double di = norm(ei), dj = norm(ej);
        if (!(di > 0) || !(dj > 0)) continue;
        const double alpha = edgeAngle(ei, ej);
        if (!(alpha > 0)) continue;  // no area: f^t would be a duplicate of a neighbour's
        s.triangles.push_back({i, j, di, dj, std::min(alpha, kMaxAngle)});
    }

    // Unique neighbours; an edge that only one of the ring's triangles contains is a border
    // edge (non-manifold edges with three or more triangles are simply interior).
    std::sort(s.neighbours.begin(), s.neighbours.end());
    std::size_t numUnique = 0;
    for (std::size_t a = 0; a < s.neighbours.size();) {
        std::size_t b = a + 1;
        while (b < s.neighbours.size() && s.neighbours[b] == s.neighbours[a]) ++b;
        if (b - a == 1) summary.border = true;
        const std::uint32_t w = s.neighbours[a];
        s.neighbours[numUnique++] = w;
        if (p0Finite && isFinite(points[w])) {
            const double d = norm(points[w] - p0);
            if (d > 0) summary.ringMin = std::min(summary.ringMin, d);
            if (w > v) ++summary.numEdgesAbove;
        }
        a = b;
    }
    s.neighbours.resize(numUnique);

    if (keepBorder && summary.border) s.triangles.clear();
    for (const UsableTriangle& t : s.triangles) {
        s.usable.push_back(t.i);
        s.usable.push_back(t.j);
    }
    std::sort(s.usable.begin(), s.usable.end());
    s.usable.erase(std::unique(s.usable.begin(), s.usable.end()), s.usable.end());
    return summary;
}

struct Candidate {
    double value;   ///< f^t/3
    double weight;  ///< ω_t
};

/// Eq. 17 on candidates sorted by value: the first whose cumulative weight reaches half the
/// total; at exactly half (the tie case) the mean of it and the next.
double weightedMedian(const Candidate* c, std::size_t m, double totalWeight)
{
    double cumulative = 0;
    for (std::size_t k = 0; k < m; ++k) {
        cumulative += c[k].weight;
        const double fraction = cumulative / totalWeight;  // renormalised (NaN triangles)
        if (fraction >= 0.5 - kTieTolerance) {
            if (std::abs(fraction - 0.5) <= kTieTolerance && k + 1 < m)
                return 0.5 * (c[k].value + c[k + 1].value);
            return c[k].value;
        }
    }
    return c[m - 1].value;  // not reached: the last fraction is 1
}

/// Stable insertion sort by value: equal values keep the ring's triangle order, so the
/// result is deterministic; fastest for the usual ≤ 12 elements.
void insertionSort(Candidate* c, std::size_t m)
{
    for (std::size_t k = 1; k < m; ++k) {
        const Candidate x = c[k];
        std::size_t j = k;
        for (; j > 0 && c[j - 1].value > x.value; --j) c[j] = c[j - 1];
        c[j] = x;
    }
}

/// Vertex states for one smooth() call when some values are not finite.
constexpr std::uint8_t kRegular = 0, kMissingNeighbour = 1, kMissing = 2;

} // namespace

struct RingSmoother::Impl {
    SmoothingOptions options;
    SmoothingInfo info;
    std::size_t numVertices = 0;

    /// CSR row per vertex over the neighbours of its usable triangles (ascending index).
    std::vector<std::size_t> rowStart;
    std::vector<std::uint32_t> neighbour;
    /// Eq. 16 coefficient c_j = Σ_{t ∋ j} ω_t b_j (mean filter only).
    std::vector<double> meanCoefficient;
    /// b_j = a_j/3 = Δ/(3|p_j − p0|) (Eq. 13 with Eq. 14's factor 1/3).
    std::vector<double> edgeFactor;

    /// Usable triangles per vertex; needed by the median and by the mean where a neighbour
    /// is missing (NaN), since the linear row cannot drop single triangles.
    std::vector<std::size_t> triangleStart;
    std::vector<RingTriangle> triangles;

    void build(const TriMesh& mesh);
    void meanPass(const std::vector<double>& in, std::vector<double>& out,
                  const std::vector<std::uint8_t>& state) const;
    void medianPass(const std::vector<double>& in, std::vector<double>& out) const;

    /// f^t/3 for a stored triangle (Eq. 13–14), written relative to f0 so that a constant
    /// field is kept exactly whatever the rounding of b: f0 + b_i(f_i − f0) + b_j(f_j − f0)
    /// = ((3 − a_i − a_j) f0 + a_i f_i + a_j f_j)/3.
    double triangleValue(std::size_t row, const RingTriangle& t, double f0, double fi,
                         double fj) const
    {
        return f0 + edgeFactor[row + t.i] * (fi - f0) + edgeFactor[row + t.j] * (fj - f0);
    }
};

void RingSmoother::Impl::build(const TriMesh& mesh)
{
    const std::size_t n = mesh.numVertices();
    numVertices = n;
    const bool keepBorder = options.border == BorderMode::Keep;
    const bool storeMean = options.filter == SmoothingFilter::Mean;
    const Incidence inc = buildIncidence(mesh);

    // Pass 1: sizes (written at v + 1, turned into offsets below), flags and Eq. 12's Δ.
    rowStart.assign(n + 1, 0);
    triangleStart.assign(n + 1, 0);
    std::vector<std::size_t> edgeStart(n + 1, 0);
    std::vector<double> ringMin(n);
    std::vector<std::uint8_t> border(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const auto& r) {
        RingScratch s;
        for (std::size_t v = r.begin(); v < r.end(); ++v) {
            const RingSummary summary = scanRing(mesh, inc, std::uint32_t(v), keepBorder, s);
            rowStart[v + 1] = s.usable.size();
            triangleStart[v + 1] = s.triangles.size();
            edgeStart[v + 1] = summary.numEdgesAbove;
            ringMin[v] = summary.ringMin;
            border[v] = summary.border;
        }
    });
    double globalDelta = std::numeric_limits<double>::infinity();
    for (std::size_t v = 0; v < n; ++v) {
        globalDelta = std::min(globalDelta, ringMin[v]);
        if (border[v]) ++info.numBorderVertices;
        if (inc.start[v + 1] == inc.start[v]) ++info.numIsolatedVertices;
        rowStart[v + 1] += rowStart[v];
        triangleStart[v + 1] += triangleStart[v];
        edgeStart[v + 1] += edgeStart[v];
    }
    info.globalDelta = std::isfinite(globalDelta) ? globalDelta : 0.0;

    neighbour.resize(rowStart[n]);
    edgeFactor.resize(rowStart[n]);
    if (storeMean) meanCoefficient.assign(rowStart[n], 0.0);
    triangles.resize(triangleStart[n]);
    std::vector<double> edgeLengths(edgeStart[n]);

    // Pass 2: each vertex fills its own slices.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const auto& r) {
        RingScratch s;
        std::vector<double> weights;
        for (std::size_t v = r.begin(); v < r.end(); ++v) {
            const RingSummary summary = scanRing(mesh, inc, std::uint32_t(v), keepBorder, s);
            const Vec3& p0 = mesh.points[v];
            std::size_t e = edgeStart[v];
            for (std::uint32_t w : s.neighbours)
                if (w > v && isFinite(p0) && isFinite(mesh.points[w]))
                    edgeLengths[e++] = norm(mesh.points[w] - p0);
            if (s.triangles.empty()) continue;

            // Eq. 12: the paper's global Δ, or the ring's own.
            const double delta =
                options.radius == RingRadius::Global ? info.globalDelta : summary.ringMin;
            // Per-triangle weights. Balanced: tan(α/2), for which Σ_t w_t (u_i + u_{i+1}) = 0
            // on a flat closed ring (each term is u_{i+1} − u_i turned by 90°), i.e. the small
            // triangles' weighted centroid is p0 and Eq. 16 keeps linear functions.
            // IsoscelesArea (Eq. 15): A'_t = (b/4)·sqrt(4Δ² − b²) with b = |p'_i − p'_{i+1}|
            // = 2Δ sin(α/2), i.e. Δ² sin(α)/2; Δ² is common to the ring and cancels in ω_t,
            // and the sine form avoids the cancellation in 4Δ² − b² near α = π.
            weights.clear();
            double area = 0;  // A
            for (const UsableTriangle& t : s.triangles) {
                const double w = options.weights == RingWeights::Balanced
                                     ? std::tan(0.5 * t.alpha)
                                     : 0.5 * std::sin(t.alpha);
                weights.push_back(w);
                area += w;
            }

            const std::size_t row = rowStart[v];
            std::copy(s.usable.begin(), s.usable.end(), neighbour.begin() + std::ptrdiff_t(row));
            const auto position = [&](std::uint32_t w) {
                return std::uint32_t(std::lower_bound(s.usable.begin(), s.usable.end(), w) -
                                     s.usable.begin());
            };
            for (std::size_t k = 0; k < s.triangles.size(); ++k) {
                const UsableTriangle& t = s.triangles[k];
                const double omega = weights[k] / area;
                const std::uint32_t li = position(t.i), lj = position(t.j);
                // Eq. 13: a = Δ/|p_j − p0| ≤ 1, as Δ is at most every non-zero edge at p0.
                const double bi = delta / (3 * t.di), bj = delta / (3 * t.dj);
                edgeFactor[row + li] = bi;
                edgeFactor[row + lj] = bj;
                if (storeMean) {
                    // Eq. 16 expanded: f̃0 = f0 + Σ_t ω_t (b_i (f_i − f0) + b_j (f_j − f0)).
                    meanCoefficient[row + li] += omega * bi;
                    meanCoefficient[row + lj] += omega * bj;
                }
                triangles[triangleStart[v] + k] = {li, lj, omega};
            }
        }
    });

    if (!edgeLengths.empty()) {
        const auto middle = edgeLengths.begin() + std::ptrdiff_t(edgeLengths.size() / 2);
        std::nth_element(edgeLengths.begin(), middle, edgeLengths.end());
        info.medianEdge = *middle;
    }
    info.globalDeltaTooSmall = info.globalDelta < 0.1 * info.medianEdge;
}

void RingSmoother::Impl::meanPass(const std::vector<double>& in, std::vector<double>& out,
                                  const std::vector<std::uint8_t>& state) const
{
    const bool anyMissing = !state.empty();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, numVertices), [&](const auto& r) {
        for (std::size_t v = r.begin(); v < r.end(); ++v) {
            const double f0 = in[v];
            const std::uint8_t s = anyMissing ? state[v] : kRegular;
            if (s == kRegular) {
                // Eq. 16 as one sparse row: f0 + Σ_j c_j (f_j − f0). The difference form
                // keeps constants exactly; f0's own coefficient is 1 − Σ_j c_j.
                double sum = 0;
                for (std::size_t e = rowStart[v]; e < rowStart[v + 1]; ++e)
                    sum += meanCoefficient[e] * (in[neighbour[e]] - f0);
                out[v] = f0 + sum;
            } else if (s == kMissing) {
                out[v] = f0;
            } else {
                // Eq. 16 over the triangles without a missing corner, weights renormalised.
                const std::size_t row = rowStart[v];
                double sum = 0, total = 0;
                for (std::size_t k = triangleStart[v]; k < triangleStart[v + 1]; ++k) {
                    const RingTriangle& t = triangles[k];
                    const double fi = in[neighbour[row + t.i]], fj = in[neighbour[row + t.j]];
                    if (!std::isfinite(fi) || !std::isfinite(fj)) continue;
                    sum += t.weight * (triangleValue(row, t, f0, fi, fj) - f0);
                    total += t.weight;
                }
                out[v] = total > 0 ? f0 + sum / total : f0;
            }
        }
    });
}

void RingSmoother::Impl::medianPass(const std::vector<double>& in, std::vector<double>& out) const
{
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, numVertices), [&](const auto& r) {
        std::array<Candidate, kSmallRing> small;
        std::vector<Candidate> large;  // rings of more than kSmallRing triangles (rare)
        for (std::size_t v = r.begin(); v < r.end(); ++v) {
            const double f0 = in[v];
            const std::size_t begin = triangleStart[v], end = triangleStart[v + 1];
            if (!std::isfinite(f0) || begin == end) {
                out[v] = f0;
                continue;
            }
            Candidate* c = small.data();
            if (end - begin > kSmallRing) {
                large.resize(end - begin);
                c = large.data();
            }
            const std::size_t row = rowStart[v];
            std::size_t m = 0;
            double total = 0;
            for (std::size_t k = begin; k < end; ++k) {
                const RingTriangle& t = triangles[k];
                const double fi = in[neighbour[row + t.i]], fj = in[neighbour[row + t.j]];
                if (!std::isfinite(fi) || !std::isfinite(fj)) continue;  // missing corner
                c[m++] = {triangleValue(row, t, f0, fi, fj), t.weight};  // f^t/3, Eq. 14
                total += t.weight;
            }
            if (m == 0) {
                out[v] = f0;
                continue;
            }
            if (m <= kSmallRing)
                insertionSort(c, m);
            else
                std::stable_sort(c, c + m, [](const Candidate& a, const Candidate& b) {
                    return a.value < b.value;
                });
            out[v] = weightedMedian(c, m, total);  // Eq. 17
        }
    });
}

RingSmoother::RingSmoother(const TriMesh& mesh, const SmoothingOptions& options)
    : mImpl(std::make_unique<Impl>())
{
    if (options.iterations < 0)
        throw InvalidInputError("the number of smoothing iterations must not be negative (got " +
                                std::to_string(options.iterations) + ")");
    if (mesh.empty()) throw InvalidInputError("cannot smooth on a mesh without triangles");
    if (mesh.numVertices() > std::numeric_limits<std::uint32_t>::max() ||
        mesh.numTriangles() > std::numeric_limits<std::uint32_t>::max())
        throw InvalidInputError("the mesh is too large to smooth (more than 2^32 elements)");
    mImpl->options = options;
    mImpl->build(mesh);
}

RingSmoother::~RingSmoother() = default;
RingSmoother::RingSmoother(RingSmoother&&) noexcept = default;
RingSmoother& RingSmoother::operator=(RingSmoother&&) noexcept = default;

const SmoothingInfo& RingSmoother::info() const { return mImpl->info; }

const SmoothingOptions& RingSmoother::options() const { return mImpl->options; }

void RingSmoother::smooth(std::vector<float>& values, Progress* progress) const
{
    const Impl& impl = *mImpl;
    const std::size_t n = impl.numVertices;
    if (values.size() != n)
        throw InvalidInputError("cannot smooth " + std::to_string(values.size()) +
                                " values on a mesh of " + std::to_string(n) + " vertices");
    const int iterations = impl.options.iterations;
    if (progress) progress->start("smoothing", std::size_t(iterations));
    if (iterations > 0) {
        std::vector<double> current(values.begin(), values.end()), next(n);

        // Missing (non-finite) values stay missing and finite ones stay finite, so which
        // vertices need the per-triangle mean is decided once for all passes.
        std::vector<std::uint8_t> state;
        const bool mean = impl.options.filter == SmoothingFilter::Mean;
        if (mean && !std::all_of(values.begin(), values.end(),
                                 [](float f) { return std::isfinite(f); })) {
            state.assign(n, kRegular);
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const auto& r) {
                for (std::size_t v = r.begin(); v < r.end(); ++v) {
                    if (!std::isfinite(current[v])) {
                        state[v] = kMissing;
                        continue;
                    }
                    for (std::size_t e = impl.rowStart[v]; e < impl.rowStart[v + 1]; ++e)
                        if (!std::isfinite(current[impl.neighbour[e]])) {
                            state[v] = kMissingNeighbour;
                            break;
                        }
                }
            });
        }

        for (int pass = 0; pass < iterations; ++pass) {
            if (mean)
                impl.meanPass(current, next, state);
            else
                impl.medianPass(current, next);
            current.swap(next);
            if (progress) progress->advance();
        }
        for (std::size_t v = 0; v < n; ++v) values[v] = float(current[v]);
    }
    if (progress) progress->end();
}

SmoothingInfo smoothField(const TriMesh& mesh, std::vector<float>& values,
                          const SmoothingOptions& options, Progress* progress)
{
    const RingSmoother smoother(mesh, options);
    smoother.smooth(values, progress);
    return smoother.info();
}

} // namespace msii
