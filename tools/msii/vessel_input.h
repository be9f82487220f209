#pragma once
// What `msii axis`, `msii profile` and `msii unroll` share: the axis as the options give it
// (fitted, given as a line, or read from an axis record) and the axis record itself.
#include <msii/mesh/trimesh.h>
#include <msii/vessels/axis_of_rotation.h>

#include <nlohmann/json.hpp>

#include <string>

namespace msii::tools {

/// The axis --axis names: "auto" (or empty) fits it (fitAxisOfRotation); "PX,PY,PZ:DX,DY,DZ"
/// is a point and a direction; a file name is an axis record of `msii axis`. @p said tells
/// how it was found, for the summary line.
/// @throw InvalidInputError naming --axis for text that is none of these, or the fit's refusal.
AxisOfRotation axisFromOption(const TriMesh& mesh, const std::string& option, std::string& said);

/// The record `msii axis` writes: point, direction, shape, residual, rim_diameter (null when
/// there is none), and what else the fit found.
nlohmann::json axisRecord(const AxisOfRotation& axis, const std::string& units);

}  // namespace msii::tools
