// SPDX-License-Identifier: MIT
#pragma once

#include <Eigen/IterativeLinearSolvers>
#include <array>
#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/linear_solver.h"
#include "solvers/linear/iterative_kernels.h"

namespace harap {

/// Preconditioned conjugate gradients [Hestenes & Stiefel 1952; Saad, Iterative Methods for
/// Sparse Linear Systems, Alg. 9.1], warm-started from `x`.
///
/// The columns of B are solved together in blocks of three: each column has its own CG scalars
/// (α, β), but one pass over A computes A·p for all of them, so the global step's three
/// coordinates stream the matrix once per iteration. A column stops when its recurrence residual
/// r_k reaches `tolerance`; others go on. The residual reported is the true ‖b − A x‖ / ‖b‖ at
/// return (one more pass over A per solve): r_k drifts from it, slightly in general and by
/// orders of magnitude on singular systems.
///
/// Preconditioners: Jacobi (M = diag A; fused into the vector updates, so an iteration is two
/// parallel passes) or incomplete Cholesky (Eigen's IncompleteCholesky, a threshold IC with
/// diagonal shifting [Lin & Moré 1999]; its two triangular solves per iteration are sequential).
///
/// Factorize() copies A and builds the preconditioner; Solve() allocates nothing after its first
/// call with a given column count. A non-positive curvature pᵀAp ≤ 0 proves A is not positive
/// definite: the solve then fails with that message. Not thread-safe; kernels run in parallel in
/// the caller's task arena.
class ConjugateGradientSolver final
    : public iterative::MatrixIterativeSolver<ConjugateGradientSolver> {
 public:
  static constexpr std::string_view kName = "cg";

  enum class Preconditioner { kJacobi, kIncompleteCholesky };

  struct Options {
    /// max_iterations: CG iterations per solve (per global step; a cap when tolerance > 0).
    /// Default 20 iterations, no tolerance: a fixed cost per global step, like the paper's
    /// "few iterations of an iterative solver per global solve" (Section 5.2).
    iterative::IterationLimits limits{20, 0.0};
    /// Jacobi by default: see docs/solvers.md for the measured comparison.
    Preconditioner preconditioner = Preconditioner::kJacobi;

    static Options FromConfig(OptionReader node);
  };

  explicit ConjugateGradientSolver(const Options& options)
      : MatrixIterativeSolver(kName), options_(options) {}

  const Options& options() const { return options_; }

  /// The estimated share of the last Solve()'s correction x* − x₀ that its iterations left
  /// undone, in the A-norm squared, max over columns (0 for columns the tolerance stopped, and
  /// when too few iterations ran to tell). CG's terms α_j r_jᵀz_j sum to ‖x_k − x₀‖²_A (the
  /// search directions are A-conjugate) and, continued to convergence, to ‖x* − x₀‖²_A; the
  /// terms not computed are extrapolated as a geometric series from the ratio of the sums of
  /// the last two blocks of kUnresolvedWindow terms (1 if they do not decay; 0 with fewer than
  /// two blocks of iterations). Strakoš & Tichý, "On error estimation in
  /// the conjugate gradient method and why it works in finite precision computations" (2002),
  /// estimate the error the same way from terms computed d iterations ahead.
  double unresolved_fraction() const { return unresolved_fraction_; }
  static constexpr int kUnresolvedWindow = 5;

 private:
  friend class iterative::MatrixIterativeSolver<ConjugateGradientSolver>;
  /// Builds the incomplete Cholesky preconditioner if it is the one chosen (Factorize()).
  void Prepare(const Context& context);
  /// CG on the row-major blocks b and x (the columns [first, first + K) of the solve).
  template <int K>
  SolveSummary SolveGathered(const double* b, double* x, Eigen::Index first);
  /// SolveGathered()'s start: r = b − A x, z = M⁻¹ r, p = z; returns per column ‖b‖², ‖r‖², rᵀz.
  template <int K>
  std::array<iterative::ColumnValues, 3> Start(const double* b, const double* x);
  /// Sets unresolved_fraction() from a successful solve's `iterations` (the first block of
  /// columns, `first` = 0, resets it; later blocks raise it): `step_energy` holds each column's
  /// Σ α_j r_jᵀz_j, `last_terms` its last 2 · kUnresolvedWindow terms (a ring).
  template <int K>
  void EstimateUnresolved(
      const iterative::ColumnConvergence& convergence, const iterative::ColumnValues& step_energy,
      const std::array<std::array<double, 2 * kUnresolvedWindow>, K>& last_terms, int iterations,
      Eigen::Index first);
  /// z = M⁻¹ r for the incomplete Cholesky preconditioner (sequential).
  template <int K>
  void ApplyIncompleteCholesky(const double* r, double* z);

  using IncompleteCholesky =
      Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>;

  Options options_;
  double unresolved_fraction_ = 0.0;
  std::unique_ptr<IncompleteCholesky> incomplete_cholesky_;
  // Row-major work blocks (r, z, p, A p, the IC workspace), kept between solves.
  iterative::Block r_, z_, p_, q_, w_;
};

// SolveImpl() calls SolveGathered<K>, defined in the .cpp: instantiated there only.
extern template class iterative::BlockIterativeSolver<ConjugateGradientSolver>;
extern template class iterative::MatrixIterativeSolver<ConjugateGradientSolver>;

}  // namespace harap
