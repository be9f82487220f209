#include <msii/mesh/vertex_normals.h>

namespace msii {

std::vector<Vec3> vertexNormals(const TriMesh& mesh, const Vec3& whenNoArea)
{
    std::vector<Vec3> normal(mesh.numVertices());
    for (const Triangle& t : mesh.triangles) {
        const Vec3 area = cross(mesh.points[t[1]] - mesh.points[t[0]], mesh.points[t[2]] - mesh.points[t[0]]);
        for (std::uint32_t v : t) normal[v] += area;
    }
    for (Vec3& n : normal) {
        const double len = norm(n);
        n = len > 0 ? n / len : whenNoArea;
    }
    return normal;
}

} // namespace msii
