#pragma once
/// @file principal_axes.h
/// @brief The surface's area-weighted moments (area, centroid, vector area,
/// covariance) and its principal axes: what a map's best-fit plane and a figure
/// sheet's orientation are chosen from.

#include <msii/mesh/trimesh.h>

#include <array>

namespace msii {

using Matrix3 = std::array<std::array<double, 3>, 3>;

struct SurfaceMoments {
    double area = 0;  ///< 0 for a mesh without area (or with non-finite points)
    Vec3 centroid;  ///< area-weighted
    Vec3 vectorArea;  ///< Σ ½ (b − a) × (c − a): about 0 for a closed surface,
        ///< about its projected area for an open scan
    Matrix3 covariance{};  ///< ∫ (x − centroid)(x − centroid)ᵀ dA / area
};

/// The moments of the surface, exact for its flat triangles: ∫ x xᵀ dA = A/12
/// (Σ vᵢvᵢᵀ + s sᵀ) per triangle (s = Σ vᵢ). Without @p covariance, its area,
/// centroid and vector area alone (the covariance stays zero), in a third of
/// the time.
SurfaceMoments surfaceMoments(const TriMesh& mesh, bool covariance = true);

/// Eigenvalues ascending and their unit eigenvectors (cyclic Jacobi rotations).
struct PrincipalAxes {
    std::array<double, 3> variances{};  ///< ascending
    std::array<Vec3, 3> axes;  ///< axes[k] belongs to variances[k]; signs are arbitrary
};
PrincipalAxes principalAxes(const Matrix3& symmetric);

/// @p a or −a, whichever has its largest component (by magnitude) positive: a
/// deterministic sign for an axis whose sign nothing else decides.
Vec3 canonicalSign(const Vec3& a);

}  // namespace msii
