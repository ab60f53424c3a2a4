// SPDX-License-Identifier: MIT
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "framework/context.h"
#include "framework/types.h"

namespace harap {

/// How one Solve() ended: one outcome instead of flags.
enum class SolveOutcome {
  kSolved,          ///< Solved by a factorization (or nothing to solve); residual not measured.
  kSolvedChecked,   ///< Solved by a factorization and the residual measured (check_residual).
  kConverged,       ///< Iterative: every column reached the tolerance.
  kIterationLimit,  ///< Iterative: the iteration budget ran out first (normal with tolerance 0);
                    ///< the answer is usable, relative_residual says how far it got.
  kFailed,          ///< Unusable (breakdown, divergence, NaN); `message` says why.
};

/// What one Solve() did.
///
/// Only kFailed means the answer is unusable; an iterative solver that spends its iteration
/// budget before reaching its tolerance succeeds (kIterationLimit) and says how far it got
/// through `relative_residual` (a fixed budget per global step is normal use).
struct SolveSummary {
  SolveOutcome outcome = SolveOutcome::kSolved;
  int iterations = 0;              ///< 0 for direct solvers.
  double relative_residual = 0.0;  ///< max over columns of ‖b − A x‖ / ‖b‖ (if measured, else 0).
  double seconds = 0.0;            ///< Wall time of the Solve() call (set by LinearSolver).
  std::string message;             ///< Why it failed, if it did.

  bool success() const { return outcome != SolveOutcome::kFailed; }
  /// Whether relative_residual was measured (iterative solvers always; direct solvers only when
  /// asked to check it), so that reports never show an unmeasured 0 as a residual.
  bool residual_computed() const {
    return outcome == SolveOutcome::kSolvedChecked || outcome == SolveOutcome::kConverged ||
           outcome == SolveOutcome::kIterationLimit;
  }
};

/// Totals over a sequence of Solve() calls (one hierarchy level's global steps).
struct SolveStatistics {
  int solves = 0;
  long long iterations = 0;            ///< Sum of SolveSummary::iterations.
  double max_relative_residual = 0.0;  ///< Largest final relative residual of any solve.
  double last_relative_residual = 0.0;
  double seconds = 0.0;  ///< Sum of SolveSummary::seconds.
  /// Solves whose residual was measured (the residuals above cover only those; 0: not computed).
  int residuals_computed = 0;

  void Add(const SolveSummary& summary) {
    ++solves;
    if (summary.residual_computed()) ++residuals_computed;
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
///
/// The public calls are written once here (Ceres' TypedLinearSolver pattern): they check their
/// arguments (a square matrix; a Factorize() before Solve(); b and x of the matrix's size), time
/// the call, turn a solution with NaN or infinite entries into a kFailed outcome and record the
/// outcome. Implementations only do the work, in the private virtual *Impl methods.
class LinearSolver {
 public:
  virtual ~LinearSolver() = default;

  /// `a` is symmetric in full storage (both triangles).
  void Factorize(const SparseMatrix& a, const Context& context);

  SolveSummary Solve(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
                     const Context& context);

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
  /// default factors from scratch. Throws like Factorize(); invalid arguments keep the factor,
  /// after other throws the solver must be factored again before the next Solve().
  RefactorSummary Refactor(const SparseMatrix& a, const std::vector<Index>& changed_rows,
                           const Context& context);

  /// Whether the last Factorize() (or Refactor()) succeeded, so that Solve() may be called.
  bool factorized() const { return factorized_; }
  /// Rows of the factorized matrix.
  Index rows() const { return rows_; }
  /// Wall time of the last Factorize() or Refactor() call.
  double factorize_seconds() const { return factorize_seconds_; }
  /// The solves since the last Factorize() or Refactor() (outcomes, iterations, time).
  const SolveStatistics& statistics() const { return statistics_; }

  /// Told what a solver that chooses its method per matrix (`adaptive`) chose: the method's name
  /// ("cholmod", "cg", "cg>cholmod") and whether its solves were direct, after each choice.
  /// Solvers with a single method never call it. The composition root records each level's
  /// choice for the run's report this way.
  using ChoiceObserver = std::function<void(std::string_view method, bool direct)>;
  void set_on_choice(ChoiceObserver on_choice) { on_choice_ = std::move(on_choice); }

 protected:
  /// `name`: the registry name, for the messages of the checks written here.
  explicit LinearSolver(std::string_view name) : name_(name) {}
  /// For solvers that choose their method: tells the observer set with set_on_choice(), if any.
  void ReportChoice(std::string_view method, bool direct) const {
    if (on_choice_) on_choice_(method, direct);
  }

 private:
  /// Factors `a` (square; Factorize() checked that and resets the state). Throws on failure.
  virtual void FactorizeImpl(const SparseMatrix& a, const Context& context) = 0;
  /// Solves for b and x of rows() rows and at least one column, after a successful
  /// FactorizeImpl(); sets outcome, iterations, residual and message (not seconds).
  virtual SolveSummary SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b,
                                 Eigen::Ref<Eigen::MatrixXd> x, const Context& context) = 0;
  /// Refactor()'s work; the default factors from scratch (FactorizeImpl).
  virtual RefactorSummary RefactorImpl(const SparseMatrix& a,
                                       const std::vector<Index>& changed_rows,
                                       const Context& context);
  std::string_view name_;
  bool factorized_ = false;
  Index rows_ = 0;
  double factorize_seconds_ = 0.0;
  SolveStatistics statistics_;
  ChoiceObserver on_choice_;
};

}  // namespace harap
