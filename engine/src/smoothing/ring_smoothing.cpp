/// @file ring_smoothing.cpp
/// @brief Fast 1-ring smoothing (paper §3.2, Eq. 12–17), set up once per mesh.
///
/// Construction scans every vertex's ring once and keeps, per vertex:
/// - a CSR row over the neighbours of its usable triangles: the neighbour's index, its edge
///   factor b_j = a_j/3 = Δ/(3|p_j − p0|) and its Eq. 16 coefficient c_j (all triangles that
///   contain it merged);
/// - its usable triangles: the two corners (as positions in the row) and the normalised
///   weight ω_t = w_t/A.
/// A mean pass is then one sparse matrix-vector product, a median pass one small sort per
/// vertex. Both are Jacobi iterations over two buffers of doubles (the float input is
/// rounded only once, at the end).
///
/// The rows live in blocks of a fixed number of vertices, each filled by one task into its
/// own arrays: one scan is enough (no counting pass), and neither the layout nor any result
/// depends on the number of threads.

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
/// α is clamped to at most π − 1e-6 so that the Balanced weight tan(α/2) stays finite.
constexpr double kMaxAngle = kPi - 1e-6;
const double kMaxTanHalf = std::tan(0.5 * kMaxAngle);
const double kMinSinObtuse = std::sin(kMaxAngle);
/// Cumulative weights this close to 1/2 count as exactly 1/2 (Eq. 17's tie case): the
/// normalised weights of equal angles do not sum to exactly 1/2 in floating point.
constexpr double kTieTolerance = 1e-12;
/// Rings up to this many triangles are sorted in a stack array (regular meshes have 6).
constexpr std::size_t kSmallRing = 16;
/// Vertices per block of rows (a fixed number, so the layout does not depend on threads).
constexpr std::size_t kBlockVertices = 4096;

/// A usable triangle of a ring as it is stored: its corners p_i, p_{i+1} as positions in the
/// vertex's CSR row, and ω_t = w_t/A.
struct RingTriangle {
    std::uint32_t i = 0, j = 0;
    double weight = 0;
};

/// The rows of vertices [begin, end). Offsets are local to the block.
struct RingBlock {
    std::size_t begin = 0, end = 0;
    std::vector<std::uint32_t> rowStart;       ///< per vertex, + 1 at the end
    std::vector<std::uint32_t> neighbour;      ///< neighbours, ascending per row
    std::vector<double> edgeFactor;            ///< b_j; |p_j − p0| until Δ is known
    std::vector<double> meanCoefficient;       ///< c_j; Σ_{t ∋ j} ω_t until Δ is known
    std::vector<std::uint32_t> triangleStart;  ///< per vertex, + 1 at the end
    std::vector<RingTriangle> triangles;
    // Construction only:
    std::vector<double> ringDelta;    ///< Eq. 12 per vertex (shortest non-zero edge)
    std::vector<double> edgeLengths;  ///< unique edges to neighbours with a larger index
    std::size_t numBorder = 0, numIsolated = 0;
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
    const auto valid = [&](const Triangle& t) { return t[0] < n && t[1] < n && t[2] < n; };
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

/// A usable triangle while a ring is scanned.
struct UsableTriangle {
    std::uint32_t i, j;  ///< vertex indices of p_i, p_{i+1}
    double di, dj;       ///< |p_i − p0|, |p_{i+1} − p0|
    double weight;       ///< w_t (RingWeights), before normalisation
};

/// Per-task buffers for scanning rings, so that the scan allocates per block, not per vertex.
struct RingScratch {
    std::vector<std::uint32_t> neighbours;  ///< unique ring neighbours, ascending
    std::vector<UsableTriangle> triangles;  ///< in incident-triangle order
    std::vector<std::uint32_t> usable;      ///< unique corners of usable triangles, ascending
};

/// The triangle weight w_t from the edges e_i = p_i − p0, e_j = p_{i+1} − p0 at p0, with
/// s = |e_i × e_j| = |e_i||e_j| sin α and c = e_i·e_j = |e_i||e_j| cos α.
/// - Balanced: tan(α/2) = sin α/(1 + cos α) = s/(|e_i||e_j| + c). With these weights
///   Σ_t w_t (u_i + u_{i+1}) = 0 on a flat closed ring (each term is u_{i+1} − u_i turned by
///   90°), i.e. the small triangles' weighted centroid is p0 and Eq. 16 keeps linear
///   functions.
/// - IsoscelesArea (Eq. 15): A'_t = (b/4)·sqrt(4Δ² − b²) with b = |p'_i − p'_{i+1}| =
///   2Δ sin(α/2), i.e. Δ² sin(α)/2. Δ² is common to the ring and cancels in ω_t = w_t/A, so
///   sin(α)/2 is used; the sine form also avoids the cancellation in 4Δ² − b² near α = π.
/// Both use α clamped to at most kMaxAngle.
double triangleWeight(RingWeights weights, double s, double c, double lengths)
{
    if (weights == RingWeights::Balanced) {
        const double denominator = lengths + c;
        return denominator > 0 ? std::min(s / denominator, kMaxTanHalf) : kMaxTanHalf;
    }
    const double sine = s / lengths;
    return 0.5 * (c < 0 ? std::max(sine, kMinSinObtuse) : sine);
}

/// Scans the ring of vertex @p v into @p block (its rows, usable triangles, Eq. 12's Δ,
/// border flag and edges). A triangle is usable when both edges at p0 have a finite non-zero
/// length and the angle between them is not zero; with @p keepBorder a border vertex (an
/// edge at p0 with a single triangle) gets none and keeps its value.
void scanRing(const TriMesh& mesh, const Incidence& inc, std::size_t v,
              const SmoothingOptions& options, bool storeMean, RingScratch& s, RingBlock& block)
{
    s.neighbours.clear();
    s.triangles.clear();
    s.usable.clear();
    const std::vector<Vec3>& points = mesh.points;
    const Vec3& p0 = points[v];
    const bool p0Finite = isFinite(p0);
    if (inc.start[v] == inc.start[v + 1]) ++block.numIsolated;

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
        const double sine = norm(cross(ei, ej)), cosine = dot(ei, ej);
        if (!(sine > 0) && !(cosine < 0)) continue;  // α = 0: no area
        s.triangles.push_back({i, j, di, dj, triangleWeight(options.weights, sine, cosine, di * dj)});
    }

    // Unique neighbours; an edge that only one of the ring's triangles contains is a border
    // edge (non-manifold edges with three or more triangles are simply interior).
    std::sort(s.neighbours.begin(), s.neighbours.end());
    bool border = false;
    double ringMin2 = std::numeric_limits<double>::infinity();
    for (std::size_t a = 0; a < s.neighbours.size();) {
        std::size_t b = a + 1;
        while (b < s.neighbours.size() && s.neighbours[b] == s.neighbours[a]) ++b;
        if (b - a == 1) border = true;
        const std::uint32_t w = s.neighbours[a];
        if (p0Finite && isFinite(points[w])) {
            const double d2 = squaredNorm(points[w] - p0);
            if (d2 > 0) ringMin2 = std::min(ringMin2, d2);
            if (w > v) block.edgeLengths.push_back(std::sqrt(d2));
        }
        a = b;
    }
    if (border) ++block.numBorder;
    // sqrt is monotone and correctly rounded: this is exactly the shortest norm().
    block.ringDelta.push_back(std::sqrt(ringMin2));

    double area = 0;  // A
    for (const UsableTriangle& t : s.triangles) area += t.weight;
    if ((options.border == BorderMode::Keep && border) || !(area > 0) || !std::isfinite(area))
        s.triangles.clear();

    for (const UsableTriangle& t : s.triangles) {
        s.usable.push_back(t.i);
        s.usable.push_back(t.j);
    }
    std::sort(s.usable.begin(), s.usable.end());
    s.usable.erase(std::unique(s.usable.begin(), s.usable.end()), s.usable.end());

    // The row: neighbours with their edge lengths (turned into b_j once Δ is known) and,
    // for the mean, Σ_{t ∋ j} ω_t (turned into c_j = b_j Σ_{t ∋ j} ω_t).
    const std::size_t row = block.neighbour.size();
    block.neighbour.insert(block.neighbour.end(), s.usable.begin(), s.usable.end());
    block.edgeFactor.resize(block.neighbour.size());
    if (storeMean) block.meanCoefficient.resize(block.neighbour.size(), 0.0);
    const auto position = [&](std::uint32_t w) {
        return std::uint32_t(std::lower_bound(s.usable.begin(), s.usable.end(), w) -
                             s.usable.begin());
    };
    for (const UsableTriangle& t : s.triangles) {
        const double omega = t.weight / area;
        const std::uint32_t li = position(t.i), lj = position(t.j);
        block.edgeFactor[row + li] = t.di;
        block.edgeFactor[row + lj] = t.dj;
        if (storeMean) {
            block.meanCoefficient[row + li] += omega;
            block.meanCoefficient[row + lj] += omega;
        }
        block.triangles.push_back({li, lj, omega});
    }
    block.rowStart.push_back(std::uint32_t(block.neighbour.size()));
    block.triangleStart.push_back(std::uint32_t(block.triangles.size()));
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

/// f^t/3 for a stored triangle (Eq. 13–14), written relative to f0 so that a constant field
/// is kept exactly whatever the rounding of b: f0 + b_i(f_i − f0) + b_j(f_j − f0)
/// = ((3 − a_i − a_j) f0 + a_i f_i + a_j f_j)/3.
inline double triangleValue(const double* b, const RingTriangle& t, double f0, double fi,
                            double fj)
{
    return f0 + b[t.i] * (fi - f0) + b[t.j] * (fj - f0);
}

} // namespace

struct RingSmoother::Impl {
    SmoothingOptions options;
    SmoothingInfo info;
    std::size_t numVertices = 0;
    std::vector<RingBlock> blocks;

    void build(const TriMesh& mesh);
    /// Runs body(block, local vertex, vertex) for every vertex, blocks in parallel.
    template <class Body>
    void forEachVertex(const Body& body) const;
    void meanPass(const std::vector<double>& in, std::vector<double>& out,
                  const std::vector<std::uint8_t>& state) const;
    void medianPass(const std::vector<double>& in, std::vector<double>& out) const;
};

template <class Body>
void RingSmoother::Impl::forEachVertex(const Body& body) const
{
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size()), [&](const auto& r) {
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            const RingBlock& block = blocks[b];
            for (std::size_t v = block.begin; v < block.end; ++v) body(block, v - block.begin, v);
        }
    });
}

void RingSmoother::Impl::build(const TriMesh& mesh)
{
    const std::size_t n = mesh.numVertices();
    numVertices = n;
    const bool storeMean = options.filter == SmoothingFilter::Mean;
    const Incidence inc = buildIncidence(mesh);

    blocks.resize((n + kBlockVertices - 1) / kBlockVertices);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size()), [&](const auto& r) {
        RingScratch s;
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            RingBlock& block = blocks[b];
            block.begin = b * kBlockVertices;
            block.end = std::min(n, block.begin + kBlockVertices);
            // Closed manifold rings have as many neighbours as triangles.
            const std::size_t incident = inc.start[block.end] - inc.start[block.begin];
            const std::size_t rowEstimate = incident + incident / 8;
            const std::size_t count = block.end - block.begin;
            block.neighbour.reserve(rowEstimate);
            block.edgeFactor.reserve(rowEstimate);
            if (storeMean) block.meanCoefficient.reserve(rowEstimate);
            block.triangles.reserve(incident);
            block.rowStart.reserve(count + 1);
            block.triangleStart.reserve(count + 1);
            block.ringDelta.reserve(count);
            block.edgeLengths.reserve(incident / 2 + count / 8);  // ~3 per vertex on a grid
            block.rowStart.push_back(0);
            block.triangleStart.push_back(0);
            for (std::size_t v = block.begin; v < block.end; ++v)
                scanRing(mesh, inc, v, options, storeMean, s, block);
        }
    });

    // Eq. 12: the global Δ is the shortest non-zero edge of all rings.
    double globalDelta = std::numeric_limits<double>::infinity();
    std::size_t numEdges = 0;
    for (const RingBlock& block : blocks) {
        for (double d : block.ringDelta) globalDelta = std::min(globalDelta, d);
        info.numBorderVertices += block.numBorder;
        info.numIsolatedVertices += block.numIsolated;
        numEdges += block.edgeLengths.size();
    }
    info.globalDelta = std::isfinite(globalDelta) ? globalDelta : 0.0;

    // Now that Δ is known: b_j = Δ/(3|p_j − p0|) (Eq. 13, a_j = Δ/|p_j − p0| ≤ 1 since Δ is
    // at most every non-zero edge at p0; Eq. 14's 1/3) and c_j = b_j Σ_{t ∋ j} ω_t, from
    // Eq. 16 expanded: f̃0 = f0 + Σ_t ω_t (b_i (f_i − f0) + b_j (f_j − f0)).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size()), [&](const auto& r) {
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            RingBlock& block = blocks[b];
            for (std::size_t local = 0; local + block.begin < block.end; ++local) {
                const double delta = options.radius == RingRadius::Global
                                         ? info.globalDelta
                                         : block.ringDelta[local];
                for (std::uint32_t e = block.rowStart[local]; e < block.rowStart[local + 1]; ++e) {
                    block.edgeFactor[e] = delta / (3 * block.edgeFactor[e]);
                    if (storeMean) block.meanCoefficient[e] *= block.edgeFactor[e];
                }
            }
            block.ringDelta = {};
        }
    });

    std::vector<double> edgeLengths;
    edgeLengths.reserve(numEdges);
    for (RingBlock& block : blocks) {
        edgeLengths.insert(edgeLengths.end(), block.edgeLengths.begin(), block.edgeLengths.end());
        block.edgeLengths = {};
    }
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
    forEachVertex([&](const RingBlock& block, std::size_t local, std::size_t v) {
        const double f0 = in[v];
        const std::uint32_t rowBegin = block.rowStart[local], rowEnd = block.rowStart[local + 1];
        const std::uint8_t s = anyMissing ? state[v] : kRegular;
        if (s == kRegular) {
            // Eq. 16 as one sparse row: f0 + Σ_j c_j (f_j − f0). The difference form keeps
            // constants exactly; f0's own coefficient is 1 − Σ_j c_j.
            double sum = 0;
            for (std::uint32_t e = rowBegin; e < rowEnd; ++e)
                sum += block.meanCoefficient[e] * (in[block.neighbour[e]] - f0);
            out[v] = f0 + sum;
        } else if (s == kMissing) {
            out[v] = f0;
        } else {
            // Eq. 16 over the triangles without a missing corner, weights renormalised.
            const std::uint32_t* neighbour = block.neighbour.data() + rowBegin;
            const double* b = block.edgeFactor.data() + rowBegin;
            double sum = 0, total = 0;
            for (std::uint32_t k = block.triangleStart[local]; k < block.triangleStart[local + 1];
                 ++k) {
                const RingTriangle& t = block.triangles[k];
                const double fi = in[neighbour[t.i]], fj = in[neighbour[t.j]];
                if (!std::isfinite(fi) || !std::isfinite(fj)) continue;
                sum += t.weight * (triangleValue(b, t, f0, fi, fj) - f0);
                total += t.weight;
            }
            out[v] = total > 0 ? f0 + sum / total : f0;
        }
    });
}

void RingSmoother::Impl::medianPass(const std::vector<double>& in, std::vector<double>& out) const
{
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size()), [&](const auto& r) {
        std::array<Candidate, kSmallRing> small;
        std::vector<Candidate> large;  // rings of more than kSmallRing triangles (rare)
        for (std::size_t blockIndex = r.begin(); blockIndex < r.end(); ++blockIndex) {
            const RingBlock& block = blocks[blockIndex];
            for (std::size_t local = 0; local + block.begin < block.end; ++local) {
                const std::size_t v = block.begin + local;
                const double f0 = in[v];
                const std::uint32_t begin = block.triangleStart[local],
                                    end = block.triangleStart[local + 1];
                if (!std::isfinite(f0) || begin == end) {
                    out[v] = f0;
                    continue;
                }
                Candidate* c = small.data();
                if (end - begin > kSmallRing) {
                    large.resize(end - begin);
                    c = large.data();
                }
                const std::uint32_t rowBegin = block.rowStart[local];
                const std::uint32_t* neighbour = block.neighbour.data() + rowBegin;
                const double* b = block.edgeFactor.data() + rowBegin;
                std::size_t m = 0;
                double total = 0;
                for (std::uint32_t k = begin; k < end; ++k) {
                    const RingTriangle& t = block.triangles[k];
                    const double fi = in[neighbour[t.i]], fj = in[neighbour[t.j]];
                    if (!std::isfinite(fi) || !std::isfinite(fj)) continue;  // missing corner
                    c[m++] = {triangleValue(b, t, f0, fi, fj), t.weight};  // f^t/3, Eq. 14
                    total += t.weight;
                }
                if (m == 0) {
                    out[v] = f0;
                    continue;
                }
                if (m <= kSmallRing)
                    insertionSort(c, m);
                else
                    std::stable_sort(c, c + m, [](const Candidate& x, const Candidate& y) {
                        return x.value < y.value;
                    });
                out[v] = weightedMedian(c, m, total);  // Eq. 17
            }
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

void RingSmoother::smooth(std::vector<float>& values, RunContext* progress) const
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
            impl.forEachVertex([&](const RingBlock& block, std::size_t local, std::size_t v) {
                if (!std::isfinite(current[v])) {
                    state[v] = kMissing;
                    return;
                }
                for (std::uint32_t e = block.rowStart[local]; e < block.rowStart[local + 1]; ++e)
                    if (!std::isfinite(current[block.neighbour[e]])) {
                        state[v] = kMissingNeighbour;
                        return;
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
                          const SmoothingOptions& options, RunContext* progress)
{
    const RingSmoother smoother(mesh, options);
    smoother.smooth(values, progress);
    return smoother.info();
}

} // namespace msii
