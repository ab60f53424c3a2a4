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

/// Groups of `group_rows` rows that `rows` rows make (the last may be shorter).
Index GroupCount(Index rows, Index group_rows) {
  return rows == 0 ? 0 : 1 + (rows - 1) / group_rows;
}

/// Greedy colouring of the groups of `group_rows` consecutive rows (the last group may be
/// shorter), in order: each group takes the smallest colour that no group coupled to it (by a
/// non-zero between their rows) has. Groups of one row colour the matrix graph: at most
/// (max degree + 1) colours, 7 on the armadillo and the buddha, 6 on the cow.
std::vector<int> GreedyColoring(const SparseMatrix& a, Index group_rows, int& num_colors) {
  const Index n = static_cast<Index>(a.rows());
  const Index groups = GroupCount(n, group_rows);
  std::vector<int> color(groups, -1);
  std::vector<Index> taken_by;  // taken_by[c] == g: colour c is used by a neighbour of group g
  num_colors = 0;
  for (Index g = 0; g < groups; ++g) {
    const Index end = std::min(n, (g + 1) * group_rows);
    for (Index i = g * group_rows; i < end; ++i) {
      for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
        const Index neighbour = static_cast<Index>(it.row()) / group_rows;
        const int c = neighbour != g ? color[neighbour] : -1;
        if (c >= 0) taken_by[c] = g;
      }
    }
    int c = 0;
    while (c < num_colors && taken_by[c] == g) ++c;
    if (c == num_colors) {
      ++num_colors;
      taken_by.push_back(-1);
    }
    color[g] = c;
  }
  return color;
}

constexpr EnumNames<GaussSeidelSolver::Sweep, 2> kSweepNames = {{
    {GaussSeidelSolver::Sweep::kForward, "forward"},
    {GaussSeidelSolver::Sweep::kSymmetric, "symmetric"},
}};
constexpr EnumNames<GaussSeidelSolver::Ordering, 3> kOrderingNames = {{
    {GaussSeidelSolver::Ordering::kColored, "colored"},
    {GaussSeidelSolver::Ordering::kNatural, "natural"},
    {GaussSeidelSolver::Ordering::kBlocks, "blocks"},
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
                     "parallel; natural = rows in order, sequential; blocks = blocks of "
                     "block_rows consecutive rows swept in order, the blocks coloured so that "
                     "blocks of one colour run in parallel");
    options.block_rows =
        node.Get("block_rows", options.block_rows, "rows per block of the blocks ordering",
                 Range::Closed(1, 1 << 24));
    options.relaxation = node.Get("relaxation", options.relaxation,
                                  "over-relaxation factor ω: 1 = Gauss–Seidel, > 1 = SOR (which "
                                  "diverges outside (0, 2))",
                                  Range::Open(0.0, 2.0));
  });
}

void GaussSeidelSolver::FactorizeImpl(const SparseMatrix& a_in, const Context& context) {
  const SparseMatrix a = iterative::CompressedCopy(a_in);
  const Eigen::VectorXd diagonal = solver_checks::PositiveDiagonal(a, "gauss_seidel");

  // Sweep order: by colour, and by row within a colour (keeps the rows' memory locality). Each
  // ordering is a colouring of groups of consecutive rows: single rows (colored), blocks of
  // block_rows (blocks), or one group of all rows (natural).
  HARAP_CHECK(options_.block_rows >= 1, "gauss_seidel: block_rows is {}, it must be at least 1",
              options_.block_rows);
  block_rows_ = 1;
  if (options_.ordering == Ordering::kBlocks) block_rows_ = options_.block_rows;
  if (options_.ordering == Ordering::kNatural) block_rows_ = std::max<Index>(rows(), 1);
  order_.resize(rows());
  color_begin_.assign(1, 0);
  if (rows() > 0) {
    int num_colors = 0;
    const std::vector<int> color = GreedyColoring(a, block_rows_, num_colors);
    color_begin_.assign(num_colors + 1, 0);
    for (Index i = 0; i < rows(); ++i) ++color_begin_[color[i / block_rows_] + 1];
    for (int c = 0; c < num_colors; ++c) color_begin_[c + 1] += color_begin_[c];
    std::vector<Index> next(color_begin_.begin(), color_begin_.end() - 1);
    for (Index i = 0; i < rows(); ++i) order_[next[color[i / block_rows_]]++] = i;
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
void GaussSeidelSolver::UpdateRow(Index k, const double* b, double* x,
                                  const std::array<bool, 3>& active) const {
  double sum[K];
  for (int c = 0; c < K; ++c) sum[c] = b[k * K + c];
  for (Index p = offsets_[k]; p < offsets_[k + 1]; ++p) {
    const double* xj = x + columns_[p] * K;
    for (int c = 0; c < K; ++c) sum[c] -= values_[p] * xj[c];
  }
  const double omega = options_.relaxation;
  for (int c = 0; c < K; ++c) {
    if (!active[c]) continue;
    const double gauss_seidel = sum[c] * inverse_diagonal_[k];
    x[k * K + c] =
        omega == 1.0 ? gauss_seidel : x[k * K + c] + omega * (gauss_seidel - x[k * K + c]);
  }
}

template <int K>
void GaussSeidelSolver::RunSweep(const double* b, double* x, const std::array<bool, 3>& active,
                                 bool backward) const {
  // The groups of one colour are not coupled: any order of the groups within a colour (and so
  // any thread split) is the same Gauss–Seidel step. A range of a colour's groups is contiguous,
  // so running it backward reverses the rows within each group, as a backward sweep must.
  const Index group_grain = std::max<Index>(1, kRowGrain / block_rows_);
  auto run_color = [&](int c) {
    const Index begin = color_begin_[c], end = color_begin_[c + 1];
    auto run_groups = [&](Index first_group, Index last_group) {
      const Index first = begin + first_group * block_rows_;
      const Index last = std::min(end, begin + last_group * block_rows_);
      if (!backward) {
        for (Index k = first; k < last; ++k) UpdateRow<K>(k, b, x, active);
      } else {
        for (Index k = last - 1; k >= first; --k) UpdateRow<K>(k, b, x, active);
      }
    };
    const Index groups = GroupCount(end - begin, block_rows_);
    if (groups <= group_grain) {
      run_groups(0, groups);
      return;
    }
    tbb::parallel_for(
        tbb::blocked_range<Index>(0, groups, group_grain),
        [&](const tbb::blocked_range<Index>& range) { run_groups(range.begin(), range.end()); });
  };
  const int colors = num_colors();
  if (!backward) {
    for (int c = 0; c < colors; ++c) run_color(c);
  } else {
    // With ω = 1 and single rows, re-running the colour just swept changes nothing (its
    // neighbours are unchanged): start the backward sweep one colour down.
    const int last = options_.relaxation == 1.0 && block_rows_ == 1 ? colors - 2 : colors - 1;
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
