#pragma once
/// @file feature_properties.h
/// @brief The per-vertex features of `msii compute` as named output properties, the same
/// for every writer: V_01 … V_NN, S_01 … S_NN, P_01 … P_NN, L_01 … L_NN (those computed,
/// radius ascending, r_j = j·R/N; NaN marks a masked value), then
/// - `quality`: the first invariant present in the order V, S, P, L (V whenever it was
///   computed) at the largest radius at which the vertex has a value; where it has none, the
///   value of a plane (qualityStandIn: 1/2 for V and S, 1 for P and L). Never NaN: viewers
///   colour by quality without checking (MeshLab 2020.09 aborts on NaN). Near an open border
///   the largest radii are masked first, so the largest valid radius keeps the border's
///   vertices coloured by their own relief, and the plane's value keeps vertices without any
///   value from stretching a colour scale fitted to percentiles;
/// - `valid_radii` (integer): at how many radii that invariant has a value at the vertex,
///   N away from borders, 0 where `quality` is only a stand-in.

#include <msii/core/feature_set.h>
#include <msii/mesh/trimesh.h>

#include <string>
#include <vector>

namespace msii {

/// Copies the features into properties, in the order of the file comment.
std::vector<VertexProperty> featureProperties(const FeatureSet& features);
/// The same, moving the columns out of @p features (a DEM window's are tens of MB each).
std::vector<VertexProperty> featureProperties(FeatureSet&& features);

/// The properties msii compute writes: featureProperties, then `filled_share` (the share of
/// hole fill in the largest ball, PrepareMeshResult::filledShare) if @p filledShare is given.
std::vector<VertexProperty> outputProperties(const FeatureSet& features, std::vector<float> filledShare);
/// The same, moving the columns out of @p features.
std::vector<VertexProperty> outputProperties(FeatureSet&& features, std::vector<float> filledShare);

/// The names of outputProperties for @p invariants at @p scales radii, in its order.
std::vector<std::string> outputPropertyNames(const std::vector<Invariant>& invariants, int scales);

/// Parses a list of feature names as users write them ("quality,V_04 s_16": separated by
/// commas or spaces, any case), each matched to one of @p available and spelled as there.
/// @throw InvalidInputError naming the first that is not available (with those that are),
///        or if the list is empty.
std::vector<std::string> parseFeatureNames(const std::string& text, const std::vector<std::string>& available);

/// The formula of an invariant's normalised value, e.g. "V/|B_r|" or "L/(2 pi r)".
std::string invariantFormula(Invariant invariant);
/// The legend of the features written into outputs: "V_jj = V/|B_r|, S_jj = S/(4 pi r^2)
/// (plane 0.5), P_jj = P/(pi r^2), L_jj = L/(2 pi r) (plane 1), r_j = j*R/N".
std::string featureLegend();
/// One invariant's convention as the JSON record states it, e.g. "P/(pi r^2), flat plane 1".
std::string invariantConvention(Invariant invariant);

/// The name of feature j (0-based) of invariant @p letter: "V_07" (two digits at least).
std::string featureName(char letter, std::size_t j);

/// The value `quality` holds at a vertex where its invariant has no value at any radius:
/// that of a plane through the vertex (V̂ = Ŝ = 1/2, P̂ = L̂ = 1); NaN if nothing was computed.
float qualityStandIn(const FeatureSet& features);

/// Which invariant `quality` comes from, e.g. "V_16" (its largest radius), for the
/// documentation of outputs.
std::string qualitySource(const FeatureSet& features);

} // namespace msii
