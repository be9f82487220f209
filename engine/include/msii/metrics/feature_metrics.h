#pragma once
/// @file feature_metrics.h
/// @brief One scalar f(p_i) per vertex from its feature vectors (paper §3.1, Eq. 4–11):
/// distances to a reference vector o (p-norms, weighted or not, the Mahalanobis-inspired
/// form) and similarities (cosine, correlation, auto-correlation, Tanimoto), plus the
/// normalised Euclidean distance (docs/method.md, Feature vectors and metrics).
///
/// Conventions (the values msii compute writes, radius ascending r_j = j·R/n):
/// V/|B|, S/(4πr²): flat surface 0.5;  P/(πr²), L/(2πr): flat surface 1.
/// - Scale weights (Eq. 4–6) per block of n elements: V (3j² − 3j + 1)/n³ (cubic),
///   P (2j − 1)/n² (quadratic), S and L 1/n (no dependency between scales, uniform so that
///   every block's weights sum to 1 as V's and P's do).
/// - Similarities (cosine, Tanimoto) work on centred values x̃ = x − flat, so that the flat
///   surface is the origin (as in GigaMesh, whose V is stored as 2V/|B| − 1); they need a
///   reference other than the flat surface.
/// - Any NaN element (masked near a border) makes f NaN for that vertex.

#include <msii/core/feature_set.h>
#include <msii/mesh/trimesh.h>

#include <cstddef>
#include <string>
#include <vector>

namespace msii {

/// n consecutive feature elements of one invariant, radius ascending.
struct FeatureBlock {
    Invariant invariant = Invariant::Volume;
    int count = 0;
};

/// Feature vectors of all vertices, row-major: values[i · dimension() + e]; the blocks are
/// concatenated in their order (e.g. V_01…V_16 then P_01…P_16).
struct FeatureTable {
    std::vector<FeatureBlock> blocks;
    std::size_t numVertices = 0;
    std::vector<float> values;
    std::size_t dimension() const;
};

/// The value of the ideal flat surface: 0.5 for V and S, 1 for P and L.
double flatValue(Invariant invariant);

/// The flat-surface reference vector of @p table (paper: "the origin").
std::vector<double> flatReference(const FeatureTable& table);

/// The feature vector of vertex @p vertex. @throw InvalidInputError if out of range or if
/// it holds a NaN (a masked vertex cannot be a reference).
std::vector<double> vertexReference(const FeatureTable& table, std::size_t vertex);

/// The vertex nearest to @p point (Euclidean). @throw InvalidInputError for an empty mesh.
std::size_t nearestVertex(const TriMesh& mesh, const Vec3& point);

/// Scale-dependency weights of Eq. 4–6 for n elements of @p invariant (see file comment).
/// @throw InvalidInputError if n < 1.
std::vector<double> scaleWeights(Invariant invariant, int n);

/// ε = 1 − Σ w_j (Eq. 7): the numeric error of the weights.
double weightError(const std::vector<double>& weights);

/// The dependency matrix W of Eq. 9 (V) or W^P of Eq. 10 (P), identity for S and L:
/// n·n row-major, w[j·n + k] for 0-based j ≤ k, zero below the diagonal.
std::vector<double> dependencyMatrix(Invariant invariant, int n);

enum class MetricKind {
    PNorm,                ///< (Σ w_e |x_e − o_e|^p)^(1/p); p = ∞: max_e w_e |x_e − o_e|
    Mahalanobis,          ///< Eq. 11: sqrt((x − o) W (x − o)ᵀ), W block-diagonal of Eq. 9/10
    Cosine,               ///< x̃·õ / (|x̃| |õ|), centred values
    Correlation,          ///< Pearson correlation of the elements of x and o
    AutoCorrelation,      ///< lag-1 autocorrelation of x − o within each block, mean over blocks
    Tanimoto,             ///< x̃·õ / (|x̃|² + |õ|² − x̃·õ), centred values
    NormalizedEuclidean,  ///< sqrt(Σ_e (x_e − o_e)² / σ_e²), σ_e² the variance of element e over the vertices
};

struct MetricOptions {
    MetricKind kind = MetricKind::PNorm;
    double p = 2.0;         ///< PNorm only: p > 0; std::numeric_limits<double>::infinity() for the maximum norm
    bool weighted = false;  ///< PNorm only: multiply each |x_e − o_e|^p (or, for p = ∞, |x_e − o_e|) by the scale weight w_e
};

struct MetricResult {
    std::vector<float> values;          ///< f per vertex (NaN where undefined, see countUndefined)
    std::vector<double> weightErrors;   ///< ε of Eq. 7 of each block's scaleWeights(), one per block (always filled)
    std::size_t numNegativeForms = 0;   ///< Mahalanobis: vertices whose quadratic form was negative (f = −sqrt(−q) there)
    std::size_t numUndefined = 0;       ///< vertices with f = NaN (NaN elements, zero-variance vectors for Correlation/Cosine/Tanimoto/AutoCorrelation)
};

/// The metric of a name as the documentation gives them: l1, l2, linf, lp (p-norm with
/// @p p), their weighted forms l1w, l2w, linfw, lpw, mahalanobis, cosine, correlation,
/// autocorrelation, tanimoto, neuclid. @throw InvalidInputError for another name or p <= 0.
MetricOptions metricOptionsByName(const std::string& name, double p = 2.0);

/// f(p_i) for every vertex of @p table against the reference @p reference (dimension()
/// values, e.g. flatReference(), vertexReference() or the user's vector).
/// The Mahalanobis-inspired form (Eq. 11): W is not symmetric, but its symmetric part is
/// positive definite for Eq. 9/10 (tested), so q ≥ 0 for every real difference; should
/// rounding give q < 0, f is −sqrt(−q) (signed: ordering and continuity kept) and counted.
/// @throw InvalidInputError if the reference has the wrong length or a NaN, p ≤ 0 or NaN,
///        or a similarity is asked against a reference it cannot use (Cosine and Tanimoto:
///        the flat reference; Correlation: a reference whose elements are all equal).
MetricResult computeMetric(const FeatureTable& table, const std::vector<double>& reference,
                           const MetricOptions& options);

} // namespace msii
