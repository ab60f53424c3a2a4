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
/// permuted right-hand side and solution live in workspaces kept between calls.
///
/// Factorize() throws NumericalError when A is not positive definite (a negative or zero pivot,
/// or one so small relative to A's diagonal that A is numerically singular) or when CHOLMOD runs
/// out of memory; the message names the pivot and says what to try.
///
/// Not thread-safe: one object per thread. BLAS (used by the supernodal factorization) follows
/// OPENBLAS_NUM_THREADS, not the Context's task arena.
class CholmodSolver final : public LinearSolver {
 public:
  static constexpr std::string_view kName = "cholmod";

  enum class Mode {
    kAuto,        ///< Simplicial or supernodal by flops / nnz(L) after analysis (see .cpp).
    kSimplicial,  ///< Up-looking LDLᵀ, column by column: fastest solves, slow factorization.
    kSupernodal,  ///< LLᵀ over dense supernodes with BLAS: fast factorization, slower solves.
  };
  enum class Ordering {
    kMetis,  ///< METIS nested dissection: least fill on meshes, but the slowest analysis.
    kAmd,    ///< Approximate minimum degree: fast analysis, 10–20% more fill on 2D meshes.
    kBest,   ///< CHOLMOD's default: AMD, then METIS too if AMD's fill is high; keeps the best.
  };

  struct Options {
    /// Factorization kind; "auto" picks the one with the lower factor + ~100 solves time.
    Mode mode = Mode::kAuto;
    /// Fill-reducing ordering. AMD: see the measurements in the .cpp.
    Ordering ordering = Ordering::kAmd;
    /// Pivots d_k ≤ pivot_tolerance · A_kk count as zero (numerically singular A). In
    /// (0, 1); 0 rejects only non-positive pivots. Singular meshes give |d_k| / A_kk ≈ 1e-12.
    double pivot_tolerance = 1e-10;
    /// Compute max over columns of ‖b − A x‖ / ‖b‖ in every Solve() (keeps a copy of A; slow).
    bool check_residual = false;

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
    bool supernodal = false;  ///< Which kind "auto" (or the fixed mode) produced.
    std::string_view ordering;  ///< The ordering used: "amd" or "metis" (either for kBest).
    double nnz_l = 0.0;       ///< Nonzeros of L without supernodal padding.
    double flops = 0.0;       ///< Flop count of the (simplicial LLᵀ) factorization.
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
