// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/linear_solver.h"

namespace harap {

/// Sparse Cholesky factorization A = P' L D L' P (simplicial) or A = P' L L' P (supernodal) with
/// CHOLMOD [Chen, Davis, Hager & Rajamanickam 2008], then X = A⁻¹ B by two triangular solves.
///
/// `a` is n×n SPD in full storage; CHOLMOD reads its lower triangle in place (no copy). B and X
/// are n×k (k = 3 for the global step). Factorize() redoes the symbolic analysis (ordering,
/// elimination tree) every time: each solver object factors one matrix (a hierarchy creates one
/// solver per level). Solve() is allocation-free after its first call with a given k: the
/// permuted right-hand side and solution live in workspaces kept between calls. (BLAS, used by
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
    kAmd,    ///< Approximate minimum degree: fast analysis, 10–20% more fill on 2D meshes.
    kBest,   ///< CHOLMOD's default: AMD, then METIS too if AMD's fill is high; keeps the best.
  };

  struct Options {
    /// Factorization kind. "auto" = supernodal factorization converted to a simplicial factor
    /// for the solves: 174K-vertex cotangent Laplacian, AMD, 1 thread: simplicial
    /// 1.3–1.9 s + 30–40 ms per 3-column solve, supernodal 0.32–0.50 s + 48–56 ms (.cpp table);
    /// auto gets the supernodal factorization time and the simplicial solve time.
    Mode mode = Mode::kAuto;
    /// Fill-reducing ordering. AMD, measured: METIS gives 15% fewer nonzeros in L on surface
    /// meshes (6.1M vs 7.3M at 174K vertices) but its analysis, redone on every Factorize(),
    /// costs 1.3–1.5 s vs 0.2–0.3 s; analysis + factor + 100 solves took 5.1–6.2 s with METIS,
    /// 4.6–5.9 s with AMD (a tie at 300 solves). "metis" pays off for volume meshes and long
    /// runs (27K cube, 300 solves: 6.5 s vs 8.0 s).
    Ordering ordering = Ordering::kAmd;
    /// Pivots d_k ≤ pivot_tolerance · A_kk count as zero (numerically singular A); in [0, 1),
    /// 0 rejects only non-positive pivots. Measured: |d| / A_kk ≤ 1.5e-12 for singular grid
    /// Laplacians up to 90K unknowns, ≥ 0.15 for pinned ones; SPD needs 0 < d_k ≤ A_kk.
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
    /// it: on armadillo-bend's finest level (2-core VM, docs/benchmarks.md) 1 factors 1.4×
    /// faster than 0 alone, and 2.8× faster with a second factorization running beside it, as
    /// in the hierarchical optimizer's setup. The BLAS thread count is process-wide: the last
    /// Factorize() sets it.
    int native_threads = 1;

    /// Reads the options and rejects unknown keys (ConfigError listing the valid ones).
    static Options FromConfig(const ConfigNode& node);
  };

  explicit CholmodSolver(const Options& options);
  ~CholmodSolver() override;
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  static std::unique_ptr<LinearSolver> Create(const ConfigNode& node);

  void Factorize(const SparseMatrix& a, const Context& context) override;
  SolveSummary Solve(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
                     const Context& context) override;
  bool is_direct() const override { return true; }

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
  };
  const FactorInfo& factor_info() const;

  const Options& options() const;

  static std::string_view ToString(Mode mode);
  static std::string_view ToString(Ordering ordering);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace harap
