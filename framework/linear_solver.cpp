// SPDX-License-Identifier: MIT
#include "framework/linear_solver.h"

#include <fmt/format.h>

#include "framework/error.h"

namespace harap {

void LinearSolver::Factorize(const SparseMatrix& a, const Context& context) {
  const Stopwatch clock;
  HARAP_CHECK(a.rows() == a.cols(), "{}: the matrix is {}×{}, not square", name_, a.rows(),
              a.cols());
  factorized_ = false;  // until FactorizeImpl() returns: a throw leaves the solver unusable
  statistics_ = SolveStatistics{};
  rows_ = static_cast<Index>(a.rows());
  FactorizeImpl(a, context);
  factorized_ = true;
  factorize_seconds_ = clock.Seconds();
}

LinearSolver::RefactorSummary LinearSolver::Refactor(const SparseMatrix& a,
                                                     const std::vector<Index>& changed_rows,
                                                     const Context& context) {
  const Stopwatch clock;
  HARAP_CHECK(a.rows() == a.cols(), "{}: the matrix is {}×{}, not square", name_, a.rows(),
              a.cols());
  // Not reset first: a RefactorImpl() that rejects its arguments keeps the factor usable, and
  // one that fails midway tracks its own state (the default below factors from scratch).
  RefactorSummary summary = RefactorImpl(a, changed_rows, context);
  factorized_ = true;
  statistics_ = SolveStatistics{};
  rows_ = static_cast<Index>(a.rows());
  factorize_seconds_ = summary.seconds = clock.Seconds();
  return summary;
}

LinearSolver::RefactorSummary LinearSolver::RefactorImpl(const SparseMatrix& a,
                                                         const std::vector<Index>& changed_rows,
                                                         const Context& context) {
  factorized_ = false;  // until FactorizeImpl() returns
  rows_ = static_cast<Index>(a.rows());
  FactorizeImpl(a, context);
  return {RefactorRoute::kFull, static_cast<Index>(changed_rows.size()), 0.0};
}

SolveSummary LinearSolver::Solve(const Eigen::Ref<const Eigen::MatrixXd>& b,
                                 Eigen::Ref<Eigen::MatrixXd> x, const Context& context) {
  const Stopwatch clock;
  HARAP_CHECK(factorized_, "{}: Solve() needs a successful Factorize() first", name_);
  HARAP_CHECK(b.rows() == rows_ && x.rows() == rows_ && x.cols() == b.cols(),
              "{}: b is {}×{} and x is {}×{}, the matrix has {} rows", name_, b.rows(), b.cols(),
              x.rows(), x.cols(), rows_);
  SolveSummary summary;
  if (rows_ > 0 && b.cols() > 0) {
    summary = SolveImpl(b, x, context);
    // A singular matrix (or a bad b) shows as NaN or infinite entries; never hand them on as
    // a usable answer.
    if (summary.success() && !x.allFinite()) {
      summary.outcome = SolveOutcome::kFailed;
      summary.relative_residual = 0.0;
      summary.message =
          b.allFinite() ? fmt::format(
                              "{}: the solution has NaN or infinite entries (the matrix is "
                              "numerically singular)",
                              name_)
                        : fmt::format("{}: the right-hand side has NaN or infinite entries", name_);
    }
  }
  summary.seconds = clock.Seconds();
  statistics_.Add(summary);
  return summary;
}

}  // namespace harap
