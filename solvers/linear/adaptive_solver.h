// SPDX-License-Identifier: MIT
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "framework/config.h"
#include "framework/linear_solver.h"
#include "solvers/linear/cholmod_solver.h"
#include "solvers/linear/conjugate_gradient_solver.h"

namespace harap {

/// Factor or iterate, decided per matrix before any factoring: the paper's suggestion (Section
/// 5.2) to use Cholesky on the levels where factoring is affordable and a warm-started iterative
/// solver (preconditioned CG from the up-sampled solution) on the finest levels where factoring
/// costs too much time or memory.
///
/// With choose = "auto", Factorize() first runs CHOLMOD's analysis alone (ordering and symbolic
/// factorization, a fraction of the factorization's time; kept and reused if it factors) and
/// reads from it the size of L and the flop count of the factorization. It then iterates when
///   - the factor would need more than max_factor_megabytes of memory (default: half the
///     machine's physical memory), or
///   - factoring plus `expected_solves` solves with the factor would take more arithmetic than
///     `expected_solves` CG solves of max_iterations iterations each:
///       flops(L) + s · 4 k nnz(L)  >  s · m · k (2 nnz(A) + 12 n)
///     (s = expected_solves, k = 3 right-hand sides, m = CG iterations per solve; a forward and
///     a backward substitution touch each entry of L twice, a Jacobi-preconditioned CG iteration
///     is a product with A plus about six vector updates).
/// Both sides are counts of arithmetic from the matrix and CHOLMOD's analysis, not timings, so
/// the choice is the same on every machine. choose = "direct" or "iterative" fixes the choice
/// (per level through the factory's `[solver.level_<l>]` tables).
///
/// When it iterates by the arithmetic rule (not for memory) and the matrix then serves more
/// solves than expected, it factors after all and solves directly from then on (chosen() =
/// "cg>cholmod"): before the solve at which the CG iterations so far have cost flops(L) (at
/// most about twice the arithmetic of the better choice in hindsight, the ski-rental argument,
/// however wrong expected_solves was), before solve number expected_solves + 1 (the premise of
/// the choice no longer holds), or when a CG solve left more than max_unresolved of its
/// correction undone (ConjugateGradientSolver::unresolved_fraction()), whichever comes first.
/// After the first solve such a stall switches before the next solve (the level often stops
/// after its first step from the up-sampled start, and then needs no factor); after a later
/// one, the level is still moving, and that system is solved again with the factor at once,
/// so the caller does not get the inexact step. Iterating because the factor exceeds the memory
/// budget (or choose = "iterative"), it never switches.
/// The last two see what the arithmetic count does not: CG's inexact steps cost the caller extra
/// global steps, and where the up-sampled start misses smooth components of the solution
/// (dragon-lift from 437K vertices up: a second step as large as the first, its CG terms
/// decaying by 1–2% per iteration), 20 Jacobi-preconditioned iterations per step resolve them
/// only over dozens of steps.
///
/// The direct solver is "cholmod" with the options of the `direct` table, the iterative one
/// "cg" with those of the `iterative` table. chosen() names the one in use.
/// Compiled only with CHOLMOD (HARAP_HAVE_CHOLMOD).
class AdaptiveSolver final : public LinearSolver {
 public:
  static constexpr std::string_view kName = "adaptive";

  enum class Choice { kAuto, kDirect, kIterative };

  struct Options {
    Choice choose = Choice::kAuto;
    /// Memory budget of the factor in MB; 0: half the physical memory (sysconf).
    double max_factor_megabytes = 0.0;
    /// Global steps (3-column solves) the matrix is expected to serve: hierarchical levels take
    /// 5–15 on armadillo-bend at tolerance 1e-6 (docs/results.md), classic runs 20–200.
    double expected_solves = 10.0;
    /// Factor once a CG solve left more than this share of its correction (A-norm squared)
    /// undone: before the next solve after the first one, at once (solving that system again)
    /// after a later one; 1 never does.
    double max_unresolved = 0.5;
    CholmodSolver::Options direct;
    ConjugateGradientSolver::Options iterative;

    static Options FromConfig(OptionReader node);
  };

  /// Why the last Factorize() chose what it chose.
  struct Decision {
    bool direct = true;
    bool estimated = false;  ///< Whether the analysis ran (choose = "auto").
    CholmodSolver::Estimate estimate;
    double budget_bytes = 0.0;
    double direct_flops = 0.0;     ///< flops(L) + s · 4 k nnz(L)
    double iterative_flops = 0.0;  ///< s · m · k (2 nnz(A) + 12 n)
  };

  explicit AdaptiveSolver(const Options& options);
  ~AdaptiveSolver() override;

  /// The chosen solver's; false before the first Factorize() (so callers warm-start).
  bool is_direct() const override;
  void PrepareForRefactor() override;

  /// "cholmod", "cg" or "cg>cholmod" (switched) after a Factorize(), "" before.
  std::string_view chosen() const;
  const Decision& decision() const { return decision_; }
  const Options& options() const { return options_; }

  /// The memory budget max_factor_megabytes = 0 stands for: half the physical memory.
  static double DefaultBudgetBytes();

 private:
  void FactorizeImpl(const SparseMatrix& a, const Context& context) override;
  SolveSummary SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
                         const Context& context) override;
  /// A direct choice refactors with cholmod's routes (same pattern, so the factor's size is
  /// unchanged); an iterative one decides anew (FactorizeImpl).
  RefactorSummary RefactorImpl(const SparseMatrix& a, const std::vector<Index>& changed_rows,
                               const Context& context) override;

  /// Factors `iterative_`'s matrix with the kept analysis and solves directly from now on.
  void SwitchToDirect(const Context& context);

  Options options_;
  bool prepared_for_refactor_ = false;
  std::unique_ptr<CholmodSolver> direct_;
  std::unique_ptr<ConjugateGradientSolver> iterative_;
  LinearSolver* chosen_ = nullptr;
  Decision decision_;
  bool may_switch_ = false;
  bool switched_ = false;
  double iterated_flops_ = 0.0;  // arithmetic of the CG solves since Factorize()
  int iterative_solves_ = 0;     // CG solves since Factorize()
  bool stalled_ = false;         // the first CG solve left more than max_unresolved undone
};

}  // namespace harap
