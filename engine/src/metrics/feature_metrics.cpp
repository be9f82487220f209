#include <msii/metrics/feature_metrics.h>

#include <msii/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace msii {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Vertices per task of the per-vertex pass: enough work to amortise scheduling.
constexpr std::size_t kVertexGrain = 512;

/// Vertices per partial sum of the variances of NormalizedEuclidean. Fixed (not per thread)
/// so that the partial sums, and the order they are merged in, do not depend on the thread
/// count; small enough that a chunk stays in cache for its second pass.
constexpr std::size_t kVarianceChunk = 2048;

/// A number for messages: "0.1", "nan", "inf" (not to_string's "0.100000").
std::string numberText(double value)
{
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", value);
    return buf;
}

/// "V_03" for element @p j (0-based) of a block, as the feature properties are named.
std::string elementLabel(Invariant invariant, std::size_t j)
{
    char buf[32];
    std::snprintf(buf, sizeof buf, "%c_%02zu", invariantLetter(invariant), j + 1);
    return buf;
}

/// The label of element @p e of the concatenated feature vector.
std::string elementLabel(const FeatureTable& table, std::size_t e)
{
    for (const FeatureBlock& b : table.blocks) {
        if (e < std::size_t(b.count)) return elementLabel(b.invariant, e);
        e -= std::size_t(b.count);
    }
    return "element " + std::to_string(e + 1);
}

/// "V×16, P×16", for messages about the layout of the feature vectors.
std::string layoutText(const FeatureTable& table)
{
    std::string text;
    for (const FeatureBlock& b : table.blocks)
        text += (text.empty() ? "" : ", ") + std::string(1, invariantLetter(b.invariant)) + "×" +
                std::to_string(b.count);
    return text;
}

/// @throw InvalidInputError if the table has no blocks or a block has no elements.
void validateBlocks(const FeatureTable& table)
{
    if (table.blocks.empty()) throw InvalidInputError("the feature table has no feature blocks");
    for (const FeatureBlock& b : table.blocks)
        if (b.count < 1)
            throw InvalidInputError(std::string("the feature block ") + invariantLetter(b.invariant) +
                                    " has " + std::to_string(b.count) + " elements (at least 1 needed)");
}

/// validateBlocks(), and values.size() == numVertices · dimension().
void validateTable(const FeatureTable& table)
{
    validateBlocks(table);
    const std::size_t expected = table.numVertices * table.dimension();
    if (table.values.size() != expected)
        throw InvalidInputError("the feature table holds " + std::to_string(table.values.size()) +
                                " values, but " + std::to_string(table.numVertices) + " vertices × " +
                                std::to_string(table.dimension()) + " elements need " +
                                std::to_string(expected));
}

/// @throw InvalidInputError if @p reference has the wrong length or a NaN (or infinite) value.
void validateReference(const FeatureTable& table, const std::vector<double>& reference)
{
    if (reference.size() != table.dimension())
        throw InvalidInputError("the reference has " + std::to_string(reference.size()) +
                                " values, but the feature vectors have " +
                                std::to_string(table.dimension()) + " (" + layoutText(table) + ")");
    for (std::size_t e = 0; e < reference.size(); ++e)
        if (!std::isfinite(reference[e]))
            throw InvalidInputError("the reference value of " + elementLabel(table, e) + " is " +
                                    numberText(reference[e]) + " (it must be a finite number)");
}

/// True if any element of the row is NaN (masked): f is then NaN.
inline bool hasNaN(const float* x, std::size_t n)
{
    bool nan = false;
    for (std::size_t e = 0; e < n; ++e) nan |= std::isnan(x[e]);
    return nan;
}

/// One block of the concatenated feature vector, with what Eq. 11 needs of it.
struct BlockSpan {
    std::size_t offset = 0;
    std::size_t count = 0;
    bool triangular = false;  ///< W of Eq. 9/10 (V, P); false: identity (S, L)
};

/// The blocks of @p table with their offsets in the concatenated vector.
std::vector<BlockSpan> blockSpans(const FeatureTable& table)
{
    std::vector<BlockSpan> spans;
    std::size_t offset = 0;
    for (const FeatureBlock& b : table.blocks) {
        const bool triangular = b.invariant == Invariant::Volume || b.invariant == Invariant::Patch;
        spans.push_back({offset, std::size_t(b.count), triangular});
        offset += std::size_t(b.count);
    }
    return spans;
}

/// f = kernel(row) for every vertex, in parallel. Each vertex is computed on its own, so the
/// result does not depend on the thread count.
template <class Kernel>
std::vector<float> forEachVertex(const FeatureTable& table, const Kernel& kernel)
{
    const std::size_t dim = table.dimension();
    std::vector<float> out(table.numVertices);
    const float* values = table.values.data();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, table.numVertices, kVertexGrain),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t i = range.begin(); i != range.end(); ++i) {
                              const float* x = values + i * dim;
                              out[i] = hasNaN(x, dim) ? float(kNaN) : float(kernel(x));
                          }
                      });
    return out;
}

/// The per-element scale weights w_e of Eq. 4–6, block after block.
std::vector<double> elementWeights(const FeatureTable& table)
{
    std::vector<double> w;
    w.reserve(table.dimension());
    for (const FeatureBlock& b : table.blocks) {
        const std::vector<double> bw = scaleWeights(b.invariant, b.count);
        w.insert(w.end(), bw.begin(), bw.end());
    }
    return w;
}

/// (Σ_e w_e |x_e − o_e|^p)^(1/p), w_e = 1 or the scale weights of Eq. 4–6; p = ∞: the
/// maximum of w_e |x_e − o_e|.
std::vector<float> pNorm(const FeatureTable& table, const std::vector<double>& o, const MetricOptions& opt)
{
    const std::size_t dim = table.dimension();
    // Unweighted is weighted with 1, which is exact; one code path for both.
    const std::vector<double> w = opt.weighted ? elementWeights(table) : std::vector<double>(dim, 1.0);
    const double* wp = w.data();
    const double* op = o.data();
    const double p = opt.p;
    if (std::isinf(p))
        return forEachVertex(table, [=](const float* x) {
            double m = 0;
            for (std::size_t e = 0; e < dim; ++e) m = std::max(m, wp[e] * std::abs(double(x[e]) - op[e]));
            return m;
        });
    if (p == 1)
        return forEachVertex(table, [=](const float* x) {
            double s = 0;
            for (std::size_t e = 0; e < dim; ++e) s += wp[e] * std::abs(double(x[e]) - op[e]);
            return s;
        });
    if (p == 2)
        return forEachVertex(table, [=](const float* x) {
            double s = 0;
            for (std::size_t e = 0; e < dim; ++e) {
                const double d = double(x[e]) - op[e];
                s += wp[e] * d * d;
            }
            return std::sqrt(s);
        });
    if (p <= 64 && std::floor(2 * p) == 2 * p) {
        // Integer and half-integer p (the usual choices, incl. 3 and 0.5): |d|^p by squaring
        // and one sqrt, several times faster than pow() per element, which is the whole
        // cost otherwise.
        const unsigned whole = unsigned(std::floor(p));
        const bool half = std::floor(p) != p;
        const double invP = 1.0 / p;
        return forEachVertex(table, [=](const float* x) {
            double s = 0;
            for (std::size_t e = 0; e < dim; ++e) {
                const double d = std::abs(double(x[e]) - op[e]);
                double power = half ? std::sqrt(d) : 1.0, base = d;
                for (unsigned k = whole; k != 0; k >>= 1) {
                    if (k & 1u) power *= base;
                    base *= base;
                }
                s += wp[e] * power;
            }
            return std::pow(s, invP);
        });
    }
    // Any other p: powf is about twice as fast as pow and as exact as the float output
    // (relative error < 1e-7 per term).
    const double invP = 1.0 / p;
    const float pf = float(p);
    return forEachVertex(table, [=](const float* x) {
        double s = 0;
        for (std::size_t e = 0; e < dim; ++e)
            s += wp[e] * double(std::pow(float(std::abs(double(x[e]) - op[e])), pf));
        return std::pow(s, invP);
    });
}

/// f = sqrt(q), q = (x − o) W (x − o)ᵀ (Eq. 11) with W block-diagonal of Eq. 9 (V), Eq. 10 (P) and the identity (S, L).
std::vector<float> mahalanobis(const FeatureTable& table, const std::vector<double>& o)
{
    // w_{j,k} = a_j / b_k for j ≤ k (1-based): V a_j = 3j² − 3j + 1, b_k = k³ (Eq. 9);
    // P a_j = 2j − 1, b_k = k² (Eq. 10). Then Σ_{k≥j} w_{j,k} d_k = a_j · Σ_{k≥j} d_k / b_k,
    // a suffix sum: q costs O(n) per block instead of O(n²).
    const std::size_t dim = table.dimension();
    std::vector<double> a(dim, 1.0), invB(dim, 1.0);
    const std::vector<BlockSpan> spans = blockSpans(table);
    for (std::size_t b = 0; b < spans.size(); ++b) {
        if (!spans[b].triangular) continue;  // S, L: identity, no coefficients
        const bool volume = table.blocks[b].invariant == Invariant::Volume;
        for (std::size_t j = 1; j <= spans[b].count; ++j) {
            const double jd = double(j);
            a[spans[b].offset + j - 1] = volume ? 3 * jd * jd - 3 * jd + 1 : 2 * jd - 1;
            invB[spans[b].offset + j - 1] = 1.0 / (volume ? jd * jd * jd : jd * jd);
        }
    }
    const double* ap = a.data();
    const double* ib = invB.data();
    const double* op = o.data();
    const BlockSpan* sp = spans.data();
    const std::size_t numSpans = spans.size();
    return forEachVertex(table, [=](const float* x) {
        double q = 0;
        for (std::size_t b = 0; b < numSpans; ++b) {
            const std::size_t off = sp[b].offset;
            if (sp[b].triangular) {
                double suffix = 0;  // Σ_{k≥j} d_k / b_k
                for (std::size_t j = off + sp[b].count; j-- > off;) {
                    const double d = double(x[j]) - op[j];
                    suffix += d * ib[j];
                    q += d * ap[j] * suffix;
                }
            } else {
                for (std::size_t j = off; j < off + sp[b].count; ++j) {
                    const double d = double(x[j]) - op[j];
                    q += d * d;
                }
            }
        }
        // W is not symmetric, so the header allows q < 0 and keeps its sign (f = −sqrt(−q)) so
        // that f stays ordered. (For the W of Eq. 9/10 the symmetric part is positive
        // definite, smallest eigenvalue about 1.5/n for V and 1/n for P, so q ≥ 0 in practice.)
        return q >= 0 ? std::sqrt(q) : -std::sqrt(-q);
    });
}

/// The reference centred on the flat surface; @throw if it is the flat surface itself.
std::vector<double> centredReference(const FeatureTable& table, const std::vector<double>& o,
                                     const char* metric)
{
    std::vector<double> c = flatReference(table);
    bool zero = true;
    for (std::size_t e = 0; e < c.size(); ++e) {
        c[e] = o[e] - c[e];
        zero = zero && c[e] == 0;
    }
    if (zero)
        throw InvalidInputError(std::string(metric) +
                                " needs a reference other than the flat surface (it is the origin of "
                                "the centred values, so the similarity to it is undefined)");
    return c;
}

/// A similarity of centred values (x̃ = x − flat, õ = o − flat) from x̃·õ, |x̃|² and |õ|²:
/// @p combine(xo, xx, oo) per vertex.
template <class Combine>
std::vector<float> centredSimilarity(const FeatureTable& table, const std::vector<double>& o,
                                     const char* metric, Combine combine)
{
    const std::size_t dim = table.dimension();
    const std::vector<double> flat = flatReference(table);
    const std::vector<double> oc = centredReference(table, o, metric);
    double oo = 0;
    for (double v : oc) oo += v * v;
    const double* fp = flat.data();
    const double* cp = oc.data();
    return forEachVertex(table, [=](const float* x) {
        double xo = 0, xx = 0;
        for (std::size_t e = 0; e < dim; ++e) {
            const double xc = double(x[e]) - fp[e];
            xo += xc * cp[e];
            xx += xc * xc;
        }
        return combine(xo, xx, oo);
    });
}

/// x̃·õ / (|x̃| |õ|); NaN for a flat vertex (x̃ = 0).
std::vector<float> cosine(const FeatureTable& table, const std::vector<double>& o)
{
    return centredSimilarity(table, o, "the cosine similarity", [](double xo, double xx, double oo) {
        return xx > 0 ? xo / (std::sqrt(xx) * std::sqrt(oo)) : kNaN;  // a flat vertex has no direction
    });
}

/// x̃·õ / (|x̃|² + |õ|² − x̃·õ); defined (0) for a flat vertex.
std::vector<float> tanimoto(const FeatureTable& table, const std::vector<double>& o)
{
    return centredSimilarity(table, o, "the Tanimoto similarity", [](double xo, double xx, double oo) {
        // |x̃|² + |õ|² − x̃·õ ≥ (|x̃|² + |õ|²)/2 > 0 since õ ≠ 0.
        const double den = xx + oo - xo;
        return den > 0 ? xo / den : kNaN;
    });
}

/// Pearson correlation of the elements of x and o (the whole concatenated vector); NaN for a
/// vertex whose elements are all equal.
std::vector<float> correlation(const FeatureTable& table, const std::vector<double>& o)
{
    const std::size_t dim = table.dimension();
    // Compared directly: a mean of equal doubles need not equal them exactly.
    if (std::all_of(o.begin(), o.end(), [&](double v) { return v == o.front(); }))
        throw InvalidInputError("the correlation needs a reference whose values are not all equal (all are " +
                                numberText(o.front()) + ", a zero variance)");
    double mo = 0;
    for (double v : o) mo += v;
    mo /= double(dim);
    std::vector<double> oc(dim);
    double oo = 0;
    for (std::size_t e = 0; e < dim; ++e) {
        oc[e] = o[e] - mo;
        oo += oc[e] * oc[e];
    }
    const double* cp = oc.data();
    return forEachVertex(table, [=](const float* x) {
        // Two passes over the row (in L1): the one-pass Σx² − n·x̄² cancels for the small
        // spread of feature values around their flat value.
        double sum = 0;
        bool constant = true;
        for (std::size_t e = 0; e < dim; ++e) {
            sum += x[e];
            constant = constant && x[e] == x[0];
        }
        if (constant) return kNaN;
        const double mx = sum / double(dim);
        double xo = 0, xx = 0;
        for (std::size_t e = 0; e < dim; ++e) {
            const double xc = double(x[e]) - mx;
            xo += xc * cp[e];
            xx += xc * xc;
        }
        return xo / std::sqrt(xx * oo);
    });
}

/// Lag-1 autocorrelation r1 of d = x − o within each block of n ≥ 2 elements, about the
/// block's mean; f is the mean of r1 over those blocks, NaN if one of them has d constant.
std::vector<float> autoCorrelation(const FeatureTable& table, const std::vector<double>& o)
{
    std::vector<BlockSpan> spans;
    for (const BlockSpan& s : blockSpans(table))
        if (s.count >= 2) spans.push_back(s);  // lag 1 needs two elements
    if (spans.empty())
        throw InvalidInputError("the auto-correlation needs a feature block of at least 2 elements (" +
                                layoutText(table) + " given)");
    const double* op = o.data();
    const BlockSpan* sp = spans.data();
    const std::size_t numSpans = spans.size();
    return forEachVertex(table, [=](const float* x) {
        double sumR = 0;
        for (std::size_t b = 0; b < numSpans; ++b) {
            const std::size_t begin = sp[b].offset, end = begin + sp[b].count;
            double sum = 0;
            bool constant = true;
            const double d0 = double(x[begin]) - op[begin];
            for (std::size_t j = begin; j < end; ++j) {
                const double d = double(x[j]) - op[j];
                sum += d;
                constant = constant && d == d0;
            }
            if (constant) return kNaN;  // zero variance: r1 is undefined
            const double mean = sum / double(sp[b].count);
            double prev = double(x[begin]) - op[begin] - mean;
            double num = 0, den = prev * prev;
            for (std::size_t j = begin + 1; j < end; ++j) {
                const double cur = double(x[j]) - op[j] - mean;
                num += prev * cur;
                den += cur * cur;
                prev = cur;
            }
            sumR += num / den;
        }
        return sumR / double(numSpans);
    });
}

/// 1/σ_e² of each element over the vertices without NaN (0 where σ_e = 0: skipped).
/// Chunks of fixed size are reduced in parallel (mean and M2 each, two passes over the
/// chunk while it is in cache) and merged in chunk order (Chan et al.), so the result is
/// the same for every thread count.
std::vector<double> inverseVariances(const FeatureTable& table)
{
    const std::size_t dim = table.dimension();
    const std::size_t n = table.numVertices;
    const std::size_t numChunks = (n + kVarianceChunk - 1) / kVarianceChunk;
    std::vector<std::size_t> counts(numChunks, 0);
    std::vector<double> means(numChunks * dim, 0.0), m2s(numChunks * dim, 0.0);
    const float* values = table.values.data();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, numChunks, 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          std::vector<char> valid(kVarianceChunk);
                          for (std::size_t c = range.begin(); c != range.end(); ++c) {
                              const std::size_t begin = c * kVarianceChunk;
                              const std::size_t end = std::min(n, begin + kVarianceChunk);
                              double* mean = &means[c * dim];
                              double* m2 = &m2s[c * dim];
                              std::size_t count = 0;
                              for (std::size_t i = begin; i < end; ++i) {
                                  const float* x = values + i * dim;
                                  valid[i - begin] = !hasNaN(x, dim);
                                  if (!valid[i - begin]) continue;
                                  ++count;
                                  for (std::size_t e = 0; e < dim; ++e) mean[e] += x[e];
                              }
                              counts[c] = count;
                              if (count == 0) continue;
                              for (std::size_t e = 0; e < dim; ++e) mean[e] /= double(count);
                              for (std::size_t i = begin; i < end; ++i) {
                                  if (!valid[i - begin]) continue;
                                  const float* x = values + i * dim;
                                  for (std::size_t e = 0; e < dim; ++e) {
                                      const double d = double(x[e]) - mean[e];
                                      m2[e] += d * d;
                                  }
                              }
                          }
                      });
    std::vector<double> mean(dim, 0.0), m2(dim, 0.0);
    double total = 0;
    for (std::size_t c = 0; c < numChunks; ++c) {
        if (counts[c] == 0) continue;
        const double nb = double(counts[c]);
        const double sum = total + nb;
        for (std::size_t e = 0; e < dim; ++e) {
            const double delta = means[c * dim + e] - mean[e];
            mean[e] += delta * nb / sum;
            m2[e] += m2s[c * dim + e] + delta * delta * total * nb / sum;
        }
        total = sum;
    }
    std::vector<double> inv(dim, 0.0);
    for (std::size_t e = 0; e < dim; ++e)
        if (total > 0 && m2[e] > 0) inv[e] = total / m2[e];  // 1/σ² with σ² = M2/N (population)
    return inv;
}

/// sqrt(Σ_e (x_e − o_e)² / σ_e²), σ_e² the population variance of element e over the vertices.
std::vector<float> normalizedEuclidean(const FeatureTable& table, const std::vector<double>& o)
{
    const std::size_t dim = table.dimension();
    const std::vector<double> inv = inverseVariances(table);
    const double* ip = inv.data();
    const double* op = o.data();
    return forEachVertex(table, [=](const float* x) {
        double s = 0;
        for (std::size_t e = 0; e < dim; ++e) {
            const double d = double(x[e]) - op[e];
            s += d * d * ip[e];  // ip[e] = 0 skips constant elements
        }
        return std::sqrt(s);
    });
}

} // namespace

std::size_t FeatureTable::dimension() const
{
    std::size_t dim = 0;
    for (const FeatureBlock& b : blocks) dim += std::size_t(std::max(b.count, 0));
    return dim;
}

double flatValue(Invariant invariant)
{
    // V/|B| and S/(4πr²) are halves of the ball and sphere on a plane; P/(πr²) and L/(2πr)
    // are the whole disc and circle.
    return invariant == Invariant::Volume || invariant == Invariant::Sphere ? 0.5 : 1.0;
}

std::vector<double> flatReference(const FeatureTable& table)
{
    validateBlocks(table);
    std::vector<double> ref;
    ref.reserve(table.dimension());
    for (const FeatureBlock& b : table.blocks) ref.insert(ref.end(), std::size_t(b.count), flatValue(b.invariant));
    return ref;
}

std::vector<double> vertexReference(const FeatureTable& table, std::size_t vertex)
{
    validateTable(table);
    if (vertex >= table.numVertices)
        throw InvalidInputError("vertex " + std::to_string(vertex) +
                                " cannot be the reference: the feature table has only " +
                                std::to_string(table.numVertices) + " vertices");
    const std::size_t dim = table.dimension();
    const float* x = table.values.data() + vertex * dim;
    std::vector<double> ref(x, x + dim);
    for (std::size_t e = 0; e < dim; ++e)
        if (std::isnan(ref[e]))
            throw InvalidInputError("vertex " + std::to_string(vertex) + " cannot be the reference: its " +
                                    elementLabel(table, e) + " is NaN (masked near a border)");
    return ref;
}

std::size_t nearestVertex(const TriMesh& mesh, const Vec3& point)
{
    if (mesh.points.empty()) throw InvalidInputError("the mesh has no vertices to find a nearest one in");
    if (!isFinite(point))
        throw InvalidInputError("the point (" + numberText(point.x) + ", " + numberText(point.y) + ", " +
                                numberText(point.z) + ") is not finite");
    // One query per run: a brute-force scan (a few ms for a million vertices) beats building
    // a search structure. Ties go to the lowest index.
    std::size_t best = 0;
    double bestDist = squaredNorm(mesh.points[0] - point);
    for (std::size_t i = 1; i < mesh.points.size(); ++i) {
        const double d = squaredNorm(mesh.points[i] - point);
        if (d < bestDist) {
            bestDist = d;
            best = i;
        }
    }
    return best;
}

std::vector<double> scaleWeights(Invariant invariant, int n)
{
    if (n < 1)
        throw InvalidInputError("scale weights need at least 1 scale, not " + std::to_string(n));
    std::vector<double> w(static_cast<std::size_t>(n));
    const double nd = n;
    for (int j = 1; j <= n; ++j) {
        const double jd = j;
        switch (invariant) {
        case Invariant::Volume:
            // Eq. 4: the shell between r_{j−1} and r_j holds ((j)³ − (j−1)³)/n³ of the ball.
            w[j - 1] = (3 * jd * jd - 3 * jd + 1) / (nd * nd * nd);
            break;
        case Invariant::Patch:
            // Eq. 6: the ring between r_{j−1} and r_j holds (j² − (j−1)²)/n² of the disc.
            w[j - 1] = (2 * jd - 1) / (nd * nd);
            break;
        case Invariant::Sphere:
        case Invariant::Line:
            // Eq. 5: the surfaces/curves at different radii share no area; uniform weights
            // sum to 1 as V's and P's do.
            w[j - 1] = 1.0 / nd;
            break;
        }
    }
    return w;
}

double weightError(const std::vector<double>& weights)
{
    double sum = 0;
    for (double w : weights) sum += w;
    return 1.0 - sum;  // Eq. 7
}

std::vector<double> dependencyMatrix(Invariant invariant, int n)
{
    if (n < 1)
        throw InvalidInputError("a dependency matrix needs at least 1 scale, not " + std::to_string(n));
    const std::size_t size = std::size_t(n);
    std::vector<double> w(size * size, 0.0);
    for (std::size_t j = 0; j < size; ++j) {
        const double jd = double(j + 1);  // 1-based as in the paper
        for (std::size_t k = j; k < size; ++k) {
            const double kd = double(k + 1);
            switch (invariant) {
            case Invariant::Volume:  // Eq. 9: column k holds the weights of Eq. 4 for n = k
                w[j * size + k] = (3 * jd * jd - 3 * jd + 1) / (kd * kd * kd);
                break;
            case Invariant::Patch:  // Eq. 10: column k holds the weights of Eq. 6 for n = k
                w[j * size + k] = (2 * jd - 1) / (kd * kd);
                break;
            case Invariant::Sphere:
            case Invariant::Line:  // no dependency between scales: the identity
                w[j * size + k] = j == k ? 1.0 : 0.0;
                break;
            }
        }
    }
    return w;
}

MetricOptions metricOptionsByName(const std::string& name, double p)
{
    if (!(p > 0)) throw InvalidInputError("the p of a p-norm must be a positive number (or infinity)");
    MetricOptions o;
    std::string base = name;
    if (base.size() > 1 && base[0] == 'l' && base.back() == 'w') o.weighted = true, base.pop_back();
    if (base == "l1") o.p = 1;
    else if (base == "l2") o.p = 2;
    else if (base == "linf") o.p = std::numeric_limits<double>::infinity();
    else if (base == "lp") o.p = p;
    else if (!o.weighted && name == "mahalanobis") o.kind = MetricKind::Mahalanobis;
    else if (!o.weighted && name == "cosine") o.kind = MetricKind::Cosine;
    else if (!o.weighted && name == "correlation") o.kind = MetricKind::Correlation;
    else if (!o.weighted && name == "autocorrelation") o.kind = MetricKind::AutoCorrelation;
    else if (!o.weighted && name == "tanimoto") o.kind = MetricKind::Tanimoto;
    else if (!o.weighted && name == "neuclid") o.kind = MetricKind::NormalizedEuclidean;
    else
        throw InvalidInputError("unknown metric '" + name +
                                "' (use l1, l2, linf, lp, their weighted forms l1w, l2w, linfw, lpw, "
                                "mahalanobis, cosine, correlation, autocorrelation, tanimoto, neuclid)");
    return o;
}

MetricResult computeMetric(const FeatureTable& table, const std::vector<double>& reference,
                           const MetricOptions& options)
{
    validateTable(table);
    if (options.kind == MetricKind::PNorm && !(options.p > 0))
        throw InvalidInputError("the p of the p-norm must be positive (or infinity), not " +
                                numberText(options.p));
    validateReference(table, reference);

    MetricResult result;
    for (const FeatureBlock& b : table.blocks)
        result.weightErrors.push_back(weightError(scaleWeights(b.invariant, b.count)));

    switch (options.kind) {
    case MetricKind::PNorm: result.values = pNorm(table, reference, options); break;
    case MetricKind::Mahalanobis: result.values = mahalanobis(table, reference); break;
    case MetricKind::Cosine: result.values = cosine(table, reference); break;
    case MetricKind::Correlation: result.values = correlation(table, reference); break;
    case MetricKind::AutoCorrelation: result.values = autoCorrelation(table, reference); break;
    case MetricKind::Tanimoto: result.values = tanimoto(table, reference); break;
    case MetricKind::NormalizedEuclidean: result.values = normalizedEuclidean(table, reference); break;
    default: throw InvalidInputError("unknown metric kind " + std::to_string(int(options.kind)));
    }

    // Counted after the parallel pass: no shared counters between threads. signbit also
    // catches a negative form whose root rounds to −0 in float.
    for (float f : result.values) {
        if (std::isnan(f)) ++result.numUndefined;
        else if (options.kind == MetricKind::Mahalanobis && std::signbit(f)) ++result.numNegativeForms;
    }
    return result;
}

} // namespace msii
