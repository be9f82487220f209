#pragma once
// Test support: a rotation about a unit axis (Rodrigues' formula), for moving meshes and
// points rigidly. cos and sin are computed once; every call evaluates the same expression in
// the same order, so a rotated point is bit-for-bit the same wherever it is computed.
#include <msii/core/vec3.h>

#include <cmath>

namespace msii::test {

struct Rotation {
    /// Rotation by @p angle (radians) about @p unitAxis, which must already be normalised.
    Rotation(const Vec3& unitAxis, double angle)
        : axis(unitAxis), c(std::cos(angle)), s(std::sin(angle))
    {
    }

    Vec3 operator()(const Vec3& p) const
    {
        return p * c + cross(axis, p) * s + axis * (dot(axis, p) * (1 - c));
    }

    /// The opposite rotation: same axis, sine negated.
    Rotation inverse() const
    {
        Rotation r = *this;
        r.s = -s;
        return r;
    }

    Vec3 axis;
    double c, s;
};

} // namespace msii::test
