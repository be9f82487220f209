#pragma once
/// @file ring_smoothing.h
/// @brief Fast 1-ring smoothing of a per-vertex function (paper §3.2, Eq. 12–17): mean or
/// area-weighted median over the geodesic disc of radius Δmin around each vertex, applied
/// k times (the paper's examples: 30) to act like a larger filter (docs/method.md, 1-ring
/// smoothing).
///
/// For vertex p0 with value f0 and each incident triangle (p0, p_i, p_{i+1}):
/// - f'_i = f0 + Δ (f_i − f0)/|p_i − p0| (Eq. 13): the value at distance Δ along the edge;
/// - f^t = f0 + f'_i + f'_{i+1} (Eq. 14): three times the small triangle's mean;
/// - a weight per triangle (RingWeights), normalised by their sum A;
/// - mean f̃0 = Σ A'_t f^t / (3A) (Eq. 16), or the weighted median of the f^t/3 (Eq. 17):
///   sorted by f^t, the first k whose cumulative weight reaches 1/2; when it is exactly 1/2
///   (the tie case) the mean of the k-th and (k+1)-th.
/// Δ is the global shortest edge of the mesh (the paper's choice, RingRadius::Global) or
/// each ring's own shortest edge (Eq. 12, RingRadius::Ring), which keeps a few near-zero
/// edges of a scan from freezing the whole mesh (with the global Δ every f'_i ≈ f0 then).
/// The filter is linear for the mean: it is set up once as a sparse matrix.
///
/// Vertices whose value is NaN stay NaN, and triangles with a NaN corner are left out of
/// their neighbours' rings; a vertex with no usable triangle keeps its value. Triangles with
/// a zero-length edge at p0 are left out. Border vertices use the triangles they have (the
/// equations as they are, BorderMode::OpenRing) or keep their value (BorderMode::Keep).

#include <msii/core/run_context.h>
#include <msii/mesh/trimesh.h>

#include <cstddef>
#include <memory>
#include <vector>

namespace msii {

enum class SmoothingFilter { Mean, Median };

enum class RingRadius {
    Global,  ///< Δ = the shortest edge of the whole mesh (paper, note under Eq. 15)
    Ring,    ///< Δ = the shortest edge of each 1-ring (Eq. 12)
};

enum class RingWeights {
    /// tan(α_t/2), α_t the angle at p0: the weights for which the ring's fan of small
    /// triangles has its centroid at p0, so the mean filter keeps linear functions on flat
    /// meshes exactly (irregular rings too); equal angles give equal weights, as Eq. 15 does.
    Balanced,
    /// Eq. 15: the area of the isosceles triangle t'_t with legs Δ, i.e. Δ²·sin(α_t)/2 (its
    /// base taken between the interpolated points p'_i, p'_{i+1}; as printed, Eq. 15 takes
    /// |p_{i+1} − p_i|, which is the base only when both neighbours lie at distance Δ and
    /// has no real root once an edge is longer than 2Δ).
    IsoscelesArea,
};

enum class BorderMode {
    OpenRing,  ///< border vertices are smoothed over the triangles they have
    Keep,      ///< border vertices keep their value
};

struct SmoothingOptions {
    SmoothingFilter filter = SmoothingFilter::Mean;
    int iterations = 30;                        ///< k ≥ 0 passes
    RingRadius radius = RingRadius::Global;
    RingWeights weights = RingWeights::Balanced;
    BorderMode border = BorderMode::OpenRing;
};

/// What the smoother found out about the mesh.
struct SmoothingInfo {
    double globalDelta = 0;      ///< shortest non-zero edge of the mesh
    double medianEdge = 0;       ///< median edge length
    /// The global Δ is below 1/10 of the median edge: with RingRadius::Global the filter
    /// hardly changes anything (each pass moves f by at most about Δ/edge of the differences).
    bool globalDeltaTooSmall = false;
    std::size_t numBorderVertices = 0;
    std::size_t numIsolatedVertices = 0;  ///< vertices in no triangle (kept as they are)
};

/// Precomputes the rings of a mesh once; then smooths any number of fields with them.
class RingSmoother {
public:
    /// @throw InvalidInputError if iterations < 0 or the mesh has no triangles.
    RingSmoother(const TriMesh& mesh, const SmoothingOptions& options = {});
    ~RingSmoother();
    RingSmoother(RingSmoother&&) noexcept;
    RingSmoother& operator=(RingSmoother&&) noexcept;

    const SmoothingInfo& info() const;
    const SmoothingOptions& options() const;

    /// Smooths @p values (one per vertex) in place, options().iterations times.
    /// @throw InvalidInputError if the size is not the vertex count.
    void smooth(std::vector<float>& values, RunContext* context = nullptr) const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

/// One-off convenience: RingSmoother(mesh, options).smooth(values).
SmoothingInfo smoothField(const TriMesh& mesh, std::vector<float>& values,
                          const SmoothingOptions& options = {}, RunContext* context = nullptr);

} // namespace msii
