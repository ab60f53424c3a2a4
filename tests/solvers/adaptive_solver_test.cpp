// SPDX-License-Identifier: MIT
// AdaptiveSolver: factor or iterate, chosen from CHOLMOD's analysis before factoring.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "framework/context.h"
#include "framework/error.h"
#include "tests/solvers/solver_test_matrices.h"

#ifdef HARAP_HAVE_CHOLMOD
#include "solvers/linear/adaptive_solver.h"
#include "solvers/linear/cholmod_solver.h"

namespace harap::testing {
namespace {

AdaptiveSolver::Options Parse(const std::string& toml) {
  return AdaptiveSolver::Options::FromConfig(OptionReader(ConfigNode::Parse(toml, "<test>")));
}

Eigen::MatrixXd RightHandSide(Index rows) {
  Eigen::MatrixXd b(rows, 3);
  for (Index i = 0; i < rows; ++i) b.row(i) << 1.0 + (i % 7), -0.5 * (i % 3), 0.25 * (i % 11);
  return b;
}

}  // namespace

TEST_CASE("adaptive: factors when the factor is cheap, bit-identical to cholmod",
          "[solvers][adaptive]") {
  const Context context;
  const SparseMatrix a = PinnedGridLaplacian(40, 40, 3);
  const Eigen::MatrixXd b = RightHandSide(a.rows());
  AdaptiveSolver adaptive(Parse(""));
  CHECK_FALSE(adaptive.is_direct());  // nothing chosen yet: callers warm-start
  CHECK(adaptive.chosen().empty());
  std::string reported;
  adaptive.set_on_choice([&](std::string_view name, bool direct) {
    reported = std::string(name) + (direct ? "+direct" : "+iterative");
  });
  adaptive.Factorize(a, context);
  CHECK(adaptive.chosen() == "cholmod");
  CHECK(adaptive.is_direct());
  CHECK(reported == "cholmod+direct");
  const AdaptiveSolver::Decision& decision = adaptive.decision();
  CHECK(decision.estimated);
  CHECK(decision.estimate.nnz_l > a.rows());
  CHECK(decision.estimate.flops > 0.0);
  CHECK(decision.direct_flops <= decision.iterative_flops);

  CholmodSolver cholmod(CholmodSolver::Options{});
  cholmod.Factorize(a, context);
  Eigen::MatrixXd x(a.rows(), 3), y(a.rows(), 3);
  adaptive.Solve(b, x, context);
  cholmod.Solve(b, y, context);
  CHECK((x.array() == y.array()).all());
  // The estimate is CHOLMOD's own count for the factor it then made.
  CHECK(decision.estimate.nnz_l == cholmod.factor_info().nnz_l);
  CHECK(decision.estimate.flops == cholmod.factor_info().flops);
}

TEST_CASE("adaptive: iterates when the factor exceeds the memory budget or costs more work",
          "[solvers][adaptive]") {
  const Context context;
  const SparseMatrix a = PinnedGridLaplacian(40, 40, 4);
  const Eigen::MatrixXd b = RightHandSide(a.rows());
  Eigen::MatrixXd exact(a.rows(), 3);
  CholmodSolver cholmod(CholmodSolver::Options{});
  cholmod.Factorize(a, context);
  cholmod.Solve(b, exact, context);

  for (const std::string& options :
       {std::string("max_factor_megabytes = 1e-3"), std::string("expected_solves = 1e-6"),
        std::string("choose = \"iterative\"")}) {
    INFO(options);
    AdaptiveSolver adaptive(
        Parse(options + "\n[iterative]\nmax_iterations = 5000\ntolerance = 1e-12\n"));
    adaptive.Factorize(a, context);
    CHECK(adaptive.chosen() == "cg");
    CHECK_FALSE(adaptive.is_direct());
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
    const SolveSummary summary = adaptive.Solve(b, x, context);
    CHECK(summary.iterations > 0);
    CHECK((x - exact).norm() <= 1e-8 * exact.norm());
  }
  // The reasons are the ones the options name.
  AdaptiveSolver small_budget(Parse("max_factor_megabytes = 1e-3"));
  small_budget.Factorize(a, context);
  CHECK(small_budget.decision().estimate.factor_bytes > small_budget.decision().budget_bytes);
  AdaptiveSolver few_solves(Parse("expected_solves = 1e-6"));
  few_solves.Factorize(a, context);
  CHECK(few_solves.decision().direct_flops > few_solves.decision().iterative_flops);
  // choose = "direct" factors without an estimate.
  AdaptiveSolver direct(Parse("choose = \"direct\"\nexpected_solves = 1e-6"));
  direct.Factorize(a, context);
  CHECK(direct.chosen() == "cholmod");
  CHECK_FALSE(direct.decision().estimated);
}

TEST_CASE("adaptive: factors after all once the iterations cost as much as the factorization",
          "[solvers][adaptive]") {
  const Context context;
  const SparseMatrix a = PinnedGridLaplacian(40, 40, 8);
  const Eigen::MatrixXd b = RightHandSide(a.rows());
  // Expecting almost no solves, it iterates; 20 CG iterations on 1600 unknowns cost more than
  // the factorization of a 40×40 grid, so the second solve is direct.
  AdaptiveSolver adaptive(Parse("expected_solves = 1e-3"));
  std::vector<std::string> reported;
  adaptive.set_on_choice([&](std::string_view name, bool) { reported.emplace_back(name); });
  adaptive.Factorize(a, context);
  REQUIRE(adaptive.chosen() == "cg");
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
  const SolveSummary first = adaptive.Solve(b, x, context);
  CHECK(first.iterations == 20);
  CHECK(20.0 * 3 * (2.0 * a.nonZeros() + 12.0 * a.rows()) >= adaptive.decision().estimate.flops);
  const SolveSummary second = adaptive.Solve(b, x, context);
  CHECK(second.iterations == 0);
  CHECK(adaptive.chosen() == "cg>cholmod");
  CHECK(adaptive.is_direct());
  CHECK(reported == std::vector<std::string>{"cg", "cg>cholmod"});
  CHECK((Eigen::MatrixXd(a) * x - b).norm() <= 1e-10 * b.norm());
  // Iterating because the factor does not fit never switches.
  AdaptiveSolver no_room(Parse("max_factor_megabytes = 1e-3"));
  no_room.Factorize(a, context);
  for (int k = 0; k < 3; ++k) CHECK(no_room.Solve(b, x, context).iterations > 0);
  CHECK(no_room.chosen() == "cg");
}

TEST_CASE("adaptive: factors after all once it served more solves than expected",
          "[solvers][adaptive]") {
  const Context context;
  // A cube's factor fills in (nested separators of side², flops ~ n²), while 2 CG iterations per
  // solve are cheap: it iterates for 2 expected solves, and the arithmetic rule alone would keep
  // iterating long after; the count rule factors before the third solve.
  const SparseMatrix a = PinnedCubeLaplacian(16);
  const Eigen::MatrixXd b = RightHandSide(a.rows());
  AdaptiveSolver adaptive(Parse("expected_solves = 2\niterative = { max_iterations = 2 }"));
  adaptive.Factorize(a, context);
  REQUIRE(adaptive.chosen() == "cg");
  const double per_solve = 2.0 * 3 * (2.0 * a.nonZeros() + 12.0 * a.rows());
  REQUIRE(3 * per_solve < adaptive.decision().estimate.flops);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
  for (int k = 0; k < 2; ++k) {
    CHECK(adaptive.Solve(b, x, context).iterations == 2);
    CHECK(adaptive.chosen() == "cg");
  }
  CHECK(adaptive.Solve(b, x, context).iterations == 0);
  CHECK(adaptive.chosen() == "cg>cholmod");
  CHECK((Eigen::MatrixXd(a) * x - b).norm() <= 1e-10 * b.norm());
}

TEST_CASE("adaptive: factors after all once a CG solve left most of its correction undone",
          "[solvers][adaptive]") {
  const Context context;
  // A pinned 160×160 grid whose solution is smooth, solved from zero: 20 Jacobi-preconditioned
  // CG iterations leave most of it undone (about 70% in the A-norm², see the cg test), as on
  // dragon-lift's finest level from 437K vertices up. A cube beside it (another component) makes
  // the factor expensive, so the arithmetic rule iterates for 3 expected solves; the count and
  // the flops rules would switch before solve 4 at the earliest, the stall rule does before the
  // second solve after a stalled first one, unless max_unresolved = 1.
  const SparseMatrix grid = PinnedGridLaplacian(160, 160, 9);
  const SparseMatrix a = BlockDiagonal({grid, PinnedCubeLaplacian(24)});
  Eigen::MatrixXd solution = Eigen::MatrixXd::Zero(a.rows(), 3);
  for (Index i = 0; i < grid.rows(); ++i) {
    const double u = static_cast<double>(i % 158) / 157.0, v = static_cast<double>(i / 158) / 157.0;
    solution.row(i) << std::sin(3.1 * u) * std::sin(3.1 * v), u * (1.0 - u), v * (1.0 - v);
  }
  const Eigen::MatrixXd b = Eigen::MatrixXd(a * solution);
  for (const std::string limit : {"0.5", "1"}) {
    INFO("max_unresolved = " << limit);
    AdaptiveSolver adaptive(Parse("expected_solves = 3\nmax_unresolved = " + limit));
    adaptive.Factorize(a, context);
    REQUIRE(adaptive.chosen() == "cg");
    // Neither the flops nor the count rule would switch before the fourth solve.
    const double per_solve = 20.0 * 3 * (2.0 * a.nonZeros() + 12.0 * a.rows());
    REQUIRE(3 * per_solve < adaptive.decision().estimate.flops);
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
    // A stalled first step is kept (the level may stop after it); the factor waits for a
    // second solve.
    CHECK(adaptive.Solve(b, x, context).iterations == 20);
    CHECK(adaptive.chosen() == "cg");
    CHECK((x - solution).norm() > 0.1 * solution.norm());
    const SolveSummary second = adaptive.Solve(b, x, context);
    if (limit == "1") {
      CHECK(second.iterations == 20);
      CHECK(adaptive.chosen() == "cg");
    } else {
      CHECK(second.iterations == 0);
      CHECK(adaptive.chosen() == "cg>cholmod");
      CHECK((x - solution).norm() <= 1e-8 * solution.norm());
    }
  }
  // A start that misses only a rough part: 20 iterations resolve it, no switch. Then a later
  // step that stalls on a smooth change (dragon-lift's second step): that system is solved again
  // with the factor at once.
  {
    AdaptiveSolver adaptive(Parse("expected_solves = 3"));
    adaptive.Factorize(a, context);
    Eigen::MatrixXd x = solution;
    for (Index i = 0; i < a.rows(); i += 3) x(i, 0) += 1e-3;
    CHECK(adaptive.Solve(b, x, context).iterations == 20);
    CHECK(adaptive.chosen() == "cg");
    const Eigen::MatrixXd moved = 2.0 * solution;
    const Eigen::MatrixXd b_moved = Eigen::MatrixXd(a * moved);
    CHECK(adaptive.Solve(b_moved, x, context).iterations == 20);  // the CG ones counted
    CHECK(adaptive.chosen() == "cg>cholmod");
    CHECK((x - moved).norm() <= 1e-8 * moved.norm());
  }
  // Iterating because the factor exceeds the memory budget: a stalled step is kept, no switch.
  {
    AdaptiveSolver over_budget(Parse("max_factor_megabytes = 0.001"));
    over_budget.Factorize(a, context);
    REQUIRE(over_budget.chosen() == "cg");
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
    for (int k = 0; k < 2; ++k) CHECK(over_budget.Solve(b, x, context).iterations == 20);
    CHECK(over_budget.chosen() == "cg");
  }
}

TEST_CASE("adaptive: a refactorization keeps the direct choice", "[solvers][adaptive]") {
  const Context context;
  SparseMatrix a = PinnedGridLaplacian(30, 30, 5);
  AdaptiveSolver adaptive(Parse(""));
  adaptive.PrepareForRefactor();
  adaptive.Factorize(a, context);
  REQUIRE(adaptive.chosen() == "cholmod");
  // Row 10 becomes the identity's (a new handle).
  for (SparseMatrix::InnerIterator it(a, 10); it; ++it) {
    const double value = it.row() == 10 ? 1.0 : 0.0;
    it.valueRef() = value;
    a.coeffRef(10, it.row()) = value;
  }
  const LinearSolver::RefactorSummary summary = adaptive.Refactor(a, {10}, context);
  CHECK(summary.route != LinearSolver::RefactorRoute::kFull);
  CHECK(adaptive.chosen() == "cholmod");
  const Eigen::MatrixXd b = RightHandSide(a.rows());
  Eigen::MatrixXd x(a.rows(), 3);
  adaptive.Solve(b, x, context);
  CHECK((Eigen::MatrixXd(a) * x - b).norm() <= 1e-10 * b.norm());
}

TEST_CASE("adaptive: options are checked", "[solvers][adaptive]") {
  CHECK_THROWS_WITH(Parse("max_factor_megabytes = -1"), Catch::Contains("max_factor_megabytes"));
  CHECK_THROWS_WITH(Parse("expected_solves = 0"), Catch::Contains("expected_solves"));
  CHECK_THROWS_WITH(Parse("max_unresolved = 1.5"), Catch::Contains("max_unresolved"));
  CHECK_THROWS_AS(Parse("choose = \"sometimes\""), ConfigError);
  CHECK_THROWS_AS(Parse("[direct]\nmode = \"fast\""), ConfigError);
  CHECK_THROWS_AS(Parse("[iterative]\nmax_iterations = -3"), ConfigError);
  CHECK(AdaptiveSolver::DefaultBudgetBytes() > 0.0);
}

TEST_CASE("cholmod: Factorize() after Analyze() of the same matrix reuses the analysis",
          "[solvers][cholmod]") {
  const Context context;
  const SparseMatrix a = PinnedGridLaplacian(35, 35, 6);
  const Eigen::MatrixXd b = RightHandSide(a.rows());
  CholmodSolver analysed(CholmodSolver::Options{}), plain(CholmodSolver::Options{});
  const CholmodSolver::Estimate estimate = analysed.Analyze(a);
  analysed.Factorize(a, context);
  plain.Factorize(a, context);
  CHECK(analysed.factor_info().analysis_seconds == estimate.analysis_seconds);
  CHECK(analysed.factor_info().nnz_l == plain.factor_info().nnz_l);
  Eigen::MatrixXd x(a.rows(), 3), y(a.rows(), 3);
  analysed.Solve(b, x, context);
  plain.Solve(b, y, context);
  CHECK((x.array() == y.array()).all());
  // Another matrix is analysed anew (the kept analysis is for `a` only).
  const SparseMatrix other = PinnedGridLaplacian(20, 50, 7);
  analysed.Analyze(a);
  analysed.Factorize(other, context);
  Eigen::MatrixXd z(other.rows(), 3);
  const Eigen::MatrixXd c = RightHandSide(other.rows());
  analysed.Solve(c, z, context);
  CHECK((Eigen::MatrixXd(other) * z - c).norm() <= 1e-10 * c.norm());
}

}  // namespace harap::testing
#endif  // HARAP_HAVE_CHOLMOD
