// SPDX-License-Identifier: MIT
#pragma once

#include <vector>

#include "framework/optimizer.h"
#include "framework/types.h"

namespace harap {

/// The connected components of a global matrix A's graph (vertices coupled by a non-zero
/// off-diagonal entry) and which rows are non-empty. They depend on A alone, so a level computes
/// them once however often its constraint set changes.
struct SystemComponents {
  explicit SystemComponents(const SparseMatrix& a);
  Index num_vertices() const { return static_cast<Index>(root.size()); }
  std::vector<Index> root;             ///< per vertex: its component's lowest vertex index
  std::vector<unsigned char> coupled;  ///< per vertex: its row of A has a non-zero entry
};

/// The vertices a constraint set fixes: the constrained ones and those pinned so that the free
/// block stays positive definite (see ConstrainedSystem).
struct FixedVertices {
  std::vector<unsigned char> fixed;  ///< per vertex
  std::vector<Index> pinned;         ///< ascending
  ConstraintReport report;
};

/// Validates `constrained` (in range, unique; InternalError otherwise) and pins one vertex of each
/// component without a constrained or anchored vertex (its lowest index) and every isolated
/// vertex. `anchored` vertices stay free but remove their component's null space: those with a
/// soft target, whose data term adds to A's diagonal (data_term.h).
FixedVertices ChooseFixedVertices(const SystemComponents& components,
                                  const std::vector<Index>& constrained,
                                  const std::vector<Index>& anchored = {});

/// The global step A U = B with some vertices' positions prescribed, as the local/global
/// iteration uses it: a matrix to factor (`system_matrix()`, num_unknowns() square) and the maps
/// between positions (#V×3) and the unknowns (num_unknowns()×3). Two implementations: the
/// eliminated system (ConstrainedSystem, one-shot runs) and the masked one (MaskedSystem,
/// interactive sessions, whose sparsity pattern does not depend on the constraint set).
class GlobalStepSystem {
 public:
  virtual ~GlobalStepSystem() = default;

  virtual Index num_vertices() const = 0;
  /// Vertices whose position the global step solves for.
  virtual Index num_free() const = 0;
  /// Rows of system_matrix().
  virtual Index num_unknowns() const = 0;
  /// The symmetric positive definite matrix to factor, full symmetric storage.
  virtual const SparseMatrix& system_matrix() const = 0;
  /// Constrained vertices followed by pinned ones.
  virtual const std::vector<Index>& fixed_vertices() const = 0;
  virtual const std::vector<Index>& free_vertices() const = 0;
  /// Vertices pinned by this class (isolated vertices and one per unconstrained component).
  virtual const std::vector<Index>& pinned_vertices() const = 0;
  virtual const ConstraintReport& report() const = 0;

  /// Takes the fixed vertices' positions from `u` (call when they change).
  virtual void SetFixedPositions(const Positions& u) = 0;
  /// The right-hand side for B (num_unknowns()×3).
  virtual void ReducedRhs(const Positions& b, Eigen::MatrixXd& rhs) const = 0;
  /// The unknowns' values in `u` (num_unknowns()×3), e.g. a warm start.
  virtual void GatherFree(const Positions& u, Eigen::MatrixXd& x) const = 0;
  /// Writes the free vertices' rows of the solution `x` into u; returns max_i ‖Δu_i‖² over them.
  virtual double ScatterFree(const Eigen::MatrixXd& x, Positions& u) const = 0;

 protected:
  GlobalStepSystem() = default;
};

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
/// fixed handles), then per iteration ReducedRhs() → solve → ScatterFree(). The unknowns are the
/// free vertices (num_unknowns() == num_free()).
/// What both implementations keep alike: the split of the vertices into free, fixed and pinned
/// and the report on it, with the accessors over them; each sets them when it is built or its
/// constraint set changes.
class VertexSplitSystem : public GlobalStepSystem {
 public:
  Index num_free() const override { return static_cast<Index>(free_vertices_.size()); }
  const std::vector<Index>& fixed_vertices() const override { return fixed_vertices_; }
  const std::vector<Index>& free_vertices() const override { return free_vertices_; }
  const std::vector<Index>& pinned_vertices() const override { return pinned_vertices_; }
  const ConstraintReport& report() const override { return report_; }

 protected:
  std::vector<Index> free_vertices_;
  std::vector<Index> fixed_vertices_;
  std::vector<Index> pinned_vertices_;
  ConstraintReport report_;
};

class ConstrainedSystem final : public VertexSplitSystem {
 public:
  /// `constrained`: indices of vertices with prescribed positions (unique, any order);
  /// `anchored`: free vertices whose soft targets make their component's block definite
  /// (ChooseFixedVertices).
  ConstrainedSystem(const SparseMatrix& a, const std::vector<Index>& constrained,
                    const std::vector<Index>& anchored = {});

  Index num_vertices() const override { return static_cast<Index>(free_index_.size()); }
  Index num_unknowns() const override { return num_free(); }
  /// A_ff in full symmetric storage.
  const SparseMatrix& reduced_matrix() const { return a_ff_; }
  const SparseMatrix& system_matrix() const override { return a_ff_; }

  /// Caches A_fc · U_c for the fixed vertices' positions in `u` (call when they change).
  void SetFixedPositions(const Positions& u) override;
  /// rhs_f = B_f − A_fc U_c (#free×3).
  void ReducedRhs(const Positions& b, Eigen::MatrixXd& rhs_f) const override;
  /// x_f = U_f (#free×3), e.g. a warm start.
  void GatherFree(const Positions& u, Eigen::MatrixXd& x_f) const override;
  /// Writes x_f into the free rows of u; returns max_i ‖Δu_i‖² over the free vertices.
  double ScatterFree(const Eigen::MatrixXd& x_f, Positions& u) const override;

 private:
  std::vector<Index> free_index_;  ///< vertex → row of A_ff, or kNoVertex if fixed
  SparseMatrix a_ff_;
  SparseMatrix a_fc_;                ///< #free × #fixed
  Eigen::MatrixXd fixed_coupling_;   ///< A_fc U_c
  Eigen::MatrixXd fixed_positions_;  ///< U_c (scratch for SetFixedPositions)
};

/// The global step over all vertices with fixed rows masked: the matrix stays #V×#V with one
/// sparsity pattern (A's, plus the diagonal, explicit zeros kept) whatever the constraint set,
///
///     M = [ A_ff  0 ]      rhs = [ B_f − A_fc U_c ]
///         [ 0     I ]            [ U_c            ],
///
/// (rows and columns of fixed vertices zeroed, 1 on their diagonal), so M's solution is the
/// eliminated system's on the free rows and U_c on the fixed ones. Changing the constraint set
/// changes M only in the rows and columns of the vertices that become fixed or free: a factor
/// of M can be updated there (LinearSolver::Refactor) instead of analysed and factored anew.
/// Which vertices are pinned follows ConstrainedSystem exactly; components are found once.
///
/// Usage per level: construct once from A, SetConstrained() for each constraint set, then as a
/// ConstrainedSystem. The unknowns are all vertices (num_unknowns() == num_vertices()).
class MaskedSystem final : public VertexSplitSystem {
 public:
  /// Nothing is fixed until SetConstrained().
  explicit MaskedSystem(const SparseMatrix& a);

  /// Fixes `constrained` (unique, in range: InternalError otherwise) and the vertices pinned for
  /// it; returns the vertices whose rows and columns of system_matrix() changed (sorted), i.e.
  /// those that went from free to fixed or back.
  std::vector<Index> SetConstrained(const std::vector<Index>& constrained,
                                    const std::vector<Index>& anchored = {});
  /// Replaces A by `a`, whose stored entries must lie on M's pattern and connect the same
  /// vertices (e.g. A + W for other soft weights W: only the diagonal differs); the fixed
  /// vertices stay. Returns false and changes nothing when `a` does not fit; otherwise appends to
  /// `changed` the vertices whose rows and columns of system_matrix() changed, so a factorization
  /// can be refactored on those rows (LinearSolver::Refactor).
  bool SetMatrix(const SparseMatrix& a, std::vector<Index>& changed);

  Index num_vertices() const override { return components_.num_vertices(); }
  Index num_unknowns() const override { return num_vertices(); }
  const SparseMatrix& system_matrix() const override { return masked_; }

  void SetFixedPositions(const Positions& u) override;
  /// rhs (#V×3): B_f − A_fc U_c on free rows, U_c on fixed rows.
  void ReducedRhs(const Positions& b, Eigen::MatrixXd& rhs) const override;
  /// x = u (#V×3).
  void GatherFree(const Positions& u, Eigen::MatrixXd& x) const override;
  /// Writes the free rows of x (#V×3) into u; returns max_i ‖Δu_i‖² over the free vertices.
  double ScatterFree(const Eigen::MatrixXd& x, Positions& u) const override;

 private:
  // Writes column `column` of masked_ from A and fixed_.
  void MaskColumn(Index column);

  SystemComponents components_;
  SparseMatrix unmasked_;             ///< A on M's pattern (A's plus the diagonal)
  SparseMatrix masked_;               ///< M
  std::vector<unsigned char> fixed_;  ///< per vertex
  Positions fixed_coupling_;          ///< A_fc U_c on free rows, U_c on fixed rows (#V×3)
};

}  // namespace harap
