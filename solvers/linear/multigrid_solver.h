// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>
#include <vector>

#include "framework/config.h"
#include "framework/linear_solver.h"
#include "solvers/linear/iterative_kernels.h"

namespace harap {

/// Conjugate gradients preconditioned by one multigrid V-cycle [Trottenberg, Oosterlee &
/// Schüller, Multigrid (2001), Ch. 2; as a CG preconditioner: Tatebe 1993], warm-started from
/// `x` (in a hierarchical run: the up-sampled solution).
///
/// Factorize() builds the levels from the matrix alone (smoothed aggregation, Vaněk, Mandel &
/// Brezina 1996; multigrid_transfer.h): the unknowns are grouped into aggregates along their
/// strong couplings (about a vertex's one-ring on a mesh matrix), the prolongation P maps an
/// aggregate's value to its unknowns (piecewise constant, or smoothed by one damped Jacobi step),
/// and the coarse matrix is the Galerkin product PᵀAP, so each coarse level is the energy of the
/// finer one restricted to the coarse space and stays SPD. Levels are added until at most
/// `coarsest_unknowns` remain (or aggregation stops shrinking the system); the coarsest matrix is
/// factored with CHOLMOD (Eigen's SimplicialLDLT in builds without it). The eliminated system
/// A_ff with its pinned components is what it gets, exactly as the Cholesky solvers do.
///
/// One application of the preconditioner is a V-cycle from zero: pre-smoothing with the
/// `smoother` (the gauss_seidel solver's symmetric sweeps, or the chebyshev solver's
/// polynomial), restriction of the residual (Pᵀ), the V-cycle of the coarser level, the
/// prolongated correction (P) and post-smoothing with the same symmetric smoother. Every step is
/// linear and the cycle is symmetric, so it is a valid CG preconditioner. A column stops once
/// ‖b − A x‖ / ‖b‖ ≤ tolerance; the residual reported is the true one at return.
///
/// Factorize() copies A and builds every level's matrix, transfer operators and smoother; Solve()
/// allocates nothing after its first call with a given column count. Non-positive curvature
/// (pᵀAp ≤ 0, or rᵀM⁻¹r ≤ 0) proves A is not positive definite; the solve then fails saying so.
/// Not thread-safe; kernels run in parallel in the caller's task arena.
class MultigridSolver final : public LinearSolver {
 public:
  static constexpr std::string_view kName = "multigrid";

  enum class Smoother { kGaussSeidel, kChebyshev };
  enum class Prolongation { kConstant, kSmoothed };

  struct Options {
    /// max_iterations: preconditioned CG iterations per solve (a cap when tolerance > 0).
    /// Default: to a relative residual of 1e-8, at most 100 iterations.
    iterative::IterationLimits limits{100, 1e-8};
    Smoother smoother = Smoother::kGaussSeidel;
    /// Symmetric Gauss–Seidel sweeps (or Chebyshev steps) before and after each coarse
    /// correction.
    int smoothing_steps = 1;
    /// Rows per block of the Gauss–Seidel smoother's `blocks` ordering; 1 is its `colored`
    /// ordering, bit for bit (docs/solvers.md, "gauss_seidel").
    Index smoother_block_rows = 512;
    /// Smoothed aggregation by default: piecewise constant prolongation needs a number of
    /// iterations that grows with the mesh (docs/solvers.md, "multigrid").
    Prolongation prolongation = Prolongation::kSmoothed;
    /// θ of the strong couplings |a_ij| ≥ θ √(a_ii a_jj) that aggregates follow.
    double strength_threshold = 0.02;
    /// The coarsest level has at most this many unknowns (then it is factored).
    int coarsest_unknowns = 2000;
    /// Most levels, the finest included.
    int max_levels = 12;

    static Options FromConfig(OptionReader node);
  };

  explicit MultigridSolver(const Options& options);
  ~MultigridSolver() override;

  bool is_direct() const override { return false; }
  const Options& options() const { return options_; }

  /// The unknowns of each level of the last Factorize(), finest first.
  std::vector<Index> level_unknowns() const;
  /// Stored non-zeros of every level's matrix together over those of the finest (the operator
  /// complexity: the cost of a V-cycle's matrix products relative to one product with A).
  double operator_complexity() const;

 private:
  struct Level;
  void FactorizeImpl(const SparseMatrix& a, const Context& context) override;
  SolveSummary SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
                         const Context& context) override;
  /// One column block [first, first + columns) of the solve: preconditioned CG.
  SolveSummary SolveColumns(const Eigen::Ref<const Eigen::MatrixXd>& b,
                            Eigen::Ref<Eigen::MatrixXd> x, Eigen::Index first, int columns,
                            const Context& context);
  /// x = V-cycle(b) from zero on `level` for the first `columns` columns of its work blocks.
  void VCycle(size_t level, int columns, const Context& context);

  Options options_;
  std::vector<std::unique_ptr<Level>> levels_;  ///< finest first; the last is factored
  // The CG blocks of the finest level (n × 3; the first `columns` used).
  Eigen::MatrixXd r_, z_, p_, q_;
};

}  // namespace harap
