// SPDX-License-Identifier: MIT
#pragma once

// Building blocks shared by the iterative linear solvers of this module (gauss_seidel, cg,
// chebyshev); not a component.
//
// Every solver works on blocks of up to three right-hand sides at once, stored row-major
// (row i of a K-column block is K consecutive doubles), so one pass over the matrix serves all
// columns of the block: the global step's three coordinates stream A once per iteration. Kernels
// are templates on the column count K ∈ {1, 2, 3}; DispatchColumns() turns a run-time count into
// the template argument. Reductions use tbb::parallel_deterministic_reduce over fixed row ranges,
// so results are bit-identical for any thread count.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "framework/config.h"
#include "framework/context.h"
#include "framework/error.h"
#include "framework/linear_solver.h"
#include "framework/types.h"
#include "solvers/linear/solver_checks.h"

namespace harap::iterative {

/// Columns handled together by one pass over the matrix (the global step has three).
inline constexpr int kMaxBlockColumns = 3;
/// Rows per task: also fixes the reduction tree, hence the bits of every result.
inline constexpr Index kRowGrain = 1024;

using ColumnValues = std::array<double, kMaxBlockColumns>;

/// Calls f(std::integral_constant<int, K>{}) with K = columns (1, 2 or 3).
template <class F>
decltype(auto) DispatchColumns(int columns, F&& f) {
  switch (columns) {
    case 1:
      return f(std::integral_constant<int, 1>{});
    case 2:
      return f(std::integral_constant<int, 2>{});
    default:
      return f(std::integral_constant<int, 3>{});
  }
}

/// Parallel loop over rows [0, n) in chunks of kRowGrain (inline when there is one chunk: small
/// systems, e.g. coarse levels, would otherwise pay the task overhead on every pass).
template <class F>
void ForRows(Index n, F&& f) {
  if (n <= kRowGrain) {
    for (Index i = 0; i < n; ++i) f(i);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<Index>(0, n, kRowGrain),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index i = range.begin(); i != range.end(); ++i) f(i);
                    });
}

/// Deterministic parallel sum over rows [0, n) of per-row column values: f(i, sums) adds row i's
/// contributions to `sums` (an array of `Count` column vectors of K sums each, e.g. p·q, or r·r
/// and r·z together).
template <int Count, class F>
std::array<ColumnValues, Count> SumRows(Index n, F&& f) {
  using Sums = std::array<ColumnValues, Count>;
  if (n <= kRowGrain) {  // One chunk: the same sums, without the task overhead.
    Sums sums{};
    for (Index i = 0; i < n; ++i) f(i, sums);
    return sums;
  }
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Index>(0, n, kRowGrain), Sums{},
      [&](const tbb::blocked_range<Index>& range, Sums sums) {
        for (Index i = range.begin(); i != range.end(); ++i) f(i, sums);
        return sums;
      },
      [](Sums a, const Sums& b) {
        for (int s = 0; s < Count; ++s) {
          for (int c = 0; c < kMaxBlockColumns; ++c) a[s][c] += b[s][c];
        }
        return a;
      });
}

/// out[c] = Σ_j A_ij x[j·K + c] for row i of the symmetric matrix `a` (column i of its compressed
/// column storage, which equals row i by symmetry).
template <int K>
inline void RowProduct(const SparseMatrix& a, Index i, const double* x, double* out) {
  const Index* outer = a.outerIndexPtr();
  const Index* inner = a.innerIndexPtr();
  const double* value = a.valuePtr();
  double sum[K] = {};
  for (Index p = outer[i]; p < outer[i + 1]; ++p) {
    const double* xj = x + static_cast<std::ptrdiff_t>(inner[p]) * K;
    for (int c = 0; c < K; ++c) sum[c] += value[p] * xj[c];
  }
  for (int c = 0; c < K; ++c) out[c] = sum[c];
}

/// A K-column row-major work block whose storage only grows (so solves with one column count
/// never reallocate after the first).
class Block {
 public:
  double* Reserve(Index rows, int columns) {
    const size_t size = static_cast<size_t>(rows) * static_cast<size_t>(columns);
    if (data_.size() < size) data_.resize(size);
    return data_.data();
  }
  double* data() { return data_.data(); }

 private:
  std::vector<double> data_;
};

/// block (row-major, K columns) = columns [first, first + K) of `source`.
template <int K>
void GatherColumns(const Eigen::Ref<const Eigen::MatrixXd>& source, Eigen::Index first,
                   double* block) {
  ForRows(static_cast<Index>(source.rows()), [&](Index i) {
    for (int c = 0; c < K; ++c)
      block[static_cast<std::ptrdiff_t>(i) * K + c] = source(i, first + c);
  });
}

/// Columns [first, first + K) of `target` = block.
template <int K>
void ScatterColumns(const double* block, Eigen::Index first, Eigen::Ref<Eigen::MatrixXd> target) {
  ForRows(static_cast<Index>(target.rows()), [&](Index i) {
    for (int c = 0; c < K; ++c)
      target(i, first + c) = block[static_cast<std::ptrdiff_t>(i) * K + c];
  });
}

/// Max over the K columns of ‖b_c − A x_c‖ / ‖b_c‖ (‖b_c − A x_c‖ for a zero column), from
/// row-major blocks; `squared_b` holds ‖b_c‖². One pass over A.
template <int K>
double MaxRelativeResidual(const SparseMatrix& a, const double* b, const double* x,
                           const ColumnValues& squared_b) {
  const ColumnValues rr = SumRows<1>(static_cast<Index>(a.rows()), [&](Index i, auto& sums) {
    double ax[K];
    RowProduct<K>(a, i, x, ax);
    for (int c = 0; c < K; ++c) {
      const double r = b[i * K + c] - ax[c];
      sums[0][c] += r * r;
    }
  })[0];
  double worst = 0.0;
  for (int c = 0; c < K; ++c) {
    worst = std::max(worst, std::sqrt(rr[c] / (squared_b[c] > 0.0 ? squared_b[c] : 1.0)));
  }
  return worst;
}

/// Which columns of a block still iterate, and the relative residuals ‖r_c‖ / ‖b_c‖ (‖r_c‖ for
/// a zero column, as solver_checks::MaxRelativeResidual). A column stops once its relative
/// residual is ≤ the tolerance (tolerance 0: only an exactly zero residual stops it), so a column
/// solved alone and the same column solved in a block take the same iterations.
class ColumnConvergence {
 public:
  /// `squared_b`: ‖b_c‖²; `squared_residual`: ‖r_c‖² of the starting guess.
  ColumnConvergence(int columns, const ColumnValues& squared_b,
                    const ColumnValues& squared_residual, double tolerance);

  /// Records the new ‖r_c‖² of the active columns and deactivates those that converged.
  /// Returns false if some residual is not finite or grew by more than kDivergenceFactor over
  /// its start value: impossible for an SPD matrix (see the solvers), so the iteration has
  /// diverged.
  bool Update(const ColumnValues& squared_residual);

  bool active(int c) const { return active_[c]; }
  bool any_active() const;
  /// Max over columns of the last recorded relative residual.
  double max_relative_residual() const;

  /// ‖r‖ may grow by at most √κ(A) under Gauss–Seidel and Chebyshev iterations with valid
  /// bounds on an SPD matrix (their A-norm error never grows); √κ < 1e8 for every matrix that is
  /// not numerically singular in double precision.
  static constexpr double kDivergenceFactor = 1e8;

 private:
  int columns_;
  double tolerance_;
  ColumnValues scale_{};  ///< ‖b_c‖² (1 for a zero column).
  ColumnValues start_{};  ///< ‖r_c‖² at the start.
  ColumnValues squared_residual_{};
  std::array<bool, kMaxBlockColumns> active_{};
};

/// The options every iterative solver shares.
struct IterationLimits {
  /// Iterations per Solve() (per global step); with tolerance > 0 a cap.
  int max_iterations = 10;
  /// Stop a column when ‖b − A x‖ / ‖b‖ ≤ tolerance; 0 runs max_iterations every solve.
  double tolerance = 0.0;
};

/// Reads `max_iterations` and `tolerance` into `limits` (defaults on input) with help texts that
/// say what one iteration is (`iteration`, e.g. "symmetric sweep"); validates them.
void ReadIterationLimits(OptionReader node, std::string_view iteration, IterationLimits& limits);

/// Options::FromConfig() of an iterative solver, written once: Options' defaults, the shared
/// limits (ReadIterationLimits into options.limits), the solver's own keys (read_own(options)),
/// then RejectUnknownKeys().
template <class Options, class ReadOwn>
Options ReadIterativeOptions(OptionReader node, std::string_view iteration, ReadOwn&& read_own) {
  Options options;
  ReadIterationLimits(node, iteration, options.limits);
  read_own(options);
  node.RejectUnknownKeys();
  return options;
}

/// The compressed copy of `a` the solvers iterate with (Eigen's uncompressed storage has gaps
/// between columns that the kernels would have to skip).
SparseMatrix CompressedCopy(const SparseMatrix& a);

/// The message for an iteration that diverged (residual grew by kDivergenceFactor, or NaN).
std::string DivergenceMessage(std::string_view solver, int iteration, std::string_view cause);

/// The end of a conjugate-gradient step (cg, multigrid's preconditioned CG): records the new
/// ‖r_c‖² in `convergence`; if the iteration diverged, marks `summary` failed with `solver`'s
/// divergence message and returns false.
bool RecordCgResiduals(ColumnConvergence& convergence, const ColumnValues& squared_residual,
                       std::string_view solver, SolveSummary& summary);

/// The body of every iterative SolveImpl(): runs solve_block(first, std::integral_constant<int,
/// K>{}) for the column blocks [first, first + K) of b and x (K = 3 except for the last block)
/// and merges what the blocks report: iterations and residual are maxima over blocks, the first
/// failure wins, and the outcome is kConverged only if every block converged. (LinearSolver's
/// Solve() checked the call and times it.)
template <class F>
SolveSummary SolveByBlocks(const Eigen::Ref<const Eigen::MatrixXd>& b, F&& solve_block) {
  SolveSummary summary;
  summary.outcome = SolveOutcome::kConverged;
  for (Eigen::Index first = 0; first < b.cols(); first += kMaxBlockColumns) {
    const int k = static_cast<int>(std::min<Eigen::Index>(kMaxBlockColumns, b.cols() - first));
    const SolveSummary block =
        DispatchColumns(k, [&](auto width) { return solve_block(first, width); });
    summary.iterations = std::max(summary.iterations, block.iterations);
    summary.relative_residual = std::max(summary.relative_residual, block.relative_residual);
    if (!summary.success()) continue;
    if (!block.success()) {
      summary.outcome = SolveOutcome::kFailed;
      summary.message = block.message;
    } else if (block.outcome == SolveOutcome::kIterationLimit) {
      summary.outcome = SolveOutcome::kIterationLimit;
    }
  }
  return summary;
}

/// The base of the iterative solvers (gauss_seidel, cg, chebyshev): LinearSolver's SolveImpl()
/// written once, as SolveByBlocks over Derived::SolveBlock<K>(b, x, first), which solves the
/// columns [first, first + K) (Derived befriends this class). Not direct.
template <class Derived>
class BlockIterativeSolver : public LinearSolver {
 public:
  bool is_direct() const final { return false; }

 protected:
  using LinearSolver::LinearSolver;

 private:
  SolveSummary SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
                         const Context& /*context*/) final {
    return SolveByBlocks(b, [&](Eigen::Index first, auto width) {
      return static_cast<Derived&>(*this).template SolveBlock<decltype(width)::value>(b, x, first);
    });
  }
};

/// The base of the iterative solvers that iterate on A in its own row order, with D⁻¹ at hand
/// (cg, chebyshev; gauss_seidel reorders the rows and keeps its own copy). Factorize() keeps a
/// compressed copy of A and its inverse diagonal (a NumericalError naming Derived::kName if an
/// entry of the diagonal is not positive) and then calls Derived::Prepare(context) for the
/// solver's own setup. A block's columns [first, first + K) of b and x are copied into row-major
/// work blocks for Derived::SolveGathered<K>(b, x, first) (x updated in place) and x's columns
/// copied back. Derived befriends this class.
template <class Derived>
class MatrixIterativeSolver : public BlockIterativeSolver<Derived> {
 public:
  /// The matrix of the last Factorize() (a compressed copy).
  const SparseMatrix& matrix() const { return a_; }

 protected:
  using BlockIterativeSolver<Derived>::BlockIterativeSolver;

  SparseMatrix a_;
  Eigen::VectorXd inverse_diagonal_;  ///< D⁻¹ of a_

 private:
  friend class BlockIterativeSolver<Derived>;

  void FactorizeImpl(const SparseMatrix& a, const Context& context) final {
    a_ = CompressedCopy(a);
    inverse_diagonal_ = solver_checks::PositiveDiagonal(a_, Derived::kName).cwiseInverse();
    static_cast<Derived&>(*this).Prepare(context);
  }

  template <int K>
  SolveSummary SolveBlock(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
                          Eigen::Index first) {
    const Index rows = static_cast<Index>(a_.rows());
    double* b_block = b_block_.Reserve(rows, K);
    double* x_block = x_block_.Reserve(rows, K);
    GatherColumns<K>(b, first, b_block);
    GatherColumns<K>(x, first, x_block);
    const SolveSummary summary =
        static_cast<Derived&>(*this).template SolveGathered<K>(b_block, x_block, first);
    ScatterColumns<K>(x_block, first, x);
    return summary;
  }

  Block b_block_, x_block_;
};

/// The outcome of a block that did not fail: kConverged if no column of `convergence` is still
/// active, else kIterationLimit.
inline SolveOutcome BlockOutcome(const ColumnConvergence& convergence) {
  return convergence.any_active() ? SolveOutcome::kIterationLimit : SolveOutcome::kConverged;
}

}  // namespace harap::iterative
