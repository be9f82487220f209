#pragma once
/// @file patch_line_fit.h
/// @brief Step 6 of P and L (msii/invariants/patch_line.h): the fit. Coarse levels, with fewer
/// samples than vertices, evaluate at the samples and fit a plane to each vertex from the
/// samples on its side of the surface; vertices where that fails (creases, corners) are left
/// to be evaluated where they are.
/// Private to the engine (patch_line.cpp and its parts).

#include "patch_line_samples.h"

#include <msii/core/vec3.h>

#include <vector>

namespace msii::detail {

/// Levels whose cells are at most this many vertex spacings are evaluated at the vertices,
/// coarser ones at the samples. On an evenly triangulated surface the samples outnumber the
/// vertices up to cells of about 1.0-1.1 median edges. Not exactly 1: the automatic voxel
/// is often half a median edge, which puts the second level's cells at exactly one, where
/// the smallest change of the mesh would flip the route.
constexpr double kDirectCellsPerSpacing = 1.2;

/// Per sample of @p level, 1 where no point of @p p without @p skip lies within the fit's
/// window (2h) of it, so that interpolateFromSamples reads no value of it, else 0 (a few more
/// are kept: those within 2h of a group of points' box). On a mesh continued past its
/// borders, the continuation's samples beyond the surface's vertices need no evaluation.
std::vector<char> samplesBeyondFit(const Level& level, double h0, const std::vector<Vec3>& p,
                                   const std::vector<char>& skip);

/// Interpolates fields given at the samples of @p level (values[k·numSamples + s], k <
/// numFields) to the points @p p with normals @p n (out[k·n + i]; points with @p skip set
/// are left alone): a linear fit in the tangent plane (value and two slopes) over the
/// samples within 2h on the point's side of the surface (kSameSide), weighted (1 −
/// (d/2h)²)⁸, so linear fields are reproduced. Where such samples do not span the plane
/// (creases, corners), @p unresolved is set instead: those points are evaluated directly.
/// For the first @p residuals[k] != nullptr fields it also gives the fit's weighted RMS
/// residual, residuals[k][i]: how far the field bends within the fit's window (a crease
/// or the onset of a new sheet nearby), which the fit blurs.
void interpolateFromSamples(const Level& level, double h0, const std::vector<Vec3>& p,
                            const std::vector<Vec3>& n, const std::vector<char>& skip,
                            int numFields, const std::vector<const float*>& values,
                            const std::vector<float*>& out, std::vector<char>& unresolved,
                            const std::vector<float*>& residuals = {});

} // namespace msii::detail
