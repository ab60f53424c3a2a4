// SPDX-License-Identifier: MIT
#pragma once
// Part of the CHOLMOD solver (cholmod_solver.h): included only by sources compiled with CHOLMOD
// (HARAP_HAVE_CHOLMOD).

#include <cholmod.h>

#include <Eigen/Dense>
#include <string_view>
#include <vector>

#include "framework/context.h"
#include "framework/linear_solver.h"
#include "framework/types.h"
#include "solvers/linear/cholmod_solver.h"
#include "solvers/linear/elimination_tree_solve.h"
#include "solvers/linear/partial_supernodal_factor.h"

namespace harap {

/// What a CholmodSolver holds and the steps its calls are made of: CHOLMOD's workspace and
/// factors, the copies Refactor() reuses, the parallel solve's plan and the solve workspaces.
/// CholmodSolver's Factorize(), Analyze() and Solve() are Factorize(), Analyze() and Solve()
/// here; its Refactor() routes (cholmod_refactor_routes.h) work on the members directly, which is
/// why they are public. Not thread-safe (one per CholmodSolver).
///
/// The factors, in CHOLMOD's kinds:
/// - `factor`: the one Solve() uses. Mode auto: a supernodal LLᵀ factorization converted to a
///   packed simplicial LDLᵀ without the relaxed supernodes' explicit zeros, as cholmod_factorize
///   converts it (final_resymbol): the supernodal mode's factorization time with the simplicial
///   mode's solve time (why: docs/solvers.md, "Why mode auto").
/// - `symbolic`: with keeps_copies(), a copy of the last analysis for Refactor().
/// - `analysis`: Analyze()'s analysis until Factorize() of the same pattern takes it.
/// - `super`: with keeps_super(), the numeric supernodal LLᵀ factor `factor` was made from, which
///   the partial route refactors in part.
struct CholmodFactorization {
  using Options = CholmodSolver::Options;
  using Mode = CholmodSolver::Mode;
  using Numeric = CholmodSolver::Numeric;
  using RefactorChoice = CholmodSolver::RefactorChoice;

  explicit CholmodFactorization(const Options& options);
  ~CholmodFactorization();
  CholmodFactorization(const CholmodFactorization&) = delete;
  CholmodFactorization& operator=(const CholmodFactorization&) = delete;

  // CholmodSolver's calls (see cholmod_solver.h; `a` was checked to be square).
  void Factorize(const SparseMatrix& a, const Context& context);
  CholmodSolver::Estimate Analyze(const SparseMatrix& a);
  SolveSummary Solve(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
                     const Context& context);

  // Numeric factorization steps. `view` is cholmod_views::LowerTriangleView(a).

  /// The numeric supernodal LLᵀ factorization of `a` into `f` (a supernodal analysis, or a
  /// numeric supernodal factor of the same analysis), as cholmod_factorize's supernodal step
  /// computes it. numeric = "parallel": PartialSupernodalFactor::FactorAll runs the same
  /// left-looking algorithm (bit-identical values) with independent subtrees on the context's
  /// threads, and reads A through the permutation instead of making the permuted copies of A
  /// that cholmod_factorize makes first (docs/solvers.md, "Why numeric = parallel"); with
  /// native_threads ≠ 1 the BLAS has threads of its own, so one thread here. numeric =
  /// "cholmod": cholmod_factorize itself. False, with common.status and f->minor set as CHOLMOD
  /// sets them, on failure.
  bool FactorSupernodal(cholmod_factor* f, cholmod_sparse& view, const SparseMatrix& a,
                        const Context& context);
  /// FactorSupernodal() into the kept `super` (its analysis), left as the supernodal LLᵀ for
  /// partial refactorization; on failure `super` becomes `factor` so ThrowOnFailure reports the
  /// failed pivot.
  void FactorizeKeptSupernodal(cholmod_sparse& view, const SparseMatrix& a, const Context& context);
  /// Factorize()'s numeric factorization when the supernodal factor is kept: the supernodal
  /// factorization into `super` (a copy of the analysis), then `factor` made from a copy of it as
  /// cholmod_factorize makes it (ConvertToFinal): the same values.
  void FactorNumericKeepingSuper(cholmod_sparse& view, const SparseMatrix& a,
                                 const Context& context);
  /// The numeric factorization of `view` into `factor` (symbolic on entry), timed: a supernodal
  /// analysis by FactorSupernodal(), then converted to the final kind as cholmod_factorize
  /// converts it (mode auto: a packed simplicial LDLᵀ without the relaxed supernodes' zeros), a
  /// simplicial one by cholmod_factorize.
  void FactorNumeric(cholmod_sparse& view, const SparseMatrix& a, const Context& context);
  /// What cholmod_factorize does after a supernodal factorization unless final_asis: the
  /// conversion to the final kind of factor, and the re-symbolic pass of a simplicial one.
  void ConvertToFinal(cholmod_sparse& view, const SparseMatrix& a);
  /// Mode auto's numeric refactorization into the current simplicial LDLᵀ factor's own arrays:
  /// a supernodal LLᵀ factorization with a copy of the analysis, then d_j = L_jj² and
  /// l_ij = L_ij / L_jj for the entries of the simplicial pattern. That is what
  /// cholmod_factorize's conversion computes (cholmod_change_factor, then cholmod_resymbol to drop
  /// the relaxed supernodes' zeros), but the pattern is known from the last factorization of the
  /// same analysis, so neither the conversion's copy nor the re-symbolic pass is needed, and the
  /// solve's plan stays valid. Returns false, before changing anything, if the factor is not
  /// such a factor; throws like Factorize() (leaving the supernodal factor for the message).
  bool FactorNumericInPlace(cholmod_sparse& view, const SparseMatrix& a, const Context& context);
  /// Copies the columns of the supernodes `partial` marked (all if `all`) from `super` into the
  /// simplicial LDLᵀ `factor` of the same analysis: d_j = L_jj², l_ij = L_ij / L_jj on the
  /// simplicial pattern (a subset of the supernode's rows). False if the patterns do not match.
  bool CopySuperToSimplicial(bool all);
  /// After a numeric factorization or modification: the pivot check, the statistics, the
  /// parallel solve's plan (`same_arrays`: the factor was modified in place without changing its
  /// pattern, so the plan only needs the new pivots; `same_pattern`: a numeric refactorization
  /// with the same analysis, whose pattern EliminationTreeSolve::Rebind verifies), and the copy
  /// of `a`.
  void FinishFactor(const SparseMatrix& a, const Eigen::VectorXd& diagonal, const Context& context,
                    bool same_arrays = false, bool same_pattern = false);

  // The analysis.

  /// The analysis (ordering, symbolic factor) of `a`, timed: Analyze()'s kept one if it was made
  /// for this very pattern, else a new one.
  cholmod_factor* TakeOrMakeAnalysis(const SparseMatrix& a);
  /// Whether compressed `a` has the pattern Analyze() was given.
  bool IsAnalysisPattern(const SparseMatrix& a) const;

  // What is kept.

  /// Keeps copies for Refactor() (the matrix also for check_residual): with an explicit numeric,
  /// update or partial route, or with auto after PrepareForRefactor() (a one-shot run that never
  /// refactors keeps nothing: the memory and the copying time; docs/solvers.md, "Refactoring after
  /// handle edits").
  bool keeps_copies() const;
  /// Keeps `super`, the numeric supernodal factor, for partial refactorizations: mode auto (the
  /// solves use the simplicial factor made from it), route partial, or any route but full after
  /// PrepareForRefactor() (set_refactor() may switch to partial later).
  bool keeps_super() const;
  SupernodalFactorView SuperView() const;
  void FreeFactor();
  void FreeSymbolic();
  void FreeAnalysis();
  void FreeSuper();
  /// A one-shot factor (no analysis copy kept, so Refactor() can only factor anew) solved by the
  /// tree: the tree solve holds its own, renumbered copy of the row indices and nothing reads
  /// CHOLMOD's again (no cholmod_solve2, no update, no conversion; FreeFactor() frees a null
  /// array), so they are freed: 4 bytes per factor entry, the largest array of a large run after
  /// the factor's values (FactorInfo::released_bytes; peak memory in docs/results.md).
  void ReleaseRowsOfOneShotFactor();
  /// Whether ReleaseRowsOfOneShotFactor() freed the rows of the current numeric factor (a
  /// numeric simplicial factor has them otherwise).
  bool rows_released() const;

  // Checks.

  /// Throws for every failure status of the last CHOLMOD call; warnings other than NOT_POSDEF
  /// (e.g. DSMALL) are left to the pivot check.
  void ThrowOnFailure(std::string_view stage, const SparseMatrix& a) const;
  /// CHOLMOD's simplicial LDLᵀ accepts negative pivots (it handles some indefinite matrices) and
  /// no factorization notices a pivot that is roundoff of a zero one (a singular matrix), so
  /// this checks each pivot against the matching diagonal entry of A.
  void CheckPivots(const SparseMatrix& a, const Eigen::VectorXd& diagonal) const;
  /// Measures a solution's residual if asked to (LinearSolver::Solve() checks and times it).
  SolveSummary FinishSolve(const Eigen::Ref<const Eigen::MatrixXd>& b,
                           const Eigen::Ref<Eigen::MatrixXd>& x);

  Options options;
  bool prepared_for_refactor = false;
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  cholmod_factor* symbolic = nullptr;
  cholmod_factor* analysis = nullptr;
  std::vector<int> analysis_outer, analysis_inner;  // its pattern, compressed (no values)
  struct {
    double lnz = 0.0, fl = 0.0, seconds = 0.0;
  } analysis_of;
  cholmod_factor* super = nullptr;
  bool super_current = false;  // no update modified `factor` since `super` was factored
  // The partial refactorization's structure and last measured speed.
  PartialSupernodalFactor partial;
  double partial_seconds_per_flop = CholmodSolver::kDefaultPartialSecondsPerFlop;
  // Seconds per factor entry touched by the deletions (cholmod_updown) and the additions
  // (cholmod_rowadd), as the last update measured them (see Refactor()).
  double delete_seconds_per_entry = CholmodSolver::kDefaultDeleteSecondsPerEntry;
  double add_seconds_per_entry = CholmodSolver::kDefaultAddSecondsPerEntry;
  // Wall time of the last full set-up of the parallel solve's plan, which additions cause.
  double plan_seconds = 0.0;
  // Solve workspaces, kept so that Solve() allocates only on its first call (per column count).
  cholmod_dense* x = nullptr;
  cholmod_dense* y = nullptr;
  cholmod_dense* e = nullptr;
  // With parallel_solve and a simplicial factor: solves with `factor` in place.
  EliminationTreeSolve tree_solve;
  LdltFactorView tree_view;  // the arrays tree_solve was set up with
  bool use_tree_solve = false;
  int rows = 0;
  bool factorized = false;
  CholmodSolver::FactorInfo info;
  // The last factored matrix: with check_residual (for the residual) or keeps_copies() (for
  // Refactor(): the pattern check and the changed rows' old values).
  SparseMatrix matrix;
  Eigen::MatrixXd residual;
  // Refactor() workspaces (factor order): path costs, the inverse permutation, marks, and the
  // row handed to cholmod_rowadd.
  std::vector<double> path_cost;
  std::vector<int> inverse_permutation, mark, row_index;
  std::vector<double> row_value;
  std::vector<int> update_start, update_row;  // the columns of the deletions' update
  std::vector<double> update_value;
};

}  // namespace harap
