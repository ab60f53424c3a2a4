// SPDX-License-Identifier: MIT
// The multigrid solver's levels and transfer operators, and its iteration counts against the
// grid size (its solves are checked with every other solver's in the conformance suite).

#include "solvers/linear/multigrid_solver.h"

#include <Eigen/Dense>
#include <algorithm>
#include <catch2/catch.hpp>
#include <vector>

#include "framework/context.h"
#include "solvers/linear/multigrid_transfer.h"
#include "tests/solvers/solver_test_matrices.h"

namespace harap::testing {
namespace {

/// Iterations to 1e-8 from zero for three random right-hand sides on a pinned n×n grid
/// Laplacian, with levels down to about 50 unknowns.
int IterationsOnGrid(int n, MultigridSolver::Prolongation prolongation, int& levels) {
  MultigridSolver::Options options;
  options.prolongation = prolongation;
  options.coarsest_unknowns = 50;
  MultigridSolver solver(options);
  const SparseMatrix a = PinnedGridLaplacian(n, n, 31);
  const Context context;
  solver.Factorize(a, context);
  levels = static_cast<int>(solver.level_unknowns().size());
  const Eigen::MatrixXd b = RandomRhs(a.rows(), 3, 32);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
  const SolveSummary summary = solver.Solve(b, x, context);
  REQUIRE(summary.outcome == SolveOutcome::kConverged);
  CHECK(RelativeResidual(a, b, x) <= 1e-8);
  return summary.iterations;
}

}  // namespace

TEST_CASE("multigrid: aggregates cover every unknown once and shrink the system", "[solvers]") {
  const SparseMatrix a = PinnedGridLaplacian(40, 40, 33);
  Index count = 0;
  const std::vector<Index> aggregate = multigrid::AggregateByStrength(a, 0.02, count);
  REQUIRE(aggregate.size() == static_cast<size_t>(a.rows()));
  std::vector<int> size(count, 0);
  for (const Index j : aggregate) {
    REQUIRE(j >= 0);
    REQUIRE(j < count);
    ++size[j];
  }
  CHECK(*std::min_element(size.begin(), size.end()) >= 1);
  // A 4-neighbour grid's aggregates are about a vertex's neighbourhood (5 unknowns).
  CHECK(count < a.rows() / 3);

  const SparseMatrix constant = multigrid::ConstantProlongation(aggregate, count);
  const Eigen::VectorXd row_sums = constant * Eigen::VectorXd::Ones(count);
  CHECK((row_sums.array() == 1.0).all());
  const SparseMatrix smoothed = multigrid::SmoothedProlongation(a, constant);
  CHECK(smoothed.nonZeros() > constant.nonZeros());

  const SparseMatrix coarse = multigrid::GalerkinProduct(a, smoothed);
  const Eigen::MatrixXd dense = Eigen::MatrixXd(coarse);
  const Eigen::MatrixXd reference =
      Eigen::MatrixXd(smoothed).transpose() * Eigen::MatrixXd(a) * Eigen::MatrixXd(smoothed);
  CHECK((dense - dense.transpose()).norm() == 0.0);
  CHECK((dense - reference).norm() <= 1e-12 * reference.norm());
  CHECK(dense.llt().info() == Eigen::Success);
}

TEST_CASE("multigrid: smoothed aggregation's iterations barely grow with the grid", "[solvers]") {
  int small_levels = 0, large_levels = 0, constant_levels = 0;
  const int small = IterationsOnGrid(50, MultigridSolver::Prolongation::kSmoothed, small_levels);
  const int large = IterationsOnGrid(150, MultigridSolver::Prolongation::kSmoothed, large_levels);
  const int constant =
      IterationsOnGrid(150, MultigridSolver::Prolongation::kConstant, constant_levels);
  INFO("smoothed: " << small << " iterations at 50², " << large
                    << " at 150²; constant: " << constant << " at 150²");
  CHECK(large_levels > small_levels);
  CHECK(large <= 1.5 * small);
  CHECK(large < constant);
}

}  // namespace harap::testing
