#pragma once
/// @file exact.h
/// @brief The exact reference mode: V, S, P and L (paper Eq. 1–2; docs/method.md, Exact mode)
/// of a triangle mesh, computed in closed form from the triangles, with no grid or sampling.
/// Slow compared with the grid-based engine (invariants/volume_sphere.h, patch_line.h), but
/// exact up to rounding for the mesh as given: the oracle the fast paths are measured
/// against.
///
/// How (details in exact.cpp). For a vertex p and a ball B_r(p), each triangle t (unit
/// outward normal n_t) lies in a plane at signed distance d_t = (a − p)·n_t from p (a any
/// corner), and t ∩ B_r is t ∩ the disc of radius ρ_t = sqrt(r² − d_t²) about the foot point
/// c_t = p + d_t n_t. Then
/// - P = Σ_t area(t ∩ disc);
/// - L = Σ_t length of the disc's circle inside t (= d area / d ρ_t);
/// - S: the field (x − p)/|x − p|³ is divergence-free, and its flux out of
///   solid ∩ (B_r \ B_ε) gives S/r² = Ω_p − Σ_t Ω_t with Ω_t = ∫_{t ∩ B_r} d_t/|x − p|³ dA
///   (the signed solid angle of t ∩ B_r seen from p) and Ω_p the solid angle of the solid's
///   cone at p, by Girard's theorem Σ_e δ_e − (k − 2)π over the k edges at p (δ_e the
///   solid's interior dihedral angle at e); triangles through p have d_t = 0 and add nothing;
/// - V: the divergence theorem with (x − p)/3 on solid ∩ B_r: 3V = Σ_t d_t area(t ∩ B_r) + r S.
/// The per-triangle integrals are closed forms over the signed sectors (c_t, A, B) of the
/// three edges (triangleBallMeasures()). Triangles are found through a uniform grid. Per
/// vertex, a triangle inside a ball is added once, at the first radius whose ball holds it,
/// and only the triangles that a sphere cuts are evaluated piece by piece, with sums of
/// angles kept as arguments of complex products (exact.cpp); the results agree with the
/// plain per-triangle sums to rounding (~1e-14). Each vertex is evaluated by one thread,
/// so results do not depend on the thread count.

#include <msii/core/run_context.h>
#include <msii/core/vec3.h>
#include <msii/mesh/trimesh.h>

#include <cstdint>
#include <vector>

namespace msii {

struct ExactOptions {
    /// Radii (mesh units): ascending, positive and finite, e.g. equidistantRadii() of
    /// invariants/scales.h.
    std::vector<double> radii;
    /// Indices of the vertices to evaluate; empty = all vertices, in index order.
    std::vector<std::uint32_t> vertices;
    /// Per mesh vertex: distance to the nearest border (mesh/border_distance.h); empty for
    /// closed meshes. A value whose ball reaches a border (r >= borderDistance) is NaN.
    std::vector<double> borderDistance;
    bool computeVolumeSphere = true;  ///< V and S (need the cone angle at the vertex)
    bool computePatchLine = true;     ///< P and L
};

struct ExactResult {
    std::vector<double> radii;            ///< as given
    std::vector<std::uint32_t> vertices;  ///< the vertices evaluated (all if none were given)
    /// [radius j][k] for vertex vertices[k], normalised: V/(4/3 π r³), S/(4π r²) (plane 0.5),
    /// P/(π r²), L/(2π r) (plane 1). NaN where masked (the ball reaches a border) and for
    /// V and S at a vertex whose cone is undefined: on a border when no borderDistance is
    /// given, in no triangle, or where its triangles fold over one another (the cone's
    /// solid angle by Girard's theorem falls outside (0, 4π): a crumpled patch of a scan,
    /// where the solid is not defined). Empty if not asked for.
    std::vector<std::vector<double>> volume, sphere, patch, line;
};

/// Computes V̂, Ŝ, P̂ and L̂ exactly (up to rounding) at each radius for the chosen vertices.
/// @pre @p mesh passed checkMesh (mesh/mesh_check.h): finite, no degenerate faces, manifold
///      and consistently oriented (counter-clockwise seen from outside the solid).
/// @throw InvalidInputError if the radii are empty, not positive and finite or not strictly
///        ascending, a vertex index is out of range, or borderDistance is neither empty nor
///        one value per vertex.
ExactResult computeExact(const TriMesh& mesh, const ExactOptions& options,
                         RunContext* context = nullptr);

/// The three integrals of one triangle over the ball B_r(p), the building block of
/// computeExact().
struct TriangleBallMeasures {
    double area = 0;        ///< area(t ∩ B_r)
    double arcLength = 0;   ///< length of the curve t ∩ ∂B_r
    double solidAngle = 0;  ///< Ω_t = ∫_{t ∩ B_r} d/|x − p|³ dA (sign of d; 0 if d = 0)
    double distance = 0;    ///< d = (a − p)·n, the signed distance of the triangle's plane
};

/// Integrals of triangle (a, b, c) (counter-clockwise about its normal) over B_r(p), in
/// closed form. d is taken from the corner nearest to p, so it is exactly 0 when p is a
/// corner.
/// @pre the triangle is not degenerate; r > 0.
TriangleBallMeasures triangleBallMeasures(const Vec3& p, const Vec3& a, const Vec3& b,
                                          const Vec3& c, double r);

} // namespace msii
