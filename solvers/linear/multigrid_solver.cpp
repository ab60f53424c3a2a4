// SPDX-License-Identifier: MIT
#include "solvers/linear/multigrid_solver.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>

#include "framework/error.h"
#include "solvers/linear/chebyshev_solver.h"
#include "solvers/linear/eigen_ldlt_solver.h"
#include "solvers/linear/gauss_seidel_solver.h"
#include "solvers/linear/multigrid_transfer.h"
#include "solvers/linear/solver_checks.h"
#ifdef HARAP_HAVE_CHOLMOD
#include "solvers/linear/cholmod_solver.h"
#endif

namespace harap {

namespace {

using iterative::ColumnValues;
using iterative::ForRows;

constexpr EnumNames<MultigridSolver::Smoother, 2> kSmootherNames = {{
    {MultigridSolver::Smoother::kGaussSeidel, "gauss_seidel"},
    {MultigridSolver::Smoother::kChebyshev, "chebyshev"},
}};

constexpr EnumNames<MultigridSolver::Prolongation, 2> kProlongationNames = {{
    {MultigridSolver::Prolongation::kConstant, "constant"},
    {MultigridSolver::Prolongation::kSmoothed, "smoothed"},
}};

/// For each column j of the compressed column matrix `m` (in parallel): the sums
/// Σ_p m_pj x(p, c) over the first `columns` columns of x, handed to store(j, sums).
template <class X, class Store>
void ColumnSums(const SparseMatrix& m, const X& x, int columns, Store&& store) {
  const Index* outer = m.outerIndexPtr();
  const Index* inner = m.innerIndexPtr();
  const double* value = m.valuePtr();
  ForRows(static_cast<Index>(m.cols()), [&](Index j) {
    std::array<double, iterative::kMaxBlockColumns> sum{};
    for (Index p = outer[j]; p < outer[j + 1]; ++p) {
      for (int c = 0; c < columns; ++c) sum[c] += value[p] * x(inner[p], c);
    }
    store(j, sum);
  });
}

/// y = Mᵀ x (accumulate: y += Mᵀ x) for the first `columns` columns, one row of the result per
/// column of `m`. With M = A (symmetric) it is A x; with M = Pᵀ stored it is P x, and with M = P
/// it is Pᵀ x.
template <bool kAccumulate>
void TransposeProduct(const SparseMatrix& m, const Eigen::MatrixXd& x, Eigen::MatrixXd& y,
                      int columns) {
  ColumnSums(m, x, columns, [&](Index j, const auto& sum) {
    for (int c = 0; c < columns; ++c) {
      if constexpr (kAccumulate) {
        y(j, c) += sum[c];
      } else {
        y(j, c) = sum[c];
      }
    }
  });
}

/// r = b − A x for the first `columns` columns (A symmetric).
void Residual(const SparseMatrix& a, const Eigen::Ref<const Eigen::MatrixXd>& b,
              const Eigen::Ref<const Eigen::MatrixXd>& x, Eigen::MatrixXd& r, int columns) {
  ColumnSums(a, x, columns, [&](Index i, const auto& sum) {
    for (int c = 0; c < columns; ++c) r(i, c) = b(i, c) - sum[c];
  });
}

ColumnValues ColumnDots(const Eigen::MatrixXd& u, const Eigen::MatrixXd& v, int columns) {
  ColumnValues dots{};
  for (int c = 0; c < columns; ++c) dots[c] = u.col(c).dot(v.col(c));
  return dots;
}

std::string NotPositiveDefinite(std::string_view what, double value, int iteration, Index column) {
  return fmt::format(
      "multigrid: {} = {:.3g} at iteration {} (column {}): the matrix is not positive definite. "
      "{}",
      what, value, iteration, column, solver_checks::kNotPositiveDefiniteAdvice);
}

}  // namespace

/// One level of the V-cycle: its matrix, the transfer operators to the next coarser level, its
/// smoother (on the coarsest level: the factorization) and its work blocks.
struct MultigridSolver::Level {
  SparseMatrix a;
  SparseMatrix p;   ///< Prolongation from the next coarser level (rows × coarse rows).
  SparseMatrix pt;  ///< Pᵀ, stored for the parallel product P e row by row.
  std::unique_ptr<LinearSolver> solver;
  Eigen::MatrixXd b, x, r;  ///< rows × 3
};

MultigridSolver::Options MultigridSolver::Options::FromConfig(OptionReader node) {
  return iterative::ReadIterativeOptions<Options>(
      node, "V-cycle-preconditioned CG iteration", [&](Options& options) {
        options.smoother = node.GetEnum(
            "smoother", options.smoother, kSmootherNames,
            "gauss_seidel = symmetric Gauss–Seidel sweeps (colored, parallel); chebyshev = "
            "Chebyshev–Jacobi polynomial of degree smoothing_steps + 1 over the top of the "
            "spectrum");
        options.smoothing_steps = node.Get(
            "smoothing_steps", options.smoothing_steps,
            "smoothing sweeps before and after each coarse correction", Range::Closed(1, 10));
        options.smoother_block_rows =
            node.Get("smoother_block_rows", options.smoother_block_rows,
                     "rows per block of the gauss_seidel smoother's blocks ordering (1: its "
                     "colored ordering)",
                     Range::Closed(1, 1 << 24));
        options.prolongation = node.GetEnum(
            "prolongation", options.prolongation, kProlongationNames,
            "constant = an aggregate's value copied to its unknowns; smoothed = that, smoothed by "
            "one damped Jacobi step (smoothed aggregation: far fewer iterations, growing slowly "
            "with the mesh)");
        options.strength_threshold =
            node.Get("strength_threshold", options.strength_threshold,
                     "θ: aggregates follow the couplings with |a_ij| ≥ θ √(a_ii a_jj)",
                     Range::HalfOpen(0.0, 1.0));
        options.coarsest_unknowns =
            node.Get("coarsest_unknowns", options.coarsest_unknowns,
                     "coarsen until at most this many unknowns remain, then factor (Cholesky)",
                     Range::AtLeast(1));
        options.max_levels =
            node.Get("max_levels", options.max_levels,
                     "most levels, the finest included (1: factor A itself)", Range::Closed(1, 40));
      });
}

MultigridSolver::MultigridSolver(const Options& options) : LinearSolver(kName), options_(options) {}

MultigridSolver::~MultigridSolver() = default;

std::vector<Index> MultigridSolver::level_unknowns() const {
  std::vector<Index> unknowns;
  for (const auto& level : levels_) unknowns.push_back(static_cast<Index>(level->a.rows()));
  return unknowns;
}

double MultigridSolver::operator_complexity() const {
  if (levels_.empty() || levels_.front()->a.nonZeros() == 0) return 0.0;
  double total = 0.0;
  for (const auto& level : levels_) total += static_cast<double>(level->a.nonZeros());
  return total / static_cast<double>(levels_.front()->a.nonZeros());
}

void MultigridSolver::FactorizeImpl(const SparseMatrix& a, const Context& context) {
  levels_.clear();
  auto finest = std::make_unique<Level>();
  finest->a = iterative::CompressedCopy(a);
  solver_checks::PositiveDiagonal(finest->a, kName);
  levels_.push_back(std::move(finest));
  context.Run([&] {
    // Coarsen until the system is small enough to factor, or aggregation stops paying (an
    // aggregate of mostly singletons: weakly coupled unknowns).
    while (static_cast<int>(levels_.size()) < options_.max_levels &&
           levels_.back()->a.rows() > options_.coarsest_unknowns) {
      Level& fine = *levels_.back();
      Index count = 0;
      const std::vector<Index> aggregate =
          multigrid::AggregateByStrength(fine.a, options_.strength_threshold, count);
      if (count == 0 || static_cast<double>(count) > 0.8 * static_cast<double>(fine.a.rows())) {
        break;
      }
      SparseMatrix p = multigrid::ConstantProlongation(aggregate, count);
      if (options_.prolongation == Prolongation::kSmoothed) {
        p = multigrid::SmoothedProlongation(fine.a, p);
      }
      auto coarse = std::make_unique<Level>();
      coarse->a = multigrid::GalerkinProduct(fine.a, p);
      fine.pt = p.transpose();
      fine.pt.makeCompressed();
      fine.p = std::move(p);
      levels_.push_back(std::move(coarse));
    }
  });
  for (size_t l = 0; l < levels_.size(); ++l) {
    Level& level = *levels_[l];
    const Eigen::Index rows = level.a.rows();
    level.b.setZero(rows, iterative::kMaxBlockColumns);
    level.x.setZero(rows, iterative::kMaxBlockColumns);
    level.r.setZero(rows, iterative::kMaxBlockColumns);
    if (l + 1 == levels_.size()) {
#ifdef HARAP_HAVE_CHOLMOD
      level.solver = std::make_unique<CholmodSolver>(CholmodSolver::Options{});
#else
      level.solver = std::make_unique<EigenLdltSolver>(EigenLdltSolver::Options{});
#endif
    } else if (options_.smoother == Smoother::kGaussSeidel) {
      GaussSeidelSolver::Options smoother;
      smoother.limits = {options_.smoothing_steps, 0.0};
      smoother.sweep = GaussSeidelSolver::Sweep::kSymmetric;
      smoother.ordering = GaussSeidelSolver::Ordering::kBlocks;
      smoother.block_rows = options_.smoother_block_rows;
      smoother.check_without_tolerance = false;
      level.solver = std::make_unique<GaussSeidelSolver>(smoother);
    } else {
      ChebyshevSolver::Options smoother;
      smoother.limits = {options_.smoothing_steps + 1, 0.0};
      smoother.lower_bound = ChebyshevSolver::LowerBound::kBudget;
      level.solver = std::make_unique<ChebyshevSolver>(smoother);
    }
    try {
      level.solver->Factorize(level.a, context);
    } catch (const NumericalError& error) {
      throw NumericalError(fmt::format("multigrid: level {} of {} ({} unknowns): {}", l,
                                       levels_.size(), rows, error.what()));
    }
  }
  const Eigen::Index n = a.rows();
  r_.setZero(n, iterative::kMaxBlockColumns);
  z_.setZero(n, iterative::kMaxBlockColumns);
  p_.setZero(n, iterative::kMaxBlockColumns);
  q_.setZero(n, iterative::kMaxBlockColumns);
}

void MultigridSolver::VCycle(size_t l, int columns, const Context& context) {
  Level& level = *levels_[l];
  auto b = level.b.leftCols(columns);
  auto x = level.x.leftCols(columns);
  x.setZero();
  const SolveSummary pre = level.solver->Solve(b, x, context);
  if (l + 1 == levels_.size()) return;
  if (!pre.success()) {
    x.setConstant(std::numeric_limits<double>::quiet_NaN());
    return;
  }
  Residual(level.a, level.b, level.x, level.r, columns);
  Level& coarse = *levels_[l + 1];
  TransposeProduct<false>(level.p, level.r, coarse.b, columns);
  VCycle(l + 1, columns, context);
  TransposeProduct<true>(level.pt, coarse.x, level.x, columns);
  level.solver->Solve(b, x, context);
}

SolveSummary MultigridSolver::SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b,
                                        Eigen::Ref<Eigen::MatrixXd> x, const Context& context) {
  return iterative::SolveByBlocks(b, [&](Eigen::Index first, auto width) {
    return SolveColumns(b, x, first, decltype(width)::value, context);
  });
}

SolveSummary MultigridSolver::SolveColumns(const Eigen::Ref<const Eigen::MatrixXd>& b_all,
                                           Eigen::Ref<Eigen::MatrixXd> x_all, Eigen::Index first,
                                           int k, const Context& context) {
  const SparseMatrix& a = levels_.front()->a;
  const auto b = b_all.middleCols(first, k);
  auto x = x_all.middleCols(first, k);
  Level& finest = *levels_.front();

  ColumnValues squared_b{};
  for (int c = 0; c < k; ++c) squared_b[c] = b.col(c).squaredNorm();
  Residual(a, b, x, r_, k);
  iterative::ColumnConvergence convergence(k, squared_b, ColumnDots(r_, r_, k),
                                           options_.limits.tolerance);
  SolveSummary summary;
  // z = M⁻¹ r: one V-cycle from zero.
  auto precondition = [&] {
    finest.b.leftCols(k) = r_.leftCols(k);
    VCycle(0, k, context);
    z_.leftCols(k) = finest.x.leftCols(k);
  };
  ColumnValues rz{};
  if (convergence.any_active() && options_.limits.max_iterations > 0) {
    precondition();
    p_.leftCols(k) = z_.leftCols(k);
    rz = ColumnDots(r_, z_, k);
  }
  while (convergence.any_active() && summary.iterations < options_.limits.max_iterations) {
    for (int c = 0; c < k; ++c) {
      if (convergence.active(c) && !(rz[c] > 0.0)) {
        summary.outcome = SolveOutcome::kFailed;
        summary.message = NotPositiveDefinite("rᵀM⁻¹r", rz[c], summary.iterations + 1, first + c);
        break;
      }
    }
    if (!summary.success()) break;
    TransposeProduct<false>(a, p_, q_, k);
    const ColumnValues pq = ColumnDots(p_, q_, k);
    ColumnValues alpha{};
    for (int c = 0; c < k; ++c) {
      if (!convergence.active(c)) continue;
      if (!(pq[c] > 0.0)) {
        summary.outcome = SolveOutcome::kFailed;
        summary.message = NotPositiveDefinite("pᵀAp", pq[c], summary.iterations + 1, first + c);
        break;
      }
      alpha[c] = rz[c] / pq[c];
    }
    if (!summary.success()) break;
    for (int c = 0; c < k; ++c) {
      if (!convergence.active(c)) continue;
      x.col(c) += alpha[c] * p_.col(c);
      r_.col(c) -= alpha[c] * q_.col(c);
    }
    ++summary.iterations;
    if (!iterative::RecordCgResiduals(convergence, ColumnDots(r_, r_, k), "multigrid", summary)) {
      break;
    }
    if (!convergence.any_active()) break;
    precondition();
    const ColumnValues rz_next = ColumnDots(r_, z_, k);
    for (int c = 0; c < k; ++c) {
      if (!convergence.active(c)) continue;
      const double beta = rz_next[c] / rz[c];
      rz[c] = rz_next[c];
      p_.col(c) = z_.col(c) + beta * p_.col(c);
    }
  }
  if (summary.success()) summary.outcome = iterative::BlockOutcome(convergence);
  // The recurrence residual drifts from b − A x: report the true one.
  Residual(a, b, x, r_, k);
  const ColumnValues squared_r = ColumnDots(r_, r_, k);
  for (int c = 0; c < k; ++c) {
    const double scale = squared_b[c] > 0.0 ? squared_b[c] : 1.0;
    summary.relative_residual =
        std::max(summary.relative_residual, std::sqrt(squared_r[c] / scale));
  }
  return summary;
}

}  // namespace harap
