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
    Closest closestOnFace(const Vec3& x, std::uint32_t f) const;

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
    double faceDistance(const Vec3& x, std::uint32_t f, Vec3& closest, int& feature) const;
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
