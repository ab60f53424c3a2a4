// SPDX-License-Identifier: MIT
#include "solvers/linear/solver_checks.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "framework/error.h"

namespace harap::solver_checks {

Eigen::VectorXd PositiveDiagonal(const SparseMatrix& a, std::string_view solver) {
  Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(a.rows());
  for (Eigen::Index j = 0; j < a.outerSize(); ++j) {
    for (SparseMatrix::InnerIterator it(a, j); it; ++it) {
      if (it.row() == j) diagonal[j] = it.value();
    }
  }
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    if (!(diagonal[i] > 0.0) || !std::isfinite(diagonal[i])) {
      throw NumericalError(fmt::format(
          "{0}: the matrix is not positive definite: its diagonal entry ({1}, {1}) is {2} (it "
          "must be positive and finite). {3}",
          solver, i, diagonal[i], kNotPositiveDefiniteAdvice));
    }
  }
  return diagonal;
}

void ThrowBadPivot(std::string_view solver, Eigen::Index rows, Eigen::Index column,
                   Eigen::Index row, double pivot, double diagonal, double pivot_tolerance) {
  const std::string why =
      !(pivot > 0.0) || !std::isfinite(pivot)
          ? std::string("the matrix is not positive definite")
          : fmt::format(
                "the matrix is numerically singular, so not positive definite (pivot / "
                "diagonal = {:.3g} <= pivot_tolerance = {:.3g})",
                pivot / diagonal, pivot_tolerance);
  throw NumericalError(fmt::format(
      "{}: {}: pivot {:.6g} at column {} of the factor (row {} of the {}×{} matrix, whose "
      "diagonal entry is {:.6g}). {}",
      solver, why, pivot, column, row, rows, rows, diagonal, kNotPositiveDefiniteAdvice));
}

double MaxRelativeResidual(const SparseMatrix& a, const Eigen::Ref<const Eigen::MatrixXd>& b,
                           const Eigen::Ref<const Eigen::MatrixXd>& x, Eigen::MatrixXd& workspace) {
  workspace.resize(b.rows(), b.cols());
  workspace.noalias() = a * x;
  workspace = b - workspace;
  double worst = 0.0;
  for (Eigen::Index j = 0; j < b.cols(); ++j) {
    const double b_norm = b.col(j).norm();
    const double r_norm = workspace.col(j).norm();
    worst = std::max(worst, b_norm > 0.0 ? r_norm / b_norm : r_norm);
  }
  return worst;
}

void ReadFactorizationOptions(OptionReader node, double& pivot_tolerance, bool& check_residual) {
  pivot_tolerance =
      node.Get("pivot_tolerance", pivot_tolerance,
               "pivots d_k <= pivot_tolerance * A_kk mean a numerically singular matrix (an "
               "error)",
               Range::HalfOpen(0.0, 1.0));
  check_residual = node.Get("check_residual", check_residual,
                            "compute max ‖b − A x‖ / ‖b‖ on every solve (keeps a copy of A; slow)");
}

}  // namespace harap::solver_checks
