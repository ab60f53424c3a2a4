// SPDX-License-Identifier: MIT
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <cstdint>
#include <utility>
#include <vector>

namespace harap {

/// Vertex and element indices (Eigen's sparse matrices use int as well).
using Index = int;

/// Marks "no vertex" in index maps.
inline constexpr Index kNoVertex = -1;

/// #V×3 vertex positions, column-major (one column per coordinate, so a global solve takes all
/// three coordinates as one right-hand side block). Planar meshes keep z = 0.
using Positions = Eigen::Matrix<double, Eigen::Dynamic, 3>;

/// One rotation per rotation site (vertex or element). Planar energies use the upper-left 2×2
/// block and keep the z row/column at identity.
using Rotation = Eigen::Matrix3d;
using Rotations = std::vector<Rotation>;

/// Column-major sparse matrix, full symmetric storage unless stated otherwise.
using SparseMatrix = Eigen::SparseMatrix<double>;

/// The entries of column j of `a` (compressed or not): [begin, end) into its index and value
/// arrays.
inline std::pair<Index, Index> ColumnRange(const SparseMatrix& a, Index j) {
  const Index begin = a.outerIndexPtr()[j];
  const Index end = a.isCompressed() ? a.outerIndexPtr()[j + 1] : begin + a.innerNonZeroPtr()[j];
  return {begin, end};
}

/// #F×3 triangles or #T×4 tetrahedra, row-major so one element is contiguous.
using Elements = Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

}  // namespace harap
