// SPDX-License-Identifier: MIT
#pragma once

#include <array>
#include <utility>

#include "framework/mesh.h"
#include "framework/types.h"

namespace harap {

// kDegenerateTriangleRatio (framework/mesh.h): triangles below it get zero weights.

/// ½·cot of the interior angle at each corner of each triangle (#F×3): column a belongs to the
/// edge opposite corner a (the Pinkall–Polthier / Chao et al. weight w_{f,jk}). Degenerate
/// triangles get zeros and are counted in `num_degenerate` (if given).
Eigen::Matrix<double, Eigen::Dynamic, 3> HalfCotangents(const Positions& vertices,
                                                        const Elements& triangles,
                                                        Index* num_degenerate = nullptr);

/// A tetrahedron with |6·volume| below this fraction of its longest edge cubed has no
/// well-defined dihedral angles; its weights are set to zero (docs/energies.md).
inline constexpr double kDegenerateTetrahedronRatio = 1e-12;

/// The six edges (a, b) of a tetrahedron's corners, in the column order of
/// TetrahedronCotangentWeights. Edge e and edge 5 − e are opposite each other.
inline constexpr std::array<std::pair<int, int>, 6> kTetrahedronEdges = {
    {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};

/// The volumetric cotangent weight of each edge of each tetrahedron (#T×6, columns in the order
/// of kTetrahedronEdges): w_ab = ℓ_cd · cot θ_cd / 6, with cd the opposite edge, ℓ_cd its length
/// and θ_cd the dihedral angle at it (the weight of the paper's Eq. 9 with its ⅙). Computed as
/// w_ab = −vol·∇φ_a·∇φ_b from the gradients of the barycentric coordinates, which is the same
/// number without trigonometry, and independent of the orientation of the tetrahedron.
/// Negative for obtuse dihedral angles. Degenerate tetrahedra get zeros and are counted in
/// `num_degenerate` (if given).
Eigen::Matrix<double, Eigen::Dynamic, 6> TetrahedronCotangentWeights(
    const Positions& vertices, const Elements& tetrahedra, Index* num_degenerate = nullptr);

/// Mixed Voronoi area of each vertex [Meyer, Desbrun, Schröder, Barr 2003], the lumped mass
/// matrix of libigl's MASSMATRIX_TYPE_VORONOI: in a non-obtuse triangle each corner gets its
/// Voronoi region, ⅛ Σ over its two edges of |e|²·cot(angle opposite e); in an obtuse triangle
/// the obtuse corner gets half the triangle's area and the other two a quarter each. The areas
/// add up to the mesh area. Degenerate triangles (same test as HalfCotangents) contribute nothing,
/// so a vertex used only by degenerate triangles (or by none) has area 0.
Eigen::VectorXd MixedVoronoiAreas(const Positions& vertices, const Elements& triangles);

}  // namespace harap
