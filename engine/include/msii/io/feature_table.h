#pragma once
/// @file feature_table.h
/// @brief Feature vectors as the metrics read them (metrics/feature_metrics.h), taken from
/// the per-vertex properties of a feature PLY (`V_01 … V_NN` and so on, as msii compute
/// writes them, io/feature_properties.h) or from GigaMesh `.mat` files.

#include <msii/metrics/feature_metrics.h>
#include <msii/mesh/trimesh.h>

#include <string>
#include <vector>

namespace msii {

/// The feature table of @p invariants (in that order) from @p properties: for each, the
/// properties <letter>_01, <letter>_02, … up to the first number missing.
/// @throw InvalidInputError if an invariant has no <letter>_01 (the message lists the
///        features that are there), or a property has the wrong number of values.
FeatureTable featureTableOf(const std::vector<VertexProperty>& properties, std::size_t numVertices,
                            const std::vector<Invariant>& invariants);

/// Reads a GigaMesh `.mat` file (`.volume.mat`: V, `.surface.mat`: P; io/gigamesh_files.h)
/// for a mesh of @p numVertices vertices and returns its values as msii feature properties
/// (V_01 … radius ascending, V as V/|B_r|).
/// @throw InvalidInputError if the file name says neither, or the file does not fit;
///        IOError if it cannot be read.
std::vector<VertexProperty> featurePropertiesFromMat(const std::string& path, std::size_t numVertices);

/// Puts @p add into @p properties, replacing properties of the same name, appending others.
void mergeProperties(std::vector<VertexProperty>& properties, std::vector<VertexProperty> add);

} // namespace msii
