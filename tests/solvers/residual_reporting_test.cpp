// SPDX-License-Identifier: MIT
// SolveSummary::residual_computed: iterative solvers always measure their residual; direct
// solvers only when asked (check_residual), so reports never show an unmeasured 0 as a residual.
#include <Eigen/Dense>
#include <catch2/catch.hpp>

#include "framework/context.h"
#include "tests/solvers/solver_test_matrices.h"

namespace harap::testing {
namespace {

TEST_CASE("linear solvers say whether they measured the residual", "[solvers]") {
  const auto registry = LinearSolverRegistry();
  const SparseMatrix a = PinnedGridLaplacian(12, 12, 3);
  const Eigen::MatrixXd b = RandomRhs(a.rows(), 3, 5);
  const Context context;
  for (const auto& name : registry.Names()) {
    DYNAMIC_SECTION(name) {
      auto solver = MakeAccurateSolver(registry, name);
      solver->Factorize(a, context);
      Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
      const SolveSummary summary = solver->Solve(b, x, context);
      REQUIRE(summary.success());
      CHECK(summary.residual_computed() == !solver->is_direct());
      SolveStatistics statistics;
      statistics.Add(summary);
      statistics.Add(summary);
      CHECK(statistics.residuals_computed == (solver->is_direct() ? 0 : 2));
      if (solver->is_direct()) {
        auto checked = MakeSolver(registry, name, "check_residual = true\n");
        checked->Factorize(a, context);
        const SolveSummary measured = checked->Solve(b, x, context);
        CHECK(measured.residual_computed());
        CHECK(measured.relative_residual > 0.0);  // rounding leaves a trace
        CHECK(measured.relative_residual < 1e-12);
      }
    }
  }
}

}  // namespace
}  // namespace harap::testing
