// SPDX-License-Identifier: MIT
#pragma once

#include <string>

#include "framework/context.h"
#include "framework/types.h"

namespace harap {

/// What one Solve() did.
struct SolveSummary {
  bool success = true;
  int iterations = 0;              ///< 0 for direct solvers.
  double relative_residual = 0.0;  ///< max over columns of ‖b − A x‖ / ‖b‖ (if computed, else 0).
  std::string message;             ///< Why it failed, if it did.
};

/// Solves A X = B for a fixed symmetric positive definite A and several right-hand sides at once
/// (the three coordinates of the global step).
///
/// Lifetime: Factorize() once per matrix (direct solvers analyze and factor; iterative solvers
/// set up preconditioners); then Solve() any number of times, allocation-free. `x` carries the
/// warm start on input (iterative solvers start from it; direct solvers ignore it).
/// Factorize() throws NumericalError if A is not positive definite or memory runs out, with a
/// message that says what to try instead.
///
///   auto solver = registries.linear_solvers.Create(config.Child("solver"), "cholmod");
///   solver->Factorize(a_ff, context);
///   solver->Solve(b, x, context);
class LinearSolver {
 public:
  virtual ~LinearSolver() = default;

  /// `a` is symmetric in full storage (both triangles).
  virtual void Factorize(const SparseMatrix& a, const Context& context) = 0;

  virtual SolveSummary Solve(const Eigen::Ref<const Eigen::MatrixXd>& b,
                             Eigen::Ref<Eigen::MatrixXd> x, const Context& context) = 0;

  /// True for factorization-based solvers (their result does not depend on the warm start).
  virtual bool is_direct() const = 0;

 protected:
  LinearSolver() = default;
};

}  // namespace harap
