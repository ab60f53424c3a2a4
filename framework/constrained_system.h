// SPDX-License-Identifier: MIT
#pragma once

#include <vector>

#include "framework/optimizer.h"
#include "framework/types.h"

namespace harap {

/// Eliminates fixed vertices from the global step A U = B, so the reduced matrix A_ff (free × free)
/// is symmetric positive definite and can be factored once per constraint set.
///
/// A connected component of A's graph (vertices coupled by a non-zero entry) that holds no
/// constrained vertex makes A_ff singular: ARAP energies are invariant to moving such a piece
/// rigidly. Such components are detected here, before any factorization, and one vertex of each
/// (the lowest index) is pinned at its current position, which removes exactly the translational
/// null space and leaves the energy's minimum unchanged (the piece still rotates and deforms
/// freely through the local step). Vertices with an empty row (used by no element, or only by
/// zero-weight degenerate elements) are pinned where they are. Both are counted in the report.
///
/// Usage per level: construct once, SetFixedPositions() whenever fixed targets move (once for
/// fixed handles), then per iteration ReducedRhs() → solve → ScatterFree().
class ConstrainedSystem {
 public:
  /// `constrained`: indices of vertices with prescribed positions (unique, any order).
  ConstrainedSystem(const SparseMatrix& a, const std::vector<Index>& constrained);

  Index num_vertices() const { return static_cast<Index>(free_index_.size()); }
  Index num_free() const { return static_cast<Index>(free_vertices_.size()); }
  /// A_ff in full symmetric storage.
  const SparseMatrix& reduced_matrix() const { return a_ff_; }
  /// Constrained vertices followed by pinned ones.
  const std::vector<Index>& fixed_vertices() const { return fixed_vertices_; }
  const std::vector<Index>& free_vertices() const { return free_vertices_; }
  /// Vertices pinned by this class (isolated vertices and one per unconstrained component).
  const std::vector<Index>& pinned_vertices() const { return pinned_vertices_; }
  const ConstraintReport& report() const { return report_; }

  /// Caches A_fc · U_c for the fixed vertices' positions in `u` (call when they change).
  void SetFixedPositions(const Positions& u);
  /// rhs_f = B_f − A_fc U_c (#free×3).
  void ReducedRhs(const Positions& b, Eigen::MatrixXd& rhs_f) const;
  /// x_f = U_f (#free×3), e.g. a warm start.
  void GatherFree(const Positions& u, Eigen::MatrixXd& x_f) const;
  /// Writes x_f into the free rows of u; returns max_i ‖Δu_i‖² over the free vertices.
  double ScatterFree(const Eigen::MatrixXd& x_f, Positions& u) const;

 private:
  std::vector<Index> free_index_;  ///< vertex → row of A_ff, or kNoVertex if fixed
  std::vector<Index> free_vertices_;
  std::vector<Index> fixed_vertices_;
  std::vector<Index> pinned_vertices_;
  SparseMatrix a_ff_;
  SparseMatrix a_fc_;               ///< #free × #fixed
  Eigen::MatrixXd fixed_coupling_;  ///< A_fc U_c
  Eigen::MatrixXd fixed_positions_;  ///< U_c (scratch for SetFixedPositions)
  ConstraintReport report_;
};

}  // namespace harap
