// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/linear_solver.h"

namespace harap {

struct CholmodFactorization;  // cholmod_factorization.h

/// Sparse Cholesky factorization A = P' L D L' P (simplicial) or A = P' L L' P (supernodal) with
/// CHOLMOD [Chen, Davis, Hager & Rajamanickam 2008], then X = A⁻¹ B by two triangular solves.
///
/// `a` is n×n SPD in full storage; CHOLMOD reads its lower triangle in place (no copy). B and X
/// are n×k (k = 3 for the global step). Factorize() redoes the symbolic analysis (ordering,
/// elimination tree) every time: each solver object factors one matrix (a hierarchy creates one
/// solver per level); Refactor() reuses it when only values change. Solve() is allocation-free
/// after its first call with a given k: the permuted right-hand side and solution live in
/// workspaces kept between calls. (BLAS, used by
/// solves with a supernodal factor, may allocate: OpenBLAS 0.3.21's small-matrix dgemm kernel
/// on AVX-512 machines takes a buffer from malloc on every call.)
///
/// Factorize() throws NumericalError when A is not positive definite (a negative or zero pivot,
/// or one so small relative to A's diagonal that A is numerically singular) or when CHOLMOD runs
/// out of memory; the message names the pivot and says what to try.
///
/// Not thread-safe: one object per thread. BLAS (used by the supernodal factorization) and
/// CHOLMOD's OpenMP loops run on Options::native_threads threads, not on the Context's task
/// arena. Compiled only when CHOLMOD was found (HARAP_WITH_CHOLMOD); create it through the
/// registry, which then lists "cholmod".
class CholmodSolver final : public LinearSolver {
 public:
  static constexpr std::string_view kName = "cholmod";

  enum class Mode {
    kAuto,        ///< Simplicial if flops / nnz(L) < 300 after the analysis, else supernodal.
    kSimplicial,  ///< Up-looking LDLᵀ, column by column: fastest solves, slow factorization.
    kSupernodal,  ///< LLᵀ over dense supernodes with BLAS: fast factorization, slower solves.
  };
  enum class Ordering {
    kMetis,  ///< METIS nested dissection: least fill on meshes, but the slowest analysis.
    kAmd,    ///< Approximate minimum degree: fast analysis, more fill than METIS on meshes.
    kBest,   ///< CHOLMOD's default: AMD, then METIS too if AMD's fill is high; keeps the best.
  };
  /// Who computes a supernodal numeric factorization (modes auto and supernodal).
  enum class Numeric {
    /// PartialSupernodalFactor::FactorAll: CHOLMOD's left-looking supernodal algorithm with the
    /// same values (bit for bit), independent subtrees of the elimination tree on the run's
    /// threads, reading A through the permutation (cholmod_factorize first makes permuted
    /// copies of A, which is most of what this saves; docs/solvers.md, "Why numeric =
    /// parallel").
    kParallel,
    kCholmod,  ///< cholmod_factorize.
  };
  /// Which route Refactor() takes (see Refactor() for the rule of kAuto).
  enum class RefactorChoice {
    kAuto,     ///< The cheapest of kPartial, kNumeric and kUpdate by the estimates below.
    kFull,     ///< Always Factorize() again (no copies kept between factorizations).
    kNumeric,  ///< Always reuse the analysis and factor the values anew.
    kUpdate,   ///< Always modify the factor (cholmod_updown / cholmod_rowadd).
    /// Refactor only the supernodes the changed rows reach (PartialSupernodalFactor); mode auto
    /// only (it keeps the supernodal factor beside the simplicial one), else kNumeric.
    kPartial,
  };

  struct Options {
    /// Factorization kind. "auto" = supernodal factorization converted to a simplicial factor
    /// for the solves. The supernodal (BLAS) factorization is several times faster than the
    /// simplicial one, while 3 right-hand sides are too few for its dense blocks to pay in the
    /// solves, where a simplicial factor is faster. ARAP factors once and solves 5–300 times, so
    /// neither pure mode suits all runs; converting (cholmod_change_factor, O(nnz(L))) gets the
    /// supernodal factorization time and the simplicial solve time (docs/solvers.md, "Why mode
    /// auto").
    Mode mode = Mode::kAuto;
    /// Fill-reducing ordering. AMD: METIS gives fewer nonzeros in L on surface meshes, so faster
    /// solves, but its analysis, redone on every Factorize(), costs more than those solves save
    /// unless a factor serves hundreds of them. "metis" pays off for volume meshes (more fill to
    /// save) and long runs (docs/solvers.md, "Why mode auto", has both orderings).
    Ordering ordering = Ordering::kAmd;
    /// Pivots d_k ≤ pivot_tolerance · A_kk count as zero (numerically singular A); in [0, 1),
    /// 0 rejects only non-positive pivots. The default lies between roundoff and real pivots: on
    /// grid Laplacians up to 90K unknowns |d| / A_kk ≤ 1.5e-12 when singular, ≥ 0.15 when
    /// pinned; SPD needs 0 < d_k ≤ A_kk.
    double pivot_tolerance = 1e-10;
    /// Solve with a simplicial factor (modes auto and simplicial) by substitution over
    /// independent subtrees of the elimination tree on all the context's threads
    /// (EliminationTreeSolve), instead of CHOLMOD's sequential cholmod_solve2. Same result up to
    /// rounding; see docs/benchmarks.md for the speed-up.
    bool parallel_solve = true;
    /// Compute max over columns of ‖b − A x‖ / ‖b‖ in every Solve() (keeps a copy of A; slow).
    bool check_residual = false;
    /// Threads for CHOLMOD's own parallelism in Factorize(): the OpenMP loops of its supernodal
    /// factorization (which ask for CHOLMOD_OMP_NUM_THREADS = 4 threads whatever the machine
    /// has) and the BLAS it calls (OpenBLAS: one thread per core); 0 leaves both as the
    /// environment sets them. harap parallelizes with TBB, and these threads only compete with
    /// it, the more so when a second factorization runs beside this one, as in the hierarchical
    /// optimizer's setup (docs/solvers.md, "Why native_threads = 1"). The BLAS thread count is
    /// process-wide: the last Factorize() sets it.
    int native_threads = 1;
    /// Refactor()'s route. kNumeric, kUpdate and kPartial, and kAuto after PrepareForRefactor(),
    /// keep a copy of the analysis (the symbolic factor, a few MB) and of the factored matrix (12
    /// bytes per nonzero of A) between calls, to reuse the one and to check the pattern and find
    /// the changed rows' old values with the other; in mode auto kPartial, and every route but
    /// kFull after PrepareForRefactor(), also keep the numeric supernodal factor (8 bytes per entry
    /// of its dense blocks; its size on a large mesh: docs/session.md) that kPartial refactors in
    /// part. kAuto without PrepareForRefactor() (one-shot runs) keeps none, and its Refactor()
    /// factors from scratch. kUpdate needs a simplicial factor (modes auto and simplicial).
    RefactorChoice refactor = RefactorChoice::kAuto;
    /// See Numeric.
    Numeric numeric = Numeric::kParallel;

    /// Reads the options and rejects unknown keys (ConfigError listing the valid ones).
    static Options FromConfig(OptionReader node);
  };

  explicit CholmodSolver(const Options& options);
  ~CholmodSolver() override;
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  /// What the analysis (ordering and symbolic factorization, no numeric work) says a
  /// factorization of a matrix will cost: the size of L and the flops, before any factoring.
  struct Estimate {
    double nnz_l = 0.0;         ///< Nonzeros of L (simplicial count).
    double flops = 0.0;         ///< Flop count of the factorization.
    double factor_bytes = 0.0;  ///< Memory of the numeric factor (values and row indices).
    double analysis_seconds = 0.0;
  };
  /// Analyses `a` (same contract as Factorize()) and keeps the analysis (and a copy of the
  /// pattern): the next Factorize() of a matrix with the same pattern reuses it instead of
  /// ordering again. Lets a caller decide
  /// whether to factor at all (AdaptiveSolver) for the price of the analysis alone.
  Estimate Analyze(const SparseMatrix& a);

  bool is_direct() const override { return true; }

  /// Refactor(), LinearSolver's public call, done by RefactorImpl (private, below; the routes are
  /// in cholmod_refactor_routes.h): Brings the factor up to date for `a` (same pattern, values
  /// changed only in the rows and columns `changed_rows`) by the route Options::refactor names; a
  /// different pattern (or no earlier Factorize(), or refactor = "full") factors from scratch
  /// (kFull). For handle edits of a masked matrix, name only the rows of the vertices that become
  /// or stop being handles: their neighbours' changed entries lie in those columns, and every row
  /// named costs work.
  ///
  /// kNumeric factors the values with a copy of the last analysis (ordering, elimination tree,
  /// supernodes); in mode auto the supernodal factor's values go straight into the simplicial
  /// factor's known pattern (no conversion, the solve's plan kept). It saves the analysis and
  /// nothing else. kUpdate (simplicial LDLᵀ only) first
  /// turns every changed row whose old row was not the identity's into the identity's, all at
  /// once: those rows and columns of L are replaced by the identity's and L D Lᵀ is updated with
  /// their old columns scaled by sqrt(d_k) (cholmod_updown, 8 columns per sweep along the
  /// elimination tree); then it adds every changed row whose new row is not the identity's
  /// (cholmod_rowadd: a sparse triangular solve for the row, then a rank-1 downdate along the
  /// path from the row to the root), each with its entries in the rows added so far. The factor
  /// keeps the symbolic pattern of the whole matrix (explicit zeros included), so its pattern
  /// never changes: after deletions only the parallel solve's pivots are refreshed; additions
  /// move the columns they solve through to the end of the factor's arrays (cholmod_rowadd
  /// makes room in columns without slack), so the solve's plan is set up again.
  ///
  /// kPartial (mode auto) keeps the numeric supernodal factor of the last factorization and
  /// recomputes only its supernodes on the elimination-tree paths from the changed columns to the
  /// root and those with a changed row (PartialSupernodalFactor: every other column of L is
  /// provably unchanged), then copies those columns into the simplicial factor (the solve's plan
  /// kept). On a mesh the paths hold the large separators, so even a local edit recomputes a
  /// large share of the work (docs/solvers.md measures it).
  /// After a kUpdate the kept supernodal factor is stale; the next kNumeric refreshes it.
  ///
  /// Rule of kAuto: the route with the lowest estimated time among kPartial (when its supernodal
  /// factor is current), kUpdate (simplicial factors) and kNumeric. kPartial's estimate is the
  /// flops of the supernodes it would recompute times the seconds per flop measured by the last
  /// partial refactorization of at least 10⁷ flops (before any: kDefaultPartialSecondsPerFlop);
  /// kNumeric's is the measured time of the last numeric factorization; kUpdate's counts the factor
  /// entries the modification touches — for each deletion the column counts summed along the
  /// elimination-tree path to the root from its column's first row that is not deleted too (where
  /// its column of the update starts), for each addition the path from its own column plus the
  /// longest path from the row's entries up to that column (the forward solve) — times the seconds
  /// per touched entry this solver measured in its last deletions and additions of at least 10⁶
  /// entries (before any: kDefaultDeleteSecondsPerEntry, kDefaultAddSecondsPerEntry), plus, if
  /// there are additions, the last measured set-up of the parallel solve's plan. All are measured
  /// on the machine the solver runs on; only the first update estimate uses the defaults.

  /// With refactor = "auto": keep the copies Refactor() reuses from the next Factorize() on.
  void PrepareForRefactor() override;

  /// Seconds per factor entry touched by the deletions and by the additions of an update before
  /// any was measured: what an update of armadillo-bend's finest matrix with a ball of 1% of the
  /// vertices measured (docs/solvers.md, "Refactoring after handle edits").
  static constexpr double kDefaultDeleteSecondsPerEntry = 0.8e-9;
  static constexpr double kDefaultAddSecondsPerEntry = 0.8e-9;
  /// Seconds per flop of a partial refactorization before one was measured: what the partial
  /// refactorization of the same edit measured (docs/solvers.md, "Refactoring after handle
  /// edits").
  static constexpr double kDefaultPartialSecondsPerFlop = 2e-10;

  /// What the last successful Factorize() produced (for experiments and benchmarks).
  struct FactorInfo {
    bool supernodal = false;    ///< Which kind "auto" (or the fixed mode) produced.
    std::string_view ordering;  ///< The ordering used: "amd" or "metis" (either for kBest).
    double nnz_l = 0.0;         ///< Nonzeros of L without supernodal padding.
    double flops = 0.0;         ///< Flop count of the (simplicial LLᵀ) factorization.
    /// With parallel_solve: the blocks of the elimination tree the solve runs on (0 = CHOLMOD's
    /// solve) and the heaviest root-to-leaf path of blocks as a fraction of the work (the part
    /// that stays sequential).
    int solve_blocks = 0;
    double solve_critical_path = 0.0;
    /// With numeric = "parallel": the independent subtrees the last supernodal factorization
    /// was split into (0: none, factored in order) and their share of its flops (the rest, the
    /// supernodes above them, is factored in order afterwards), and the heaviest subtree's
    /// share (no thread's part is smaller).
    int numeric_subtrees = 0;
    double numeric_subtree_work = 0.0;
    double numeric_largest_subtree = 0.0;
    /// Wall time of the last analysis (ordering, symbolic factorization) and of the last
    /// numeric factorization (including the conversion to simplicial form in mode auto).
    double analysis_seconds = 0.0;
    double numeric_seconds = 0.0;
    /// Wall time of the last preparation of the parallel solve (EliminationTreeSolve::Setup,
    /// or only new pivots when Refactor() kept the factor's pattern).
    double solve_setup_seconds = 0.0;
    /// Bytes kept for Refactor() (the analysis and the matrix; 0 with refactor = "full").
    double refactor_bytes = 0.0;
    /// Bytes of CHOLMOD's row indices freed because the parallel solve has its own copy and a
    /// one-shot factor (nothing kept for Refactor()) never reads them again (0 otherwise).
    double released_bytes = 0.0;
    /// The last Refactor()'s estimates (0 when it did not estimate), see Refactor().
    double estimated_update_seconds = 0.0;
    double estimated_numeric_seconds = 0.0;
    double estimated_partial_seconds = 0.0;
    /// The last partial refactorization's share of the factorization's flops and supernodes.
    double partial_work_fraction = 0.0;
    int partial_supernodes = 0;
  };
  const FactorInfo& factor_info() const;

  const Options& options() const;
  /// Changes Options::refactor for the next Refactor() calls (experiments, tests). Switching
  /// to a route that keeps copies takes effect after the next Factorize(), which keeps them.
  void set_refactor(RefactorChoice choice);

  static std::string_view ToString(Mode mode);
  static std::string_view ToString(Ordering ordering);
  static std::string_view ToString(RefactorChoice choice);

  /// Stops the idle worker threads of the BLAS behind CHOLMOD (OpenBLAS) and sets it to one
  /// thread, which is what Options::native_threads = 1 (the default) uses. OpenBLAS starts a
  /// worker per core but one when the process loads, and an idle worker spins in sched_yield for
  /// about 0.1 s (OpenBLAS's thread timeout) before it sleeps, taking a core from the run's
  /// threads; a factorization with native_threads > 1, or 0 where the environment's count is
  /// above 1, makes OpenBLAS start all of them again. Must not run while any thread is inside
  /// BLAS (a factorization, a host program's own BLAS calls): only for a program that owns its
  /// process, at its start (the command line). Does nothing with another BLAS. docs/solvers.md,
  /// "Why native_threads = 1".
  static void StopIdleNativeThreads();

 private:
  void FactorizeImpl(const SparseMatrix& a, const Context& context) override;
  SolveSummary SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
                         const Context& context) override;
  RefactorSummary RefactorImpl(const SparseMatrix& a, const std::vector<Index>& changed_rows,
                               const Context& context) override;
  std::unique_ptr<CholmodFactorization> factorization_;
};

}  // namespace harap
