// SPDX-License-Identifier: MIT
#pragma once

#include <string>
#include <vector>

#include "framework/context.h"
#include "framework/types.h"

namespace harap {

/// What one Solve() did.
///
/// `success` is false only when the answer is unusable (breakdown, divergence, NaN); an iterative
/// solver that spends its iteration budget before reaching its tolerance succeeds and says how
/// far it got through `relative_residual` (a fixed budget per global step is normal use).
struct SolveSummary {
  bool success = true;
  int iterations = 0;              ///< 0 for direct solvers.
  double relative_residual = 0.0;  ///< max over columns of ‖b − A x‖ / ‖b‖ (if computed, else 0).
  /// Whether relative_residual was measured (iterative solvers always; direct solvers only when
  /// asked to check it), so that reports never show an unmeasured 0 as a residual.
  bool residual_computed = false;
  double seconds = 0.0;            ///< Wall time of the Solve() call.
  std::string message;             ///< Why it failed, if it did.
};

/// Totals over a sequence of Solve() calls (one hierarchy level's global steps).
struct SolveStatistics {
  int solves = 0;
  long long iterations = 0;            ///< Sum of SolveSummary::iterations.
  double max_relative_residual = 0.0;  ///< Largest final relative residual of any solve.
  double last_relative_residual = 0.0;
  double seconds = 0.0;                ///< Sum of SolveSummary::seconds.
  /// Solves whose residual was measured (the residuals above cover only those; 0: not computed).
  int residuals_computed = 0;

  void Add(const SolveSummary& summary) {
    ++solves;
    if (summary.residual_computed) ++residuals_computed;
    iterations += summary.iterations;
    if (summary.relative_residual > max_relative_residual) {
      max_relative_residual = summary.relative_residual;
    }
    last_relative_residual = summary.relative_residual;
    seconds += summary.seconds;
  }
};

/// Solves A X = B for a fixed symmetric positive definite A and several right-hand sides at once
/// (the three coordinates of the global step).
///
/// Lifetime: Factorize() once per matrix (direct solvers analyze and factor; iterative solvers
/// set up preconditioners); then Solve() any number of times, allocation-free. `x` carries the
/// warm start on input (iterative solvers start from it; direct solvers ignore it).
/// Factorize() throws NumericalError if A is not positive definite or memory runs out, with a
/// message that says what to try instead.
///
///   auto solver = registries.linear_solvers.Create(config.Child("solver"), "cholmod");
///   solver->Factorize(a_ff, context);
///   solver->Solve(b, x, context);
class LinearSolver {
 public:
  virtual ~LinearSolver() = default;

  /// `a` is symmetric in full storage (both triangles).
  virtual void Factorize(const SparseMatrix& a, const Context& context) = 0;

  virtual SolveSummary Solve(const Eigen::Ref<const Eigen::MatrixXd>& b,
                             Eigen::Ref<Eigen::MatrixXd> x, const Context& context) = 0;

  /// True for factorization-based solvers (their result does not depend on the warm start).
  virtual bool is_direct() const = 0;

  /// How Refactor() brought the factorization up to date.
  enum class RefactorRoute {
    kFull,     ///< Analysis and factorization from scratch (what Factorize() does).
    kNumeric,  ///< The last analysis (ordering, elimination tree) reused, values factored anew.
    kUpdate,   ///< The existing factor modified row by row (low-rank updates), nothing refactored.
    kPartial,  ///< Only the part of the factor the changed rows reach factored anew.
  };
  struct RefactorSummary {
    RefactorRoute route = RefactorRoute::kFull;
    Index changed_rows = 0;
    double seconds = 0.0;
  };

  /// Call before Factorize() when Refactor() will follow (an interactive session's levels):
  /// solvers that keep copies to make Refactor() cheaper (the analysis, the matrix) keep them
  /// only then, so one-shot runs that never refactor pay neither the memory nor the copying.
  /// Refactor() works without it too (it may then factor from scratch). Default: nothing.
  virtual void PrepareForRefactor() {}

  /// Brings the factorization up to date for `a`, which has the same size and sparsity pattern
  /// (explicit zeros included) as the matrix of the last Factorize(), and whose values differ
  /// only in the rows and columns `changed_rows` (sorted, unique). Interactive sessions change
  /// which vertices are handles this way: a handle's row and column become the identity's.
  /// Solvers choose the cheapest route that gives the same factorization up to rounding; the
  /// default factors from scratch. Throws like Factorize(); on a throw the solver must be
  /// factored again before the next Solve().
  virtual RefactorSummary Refactor(const SparseMatrix& a, const std::vector<Index>& changed_rows,
                                   const Context& context) {
    Stopwatch clock;
    Factorize(a, context);
    return {RefactorRoute::kFull, static_cast<Index>(changed_rows.size()), clock.Seconds()};
  }

 protected:
  LinearSolver() = default;
};

}  // namespace harap
