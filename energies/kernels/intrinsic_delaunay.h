// SPDX-License-Identifier: MIT
#pragma once

#include "framework/types.h"

namespace harap {

/// An intrinsic triangulation of a triangle mesh's vertices: triangles given by their corners and
/// by the intrinsic lengths of their sides (geodesics on the rest surface), not by positions.
struct IntrinsicTriangulation {
  Elements triangles;                                ///< #F×3, the same count as the input's
  Eigen::Matrix<double, Eigen::Dynamic, 3> lengths;  ///< length of the side opposite each corner
  Index flips = 0;                                   ///< edge flips performed
  /// ½·cot of each corner's intrinsic angle: the weight of the side opposite the corner (as
  /// HalfCotangents() for positions), ≥ 0 for every edge (summed over its sides).
  Eigen::Matrix<double, Eigen::Dynamic, 3> half_cot;
  /// Edges that stay non-Delaunay after the flips, whose weights are set to zero: boundary edges
  /// opposite an obtuse angle (one triangle, nothing to flip with), non-manifold edges, edges
  /// between faces of opposite orientation, and edges whose flip would join a vertex to itself
  /// or leave a degenerate triangle. Zero on closed, consistently oriented meshes of
  /// non-degenerate triangles.
  Index zeroed_edges = 0;
  Index degenerate = 0;  ///< triangles without defined angles (zero weights)
};

/// The intrinsic Delaunay triangulation of the surface, by edge flips [Bobenko & Springborn 2007,
/// "A discrete Laplace–Beltrami operator for simplicial surfaces"; Sharp, Soliman & Crane 2019,
/// "Navigating intrinsic triangulations"]. The surface (the rest mesh as a metric space) stays as
/// it is; only its triangulation changes: an edge whose opposite angles α, β have
/// cot α + cot β < 0 is replaced by the other diagonal of the quadrilateral its two triangles
/// form when unfolded into the plane, whose length follows from the four side lengths. Every
/// flip decreases the Dirichlet energy of the piecewise-linear interpolants, so the flips end,
/// with every edge Delaunay (cot α + cot β ≥ 0): the cotangent weights of the result are
/// non-negative, so its Laplacian is an M-matrix.
///
/// `triangles` must index `vertices`. Edges shared by exactly two consistently oriented,
/// non-degenerate triangles are flipped; the others keep their triangles, and a weight that stays
/// negative is set to zero (see `zeroed_edges`), so every weight of the result is ≥ 0.
IntrinsicTriangulation IntrinsicDelaunayTriangulation(const Positions& vertices,
                                                      const Elements& triangles);

/// ½·cot of each corner's angle of triangles given by side lengths (column a: the side opposite
/// corner a), the weight of the side opposite the corner, as HalfCotangents() gives for
/// positions. Triangles with 2·area ≤ kDegenerateTriangleRatio · (longest side)² get zeros and
/// are counted in `num_degenerate` (if given).
Eigen::Matrix<double, Eigen::Dynamic, 3> HalfCotangentsFromLengths(
    const Eigen::Matrix<double, Eigen::Dynamic, 3>& lengths, Index* num_degenerate = nullptr);

}  // namespace harap
