// SPDX-License-Identifier: MIT
#include "solvers/linear/iterative_kernels.h"

#include <fmt/format.h>

#include "framework/error.h"

namespace harap::iterative {

ColumnConvergence::ColumnConvergence(int columns, const ColumnValues& squared_b,
                                     const ColumnValues& squared_residual, double tolerance)
    : columns_(columns), tolerance_(tolerance), start_(squared_residual) {
  for (int c = 0; c < columns_; ++c) {
    scale_[c] = squared_b[c] > 0.0 ? squared_b[c] : 1.0;
    active_[c] = true;
  }
  Update(squared_residual);
}

bool ColumnConvergence::Update(const ColumnValues& squared_residual) {
  bool finite = true;
  for (int c = 0; c < columns_; ++c) {
    if (!active_[c]) continue;
    const double rr = squared_residual[c];
    squared_residual_[c] = rr;
    if (!std::isfinite(rr) || rr > kDivergenceFactor * kDivergenceFactor * start_[c]) {
      finite = false;
      continue;
    }
    if (rr <= tolerance_ * tolerance_ * scale_[c]) active_[c] = false;
  }
  return finite;
}

bool ColumnConvergence::any_active() const {
  for (int c = 0; c < columns_; ++c) {
    if (active_[c]) return true;
  }
  return false;
}

double ColumnConvergence::max_relative_residual() const {
  double worst = 0.0;
  for (int c = 0; c < columns_; ++c) {
    worst = std::max(worst, std::sqrt(squared_residual_[c] / scale_[c]));
  }
  return worst;
}

void ReadIterationLimits(OptionReader node, std::string_view iteration, IterationLimits& limits) {
  limits.max_iterations =
      node.Get("max_iterations", limits.max_iterations,
               fmt::format("{}s per solve (per global step); a cap when tolerance > 0", iteration),
               Range::AtLeast(1));
  limits.tolerance = node.Get("tolerance", limits.tolerance,
                              "stop when ‖b − A x‖ / ‖b‖ ≤ tolerance (per column); 0: always run "
                              "max_iterations",
                              Range::HalfOpen(0.0, 1.0));
}

std::string DivergenceMessage(std::string_view solver, int iteration, std::string_view cause) {
  return fmt::format(
      "{}: the iteration diverged at iteration {} (the residual became non-finite or grew by "
      "more than {:.0e}): {}",
      solver, iteration, ColumnConvergence::kDivergenceFactor, cause);
}

bool RecordCgResiduals(ColumnConvergence& convergence, const ColumnValues& squared_residual,
                       std::string_view solver, SolveSummary& summary) {
  if (convergence.Update(squared_residual)) return true;
  summary.outcome = SolveOutcome::kFailed;
  summary.message =
      DivergenceMessage(solver, summary.iterations,
                        "the matrix is not positive definite or the right-hand side is not finite");
  return false;
}

SparseMatrix CompressedCopy(const SparseMatrix& a) {
  SparseMatrix copy = a;
  copy.makeCompressed();
  return copy;
}

}  // namespace harap::iterative
