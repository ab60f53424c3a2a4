// SPDX-License-Identifier: MIT
#include "solvers/linear/gauss_seidel_solver.h"

#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "framework/error.h"
#include "solvers/linear/solver_checks.h"

namespace harap {

namespace {

using iterative::ColumnValues;
using iterative::ForRows;
using iterative::kRowGrain;
using iterative::SumRows;

/// Greedy colouring in row order: each row takes the smallest colour none of its neighbours
/// has. Uses at most (max degree + 1) colours: 7 on the armadillo and the buddha, 6 on the cow.
std::vector<int> GreedyColoring(const SparseMatrix& a, int& num_colors) {
  const Index n = static_cast<Index>(a.rows());
  std::vector<int> color(n, -1);
  std::vector<Index> taken_by;  // taken_by[c] == i: colour c is used by a neighbour of row i
  num_colors = 0;
  for (Index i = 0; i < n; ++i) {
    for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
      const int c = color[it.row()];
      if (c >= 0) taken_by[c] = i;
    }
    int c = 0;
    while (c < num_colors && taken_by[c] == i) ++c;
    if (c == num_colors) {
      ++num_colors;
      taken_by.push_back(-1);
    }
    color[i] = c;
  }
  return color;
}

constexpr EnumNames<GaussSeidelSolver::Sweep, 2> kSweepNames = {{
    {GaussSeidelSolver::Sweep::kForward, "forward"},
    {GaussSeidelSolver::Sweep::kSymmetric, "symmetric"},
}};
constexpr EnumNames<GaussSeidelSolver::Ordering, 2> kOrderingNames = {{
    {GaussSeidelSolver::Ordering::kColored, "colored"},
    {GaussSeidelSolver::Ordering::kNatural, "natural"},
}};

}  // namespace

GaussSeidelSolver::Options GaussSeidelSolver::Options::FromConfig(OptionReader node) {
  return iterative::ReadIterativeOptions<Options>(node, "sweep", [&](Options& options) {
    options.sweep = node.GetEnum("sweep", options.sweep, kSweepNames,
                                 "forward = rows in order; symmetric = forward then backward "
                                 "(SGS/SSOR, one iteration costs about two forward sweeps)");
    options.ordering =
        node.GetEnum("ordering", options.ordering, kOrderingNames,
                     "colored = rows grouped by a greedy graph colouring, each colour updated in "
                     "parallel; natural = rows in order, sequential");
    options.relaxation = node.Get("relaxation", options.relaxation,
                                  "over-relaxation factor ω: 1 = Gauss–Seidel, > 1 = SOR (which "
                                  "diverges outside (0, 2))",
                                  Range::Open(0.0, 2.0));
  });
}

void GaussSeidelSolver::FactorizeImpl(const SparseMatrix& a_in, const Context& context) {
  const SparseMatrix a = iterative::CompressedCopy(a_in);
  const Eigen::VectorXd diagonal = solver_checks::PositiveDiagonal(a, "gauss_seidel");

  // Sweep order: by colour, and by row within a colour (keeps the rows' memory locality).
  order_.resize(rows());
  color_begin_.assign(1, 0);
  if (options_.ordering == Ordering::kColored && rows() > 0) {
    int num_colors = 0;
    const std::vector<int> color = GreedyColoring(a, num_colors);
    color_begin_.assign(num_colors + 1, 0);
    for (Index i = 0; i < rows(); ++i) ++color_begin_[color[i] + 1];
    for (int c = 0; c < num_colors; ++c) color_begin_[c + 1] += color_begin_[c];
    std::vector<Index> next(color_begin_.begin(), color_begin_.end() - 1);
    for (Index i = 0; i < rows(); ++i) order_[next[color[i]]++] = i;
  } else {
    for (Index i = 0; i < rows(); ++i) order_[i] = i;
    color_begin_.push_back(rows());
  }
  std::vector<Index> position(rows());
  for (Index k = 0; k < rows(); ++k) position[order_[k]] = k;

  // Off-diagonal rows in sweep order (row i of A is column i: A is symmetric).
  offsets_.assign(rows() + 1, 0);
  for (Index k = 0; k < rows(); ++k) {
    const Index i = order_[k];
    Index count = 0;
    for (SparseMatrix::InnerIterator it(a, i); it; ++it) count += it.row() != i ? 1 : 0;
    offsets_[k + 1] = offsets_[k] + count;
  }
  columns_.resize(offsets_[rows()]);
  values_.resize(offsets_[rows()]);
  diagonal_.resize(rows());
  inverse_diagonal_.resize(rows());
  context.Run([&] {
    ForRows(rows(), [&](Index k) {
      const Index i = order_[k];
      Index p = offsets_[k];
      for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
        if (it.row() == i) continue;
        columns_[p] = position[it.row()];
        values_[p] = it.value();
        ++p;
      }
      diagonal_[k] = diagonal[i];
      inverse_diagonal_[k] = 1.0 / diagonal[i];
    });
  });
}

template <int K>
void GaussSeidelSolver::UpdateRows(Index begin, Index end, const double* b, double* x,
                                   const std::array<bool, 3>& active) const {
  const double omega = options_.relaxation;
  for (Index k = begin; k < end; ++k) {
    double sum[K];
    for (int c = 0; c < K; ++c) sum[c] = b[k * K + c];
    for (Index p = offsets_[k]; p < offsets_[k + 1]; ++p) {
      const double* xj = x + columns_[p] * K;
      for (int c = 0; c < K; ++c) sum[c] -= values_[p] * xj[c];
    }
    for (int c = 0; c < K; ++c) {
      if (!active[c]) continue;
      const double gauss_seidel = sum[c] * inverse_diagonal_[k];
      x[k * K + c] =
          omega == 1.0 ? gauss_seidel : x[k * K + c] + omega * (gauss_seidel - x[k * K + c]);
    }
  }
}

template <int K>
void GaussSeidelSolver::RunSweep(const double* b, double* x, const std::array<bool, 3>& active,
                                 bool backward) const {
  if (options_.ordering == Ordering::kNatural) {
    if (!backward) {
      UpdateRows<K>(0, rows(), b, x, active);
    } else {
      for (Index k = rows() - 1; k >= 0; --k) UpdateRows<K>(k, k + 1, b, x, active);
    }
    return;
  }
  // Rows of one colour are not coupled: any order within a colour (and so any thread split) is
  // the same Gauss–Seidel step.
  const int colors = num_colors();
  auto run_color = [&](int c) {
    if (color_begin_[c + 1] - color_begin_[c] <= kRowGrain) {
      UpdateRows<K>(color_begin_[c], color_begin_[c + 1], b, x, active);
      return;
    }
    tbb::parallel_for(tbb::blocked_range<Index>(color_begin_[c], color_begin_[c + 1], kRowGrain),
                      [&](const tbb::blocked_range<Index>& range) {
                        UpdateRows<K>(range.begin(), range.end(), b, x, active);
                      });
  };
  if (!backward) {
    for (int c = 0; c < colors; ++c) run_color(c);
  } else {
    // With ω = 1 re-running the colour just swept changes nothing (its neighbours are
    // unchanged): start the backward sweep one colour down.
    const int last = options_.relaxation == 1.0 ? colors - 2 : colors - 1;
    for (int c = last; c >= 0; --c) run_color(c);
  }
}

template <int K>
ColumnValues GaussSeidelSolver::SquaredResidual(const double* b, const double* x) const {
  return SumRows<1>(rows(), [&](Index k, auto& sums) {
    double r[K];
    for (int c = 0; c < K; ++c) r[c] = b[k * K + c] - diagonal_[k] * x[k * K + c];
    for (Index p = offsets_[k]; p < offsets_[k + 1]; ++p) {
      const double* xj = x + columns_[p] * K;
      for (int c = 0; c < K; ++c) r[c] -= values_[p] * xj[c];
    }
    for (int c = 0; c < K; ++c) sums[0][c] += r[c] * r[c];
  })[0];
}

template <int K>
SolveSummary GaussSeidelSolver::SolveBlock(const Eigen::Ref<const Eigen::MatrixXd>& b_in,
                                           Eigen::Ref<Eigen::MatrixXd> x_out, Eigen::Index first) {
  double* b = b_.Reserve(rows(), K);
  double* x = x_.Reserve(rows(), K);
  const ColumnValues squared_b = SumRows<1>(rows(), [&](Index k, auto& sums) {
    for (int c = 0; c < K; ++c) {
      b[k * K + c] = b_in(order_[k], first + c);
      x[k * K + c] = x_out(order_[k], first + c);
      sums[0][c] += b[k * K + c] * b[k * K + c];
    }
  })[0];

  const double tolerance = options_.limits.tolerance;
  // Without a tolerance the warm start's residual is not needed (it would cost a pass): the
  // divergence test then only catches non-finite values.
  ColumnValues start;
  start.fill(std::numeric_limits<double>::infinity());
  if (tolerance > 0.0) start = SquaredResidual<K>(b, x);
  iterative::ColumnConvergence convergence(K, squared_b, start, tolerance);
  std::array<bool, 3> active{};

  SolveSummary summary;
  bool diverged = false;
  while (summary.iterations < options_.limits.max_iterations) {
    if (tolerance > 0.0 && !convergence.any_active()) break;
    for (int c = 0; c < K; ++c) active[c] = convergence.active(c);
    RunSweep<K>(b, x, active, /*backward=*/false);
    if (options_.sweep == Sweep::kSymmetric) RunSweep<K>(b, x, active, /*backward=*/true);
    ++summary.iterations;
    if (tolerance > 0.0 && !convergence.Update(SquaredResidual<K>(b, x))) {
      diverged = true;
      break;
    }
  }
  if (!diverged && tolerance == 0.0 && options_.check_without_tolerance) {
    diverged = !convergence.Update(SquaredResidual<K>(b, x));
  }
  summary.outcome = diverged ? SolveOutcome::kFailed : iterative::BlockOutcome(convergence);
  if (diverged) {
    summary.message = iterative::DivergenceMessage(
        "gauss_seidel", summary.iterations,
        fmt::format("the matrix is not positive definite (Gauss–Seidel converges for every SPD "
                    "matrix) or the right-hand side is not finite. {}",
                    solver_checks::kNotPositiveDefiniteAdvice));
  }
  const bool measured = tolerance > 0.0 || options_.check_without_tolerance;
  summary.relative_residual = measured ? convergence.max_relative_residual() : 0.0;
  ForRows(rows(), [&](Index k) {
    for (int c = 0; c < K; ++c) x_out(order_[k], first + c) = x[k * K + c];
  });
  return summary;
}

template class iterative::BlockIterativeSolver<GaussSeidelSolver>;

}  // namespace harap
