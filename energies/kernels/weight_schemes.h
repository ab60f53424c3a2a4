// SPDX-License-Identifier: MIT
#pragma once

#include "framework/config.h"
#include "framework/types.h"

namespace harap {

/// The edge weights of the cotangent ARAP energies (docs/energies.md, "Weight schemes").
enum class WeightScheme {
  kCotangent,          ///< "cotan": ½cot of the mesh's own angles (may be negative)
  kIntrinsicDelaunay,  ///< ½cot of the intrinsic Delaunay triangulation's angles (≥ 0)
  kClamped,            ///< "clamped": every cotangent raised to at least `min_cotangent`
  kUniform,            ///< ½ per face side, so 1 per interior edge
  kAsInputLevel,       ///< coarse levels only: the scheme of the input level
};

inline constexpr EnumNames<WeightScheme, 4> kWeightSchemeNames = {
    {{WeightScheme::kCotangent, "cotan"},
     {WeightScheme::kIntrinsicDelaunay, "intrinsic_delaunay"},
     {WeightScheme::kClamped, "clamped"},
     {WeightScheme::kUniform, "uniform"}}};
inline constexpr EnumNames<WeightScheme, 5> kCoarseWeightSchemeNames = {
    {{WeightScheme::kAsInputLevel, "same"},
     {WeightScheme::kCotangent, "cotan"},
     {WeightScheme::kIntrinsicDelaunay, "intrinsic_delaunay"},
     {WeightScheme::kClamped, "clamped"},
     {WeightScheme::kUniform, "uniform"}}};

/// Weights on a triangulation of a mesh's vertices: the mesh's own triangles, or (intrinsic
/// Delaunay) other triangles of the same vertices. The energies sum over `triangles`, with the
/// rest positions of their corners.
struct TriangleWeights {
  Elements triangles;                                 ///< #F×3
  Eigen::Matrix<double, Eigen::Dynamic, 3> half_cot;  ///< weight of the side opposite each corner
  Index degenerate = 0;    ///< triangles whose weights are zero (no defined angles)
  Index flips = 0;         ///< intrinsic Delaunay: edge flips performed
  Index zeroed_edges = 0;  ///< intrinsic Delaunay: non-Delaunay edges left, weights set to 0
};

/// The weights of `scheme` (not kAsInputLevel) for the triangle mesh (vertices, triangles).
/// `min_cotangent` (kClamped): the lower bound of every corner's cotangent.
TriangleWeights ComputeTriangleWeights(const Positions& vertices, const Elements& triangles,
                                       WeightScheme scheme, double min_cotangent);

}  // namespace harap
