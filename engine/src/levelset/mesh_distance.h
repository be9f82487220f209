#pragma once
// Private to the engine: exact signed distance from a point to a consistently oriented
// triangle mesh, found by descending over the mesh from a nearby start triangle.
#include <msii/mesh/trimesh.h>

#include <array>
#include <cstdint>
#include <mutex>
#include <vector>

namespace msii::detail {

class MeshDistance {
public:
    /// Keeps a reference: @p mesh must outlive this object.
    explicit MeshDistance(const TriMesh& mesh);

    /// Signed distance (negative inside the solid) from @p x to the mesh, exact whatever
    /// the shape. A descent from the triangles of vertex @p startVertex (moving to
    /// neighbouring triangles while they are closer) gives a bound; sharp edges and corners
    /// give the descent local minima, so every triangle within that bound is then checked,
    /// through a uniform grid of triangles built on the first call with that call's
    /// @p cellSize (enlarged if the grid would have more than 2^25 cells).
    double exactSignedDistance(const Vec3& x, std::uint32_t startVertex, double cellSize) const;

    /// The closest point of one triangle to a point, and the feature (face, edge or vertex)
    /// it lies on.
    struct Closest {
        double squaredDistance = 0;
        Vec3 point;
        std::uint32_t face = 0;
        int feature = 0;
    };
    /// Inline, as closestPointOnTriangle: the band's rasterization asks for it at every voxel
    /// near a triangle, where a call cost about as much as the work.
    Closest closestOnFace(const Vec3& x, std::uint32_t f) const
    {
        Closest c;
        c.face = f;
        c.squaredDistance = faceDistance(x, f, c.point, c.feature);
        return c;
    }

    /// Signed distance from @p x given its closest point on the whole mesh @p c: the sign
    /// is that of the pseudo-normal of c's feature (Baerentzen & Aanaes), exact for a
    /// consistently oriented mesh.
    /// @param onBorder  if given, set when the closest feature is a vertex or edge of the
    ///                  mesh's border and x lies off to its side (beyond the border, where
    ///                  the side is a guess).
    double signedFromClosest(const Vec3& x, const Closest& c, bool* onBorder = nullptr) const;

    /// A sphere around triangle @p f: centred at its centroid, through its farthest vertex
    /// (for quick rejections: no point of the triangle is closer than |x − centre| − radius).
    struct BoundingSphere {
        Vec3 centre;
        double radius = 0;
    };
    const BoundingSphere& boundingSphere(std::size_t f) const { return mBoundingSphere[f]; }

    /// Unit normal of triangle @p f, pointing out of the solid.
    const Vec3& faceNormal(std::size_t f) const { return mFaceNormal[f]; }

    /// Angle-weighted (pseudo-)normal of vertex @p v, unit length, pointing out of the solid.
    const Vec3& vertexNormal(std::size_t v) const { return mVertexNormal[v]; }

private:
    /// Features of a triangle (a, b, c) that can hold the closest point.
    enum Feature { kFace, kVertexA, kVertexB, kVertexC, kEdgeAB, kEdgeBC, kEdgeCA };

    /// Closest point on triangle (a, b, c) to p and the feature it lies on (Voronoi regions,
    /// as in Ericson, Real-Time Collision Detection, 5.1.5).
    static Vec3 closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, int& feature)
    {
        const Vec3 ab = b - a, ac = c - a, ap = p - a;
        const double d1 = dot(ab, ap), d2 = dot(ac, ap);
        if (d1 <= 0 && d2 <= 0) { feature = kVertexA; return a; }
        const Vec3 bp = p - b;
        const double d3 = dot(ab, bp), d4 = dot(ac, bp);
        if (d3 >= 0 && d4 <= d3) { feature = kVertexB; return b; }
        const double vc = d1 * d4 - d3 * d2;
        if (vc <= 0 && d1 >= 0 && d3 <= 0) { feature = kEdgeAB; return a + ab * (d1 / (d1 - d3)); }
        const Vec3 cp = p - c;
        const double d5 = dot(ab, cp), d6 = dot(ac, cp);
        if (d6 >= 0 && d5 <= d6) { feature = kVertexC; return c; }
        const double vb = d5 * d2 - d1 * d6;
        if (vb <= 0 && d2 >= 0 && d6 <= 0) { feature = kEdgeCA; return a + ac * (d2 / (d2 - d6)); }
        const double va = d3 * d6 - d5 * d4;
        if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
            feature = kEdgeBC;
            return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
        }
        feature = kFace;
        const double denom = 1.0 / (va + vb + vc);
        return a + ab * (vb * denom) + ac * (vc * denom);
    }

    double faceDistance(const Vec3& x, std::uint32_t f, Vec3& closest, int& feature) const
    {
        const auto& t = mMesh.triangles[f];
        closest = closestPointOnTriangle(x, mMesh.points[t[0]], mMesh.points[t[1]], mMesh.points[t[2]], feature);
        return squaredNorm(x - closest);
    }
    /// The descent of exactSignedDistance(): a local minimum of the distance over triangles.
    Closest descend(const Vec3& x, std::uint32_t startVertex) const;
    Vec3 pseudoNormal(std::uint32_t f, int feature) const;

    void buildGrid(double cellSize) const;
    std::size_t cellIndex(std::int64_t x, std::int64_t y, std::int64_t z) const
    {
        return std::size_t((x * mGridDims[1] + y) * mGridDims[2] + z);
    }

    const TriMesh& mMesh;
    // Uniform grid of triangles over the mesh's bounding box, built on first use: cell c
    // holds mCellTris[mCellFirst[c] .. mCellFirst[c + 1]).
    mutable std::once_flag mGridOnce;
    mutable double mCell = 0;
    mutable Vec3 mGridOrigin;
    mutable std::array<std::int64_t, 3> mGridDims{};
    mutable std::vector<std::uint32_t> mCellFirst, mCellTris;
    std::vector<Vec3> mFaceNormal, mVertexNormal;
    std::vector<BoundingSphere> mBoundingSphere;
    std::vector<std::uint32_t> mFirst, mFaces;  // vertex -> incident faces (CSR)
    std::vector<std::uint8_t> mBorderVertex;    // 1 for vertices on a border edge
};

} // namespace msii::detail
