#pragma once
/// @file components.h
/// @brief Thresholding a per-vertex function f into connected components on the mesh (the
/// marked regions an epigrapher wants as separate signs), with area, size and centroid.

#include <msii/mesh/trimesh.h>

#include <cstdint>
#include <vector>

namespace msii {

struct ComponentOptions {
    double threshold = 0;     ///< a vertex is selected when f >= threshold (or <= with below)
    bool below = false;       ///< select f <= threshold instead
    /// Components with fewer vertices than this are dropped (their vertices get label 0).
    std::size_t minVertices = 1;
    double minArea = 0;       ///< components with less area than this (mesh units²) are dropped too
};

struct Component {
    std::uint32_t label = 0;     ///< 1, 2, ... in order of decreasing area
    std::size_t vertices = 0;    ///< selected vertices in the component
    double area = 0;             ///< mesh units²: Σ over its vertices of a third of each incident triangle's area (barycentric cells)
    Vec3 centroid;               ///< area-weighted mean of its vertices (by the same cells)
    Vec3 boxMin, boxMax;         ///< bounding box of its vertices
};

struct ComponentResult {
    std::vector<std::uint32_t> label;  ///< per vertex: 0 = not selected or dropped, else the component
    std::vector<Component> components; ///< kept components, label k at index k − 1
    std::size_t droppedComponents = 0; ///< components removed by the size filters
};

/// Connected components (through mesh edges) of the vertices whose f passes the threshold.
/// NaN values are never selected. Deterministic and independent of the thread count.
/// @throw InvalidInputError if f does not have one value per vertex or the threshold is NaN.
ComponentResult findComponents(const TriMesh& mesh, const std::vector<float>& f,
                               const ComponentOptions& options = {});

} // namespace msii
