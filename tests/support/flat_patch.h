#pragma once
// Test support: the generator's irregular flat patch, z = 0 over [0, width] × [0, height],
// triangles facing +z (msii/samples/generators.h, HeightFieldKind::Plane).
#include <msii/samples/generators.h>

#include <cstdint>

namespace msii::test {

inline TriMesh flatPatch(double width, double height, double spacing, std::uint64_t seed = 1)
{
    samples::HeightFieldOptions o;
    o.kind = samples::HeightFieldKind::Plane;
    o.width = width;
    o.height = height;
    o.spacing = spacing;
    o.seed = seed;
    return samples::makeHeightField(o);
}

} // namespace msii::test
