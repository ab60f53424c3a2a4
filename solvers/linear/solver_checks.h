// SPDX-License-Identifier: MIT
#pragma once

// Checks and error messages shared by the linear solvers of this module (not a component).

#include <Eigen/Core>
#include <string>
#include <string_view>

#include "framework/config.h"
#include "framework/types.h"

namespace harap::solver_checks {

/// The diagonal of the n×n matrix `a` (any storage). Throws NumericalError naming `solver` if an
/// entry is ≤ 0, missing or not finite: then `a` cannot be positive definite.
Eigen::VectorXd PositiveDiagonal(const SparseMatrix& a, std::string_view solver);

/// Throws NumericalError for pivot `pivot` at `column` of the factor (row `row` of `a`, whose
/// diagonal entry is `diagonal`): not positive definite if ≤ 0 or NaN, numerically singular
/// if ≤ pivot_tolerance · diagonal.
[[noreturn]] void ThrowBadPivot(std::string_view solver, Eigen::Index rows, Eigen::Index column,
                                Eigen::Index row, double pivot, double diagonal,
                                double pivot_tolerance);

/// True when a pivot of an SPD matrix's LDLᵀ factor is acceptable: d > pivot_tolerance · A_kk.
/// For SPD A, 0 < d_k ≤ A_kk and d_k / A_kk is invariant to diagonal scaling (for the last
/// pivot it is 1 / (A_kk (A⁻¹)_kk)), so one tolerance suits every mesh size and unit.
inline bool AcceptablePivot(double pivot, double diagonal, double pivot_tolerance) {
  return pivot > pivot_tolerance * diagonal;  // False for NaN as well.
}

/// Max over columns of ‖b − A x‖ / ‖b‖ (‖b − A x‖ for a zero column); `workspace` is resized to
/// n×k, so repeated calls with one k do not allocate.
double MaxRelativeResidual(const SparseMatrix& a, const Eigen::Ref<const Eigen::MatrixXd>& b,
                           const Eigen::Ref<const Eigen::MatrixXd>& x, Eigen::MatrixXd& workspace);

/// Reads the options every factorization-based solver shares — `pivot_tolerance` (validated)
/// and `check_residual` — with their help texts, into the given fields (defaults on input).
void ReadFactorizationOptions(OptionReader node, double& pivot_tolerance, bool& check_residual);

/// Advice shared by the "not positive definite" messages.
inline constexpr std::string_view kNotPositiveDefiniteAdvice =
    "The global-step matrix should be symmetric positive definite once the constrained vertices "
    "are eliminated; it is not when a connected component has no constrained vertex (its "
    "translation is free) or the mesh is degenerate (zero-area elements, coincident vertices, "
    "NaN/inf weights).";

/// Advice shared by the out-of-memory messages.
inline constexpr std::string_view kOutOfMemoryAdvice =
    "Try an iterative solver ([solver] type = \"cg\" or \"gauss_seidel\", or --solver cg)";

}  // namespace harap::solver_checks
