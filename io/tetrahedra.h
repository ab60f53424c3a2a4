// SPDX-License-Identifier: MIT
// Tetrahedron geometry the readers and writers share: signed volume, the orientation convention
// (and the fix for files written with the other one), boundary triangles.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "framework/mesh.h"
#include "framework/mesh_topology.h"  // BoundaryTriangles

namespace harap {

/// 6 × the signed volume of the tetrahedron (a, b, c, d): det([b − a, c − a, d − a]). Positive is
/// harap's orientation (TetGen's and WRAPD's too): d lies on the side of triangle (a, b, c) that
/// its counter-clockwise normal points to.
double TetrahedronDeterminant(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c, const Eigen::Vector3d& d);

/// What OrientTetrahedra found.
struct TetrahedronOrientation {
  Index reoriented = 0;           ///< Tetrahedra with negative volume, now swapped.
  std::vector<Index> degenerate;  ///< Flat tetrahedra (see OrientTetrahedra), ascending.
};

/// Makes every tetrahedron of `mesh` positively oriented by swapping its last two corners where
/// the signed volume is negative. The vertex order of a rest tetrahedron carries no meaning (the
/// per-tetrahedron energies are invariant under permuting its corners), so this only fixes the
/// convention later code relies on (inversion = negative volume relative to the rest state).
/// Tetrahedra that are flat to rounding precision, |det| ≤ 1e-12 · |b − a| |c − a| |d − a| (for
/// a regular tetrahedron the ratio is 0.71), have no orientation and no finite cotangent
/// weights; they are listed in `degenerate` and left unchanged. Triangle meshes: no-op.
TetrahedronOrientation OrientTetrahedra(Mesh& mesh);

}  // namespace harap
