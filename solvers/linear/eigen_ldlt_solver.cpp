// SPDX-License-Identifier: MIT
#include "solvers/linear/eigen_ldlt_solver.h"

#include <fmt/format.h>

#include <new>
#include <string>

#include "framework/error.h"
#include "solvers/linear/solver_checks.h"

namespace harap {

EigenLdltSolver::Options EigenLdltSolver::Options::FromConfig(OptionReader node) {
  Options options;
  solver_checks::ReadFactorizationOptions(node, options.pivot_tolerance, options.check_residual);
  node.RejectUnknownKeys();
  return options;
}

void EigenLdltSolver::FactorizeImpl(const SparseMatrix& a, const Context& /*context*/) {
  a_copy_ = SparseMatrix();
  if (a.rows() == 0) return;
  const Eigen::VectorXd diagonal = solver_checks::PositiveDiagonal(a, "eigen_ldlt");

  try {
    ldlt_.compute(a);
  } catch (const std::bad_alloc&) {
    // Eigen reports failed allocations (the factor's fill) with std::bad_alloc.
    throw NumericalError(fmt::format(
        "eigen_ldlt: out of memory during the factorization of a {}×{} matrix with {} nonzeros. "
        "{}, solver \"cholmod\" (less fill), or a coarser mesh.",
        a.rows(), a.cols(), a.nonZeros(), solver_checks::kOutOfMemoryAdvice));
  }
  if (ldlt_.info() == Eigen::InvalidInput) {
    throw InternalError("eigen_ldlt: Eigen rejected the matrix as invalid input");
  }
  // Eigen stops only at an exactly zero pivot (NumericalIssue) and accepts negative ones, so
  // check every pivot, up to and including the one Eigen stopped at (the later ones are unset).
  // Pivot k belongs to row Pinv(k) of A, since Eigen factors P A P⁻¹.
  pivots_ = ldlt_.vectorD();  // vectorD() returns a copy: keep one for Solve().
  const Eigen::VectorXd& pivots = pivots_;
  const auto& to_row = ldlt_.permutationPinv().indices();
  for (Eigen::Index k = 0; k < pivots.size(); ++k) {
    const Eigen::Index row = to_row.size() > 0 ? to_row[k] : k;
    if (!solver_checks::AcceptablePivot(pivots[k], diagonal[row], options_.pivot_tolerance)) {
      solver_checks::ThrowBadPivot("eigen_ldlt", a.rows(), k, row, pivots[k], diagonal[row],
                                   options_.pivot_tolerance);
    }
  }
  HARAP_CHECK(ldlt_.info() == Eigen::Success, "SimplicialLDLT failed but every pivot is positive");
  if (options_.check_residual) a_copy_ = a;
}

SolveSummary EigenLdltSolver::SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b,
                                        Eigen::Ref<Eigen::MatrixXd> x, const Context& /*context*/) {
  SolveSummary summary;
  // Eigen's own solve() permutes the result in place and copies D, which allocates on every
  // call; going through a kept workspace and pivot copy makes every step allocation-free.
  workspace_.resize(b.rows(), b.cols());
  workspace_.noalias() = ldlt_.permutationP() * b;
  ldlt_.matrixL().solveInPlace(workspace_);
  for (Eigen::Index j = 0; j < workspace_.cols(); ++j) workspace_.col(j).array() /= pivots_.array();
  ldlt_.matrixU().solveInPlace(workspace_);
  x.noalias() = ldlt_.permutationPinv() * workspace_;

  // (LinearSolver::Solve() turns a non-finite solution into a failure.)
  if (options_.check_residual && x.allFinite()) {
    summary.relative_residual = solver_checks::MaxRelativeResidual(a_copy_, b, x, residual_);
    summary.outcome = SolveOutcome::kSolvedChecked;
  }
  return summary;
}

}  // namespace harap
