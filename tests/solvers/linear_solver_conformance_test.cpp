// SPDX-License-Identifier: MIT
// Conformance suite run on every name RegisterLinearSolvers() provides, so a new solver is tested
// without new test code.

#include <Eigen/Dense>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "framework/context.h"
#include "framework/error.h"
#include "tests/solvers/solver_test_matrices.h"

namespace harap::testing {
namespace {

struct NamedMatrix {
  std::string label;
  SparseMatrix a;
};

std::vector<NamedMatrix> SpdMatrices() {
  Eigen::MatrixXd one(1, 1);
  one << 2.5;
  Eigen::MatrixXd two(2, 2);
  two << 2.0, -1.0, -1.0, 3.0;
  return {
      {"1x1", FromDense(one)},
      {"2x2", FromDense(two)},
      {"pinned 47x47 grid Laplacian (2025 unknowns)", PinnedGridLaplacian(47, 47, 7)},
      {"pinned 12x200 grid Laplacian (1980 unknowns)", PinnedGridLaplacian(12, 200, 8)},
  };
}

std::vector<NamedMatrix> NotPositiveDefiniteMatrices() {
  std::vector<NamedMatrix> matrices;
  SparseMatrix negative_diagonal = PinnedGridLaplacian(20, 20, 3);
  negative_diagonal.coeffRef(17, 17) = -1.0;
  matrices.push_back({"negative diagonal entry", negative_diagonal});
  // Positive diagonal (≥ 2 − 1) but the smallest eigenvalues (≈ 0.01) shifted below zero: only
  // a pivot check can tell, a diagonal check cannot.
  SparseMatrix shifted = PinnedGridLaplacian(47, 47, 4);
  for (int i = 0; i < shifted.rows(); ++i) shifted.coeffRef(i, i) -= 1.0;
  matrices.push_back({"indefinite with positive diagonal (grid)", shifted});
  Eigen::MatrixXd two(2, 2);
  two << 1.0, 2.0, 2.0, 1.0;  // Eigenvalues 3 and −1.
  matrices.push_back({"indefinite with positive diagonal (2x2)", FromDense(two)});
  Eigen::MatrixXd negative_definite = -Eigen::MatrixXd(PinnedGridLaplacian(6, 6, 5));
  matrices.push_back({"negative definite", FromDense(negative_definite)});
  SparseMatrix empty_column = PinnedGridLaplacian(10, 10, 6);
  empty_column.prune(
      [](Eigen::Index row, Eigen::Index col, double) { return row != 5 && col != 5; });
  matrices.push_back({"zero row and column", empty_column});
  return matrices;
}

std::vector<NamedMatrix> SingularMatrices() {
  Eigen::MatrixXd two(2, 2);
  two << 1.0, -1.0, -1.0, 1.0;
  return {
      {"2x2 Laplacian", FromDense(two)},
      {"unpinned 20x20 grid Laplacian", GridLaplacian(20, 20, 9)},
      {"unpinned 47x47 grid Laplacian", GridLaplacian(47, 47, 10)},
  };
}

bool BitwiseEqual(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y) {
  return x.rows() == y.rows() && x.cols() == y.cols() && (x.array() == y.array()).all();
}

}  // namespace

TEST_CASE("linear solvers: the registry holds the reference solver", "[solvers]") {
  const auto registry = LinearSolverRegistry();
  CHECK(registry.Contains("eigen_ldlt"));
  for (const auto& name : registry.Names()) {
    INFO(name);
    CHECK(!registry.Description(name).empty());
  }
}

TEST_CASE("linear solvers: SPD systems with 3 right-hand sides", "[solvers]") {
  const auto registry = LinearSolverRegistry();
  for (const auto& name : registry.Names()) {
    for (const auto& [label, a] : SpdMatrices()) {
      DYNAMIC_SECTION(name << " on " << label) {
        auto solver = MakeAccurateSolver(registry, name);
        const Context context;
        solver->Factorize(a, context);
        const Eigen::MatrixXd b = RandomRhs(a.rows(), 3, 11);
        Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
        const SolveSummary summary = solver->Solve(b, x, context);
        CHECK(summary.success());
        CHECK(summary.message.empty());
        CHECK(x.allFinite());
        CHECK(RelativeResidual(a, b, x) < 1e-10);
        const Eigen::MatrixXd reference = Eigen::MatrixXd(a).llt().solve(b);
        CHECK(RelativeDifference(x, reference) <
              (solver->is_direct() ? 1e-10 : kIterativeAccuracy));
        if (!solver->is_direct()) {
          CHECK(summary.iterations > 0);
          CHECK(summary.relative_residual <= kConformanceTolerance);
        }
      }
    }
  }
}

TEST_CASE("linear solvers: repeated solves, warm starts, strided blocks, refactorization",
          "[solvers]") {
  const auto registry = LinearSolverRegistry();
  const SparseMatrix a = PinnedGridLaplacian(47, 47, 12);
  const Eigen::Index n = a.rows();
  const Eigen::MatrixXd b = RandomRhs(n, 3, 13);
  for (const auto& name : registry.Names()) {
    DYNAMIC_SECTION(name) {
      auto solver = MakeAccurateSolver(registry, name);
      const Context context;
      solver->Factorize(a, context);
      Eigen::MatrixXd first = Eigen::MatrixXd::Zero(n, 3);
      REQUIRE(solver->Solve(b, first, context).success());

      // Direct solvers ignore the warm start, so even NaN there must not leak into x.
      Eigen::MatrixXd second =
          solver->is_direct()
              ? Eigen::MatrixXd::Constant(n, 3, std::numeric_limits<double>::quiet_NaN())
              : Eigen::MatrixXd::Zero(n, 3);
      REQUIRE(solver->Solve(b, second, context).success());
      if (solver->is_direct()) {
        CHECK(BitwiseEqual(first, second));
      } else {
        CHECK(RelativeDifference(second, first) < 1e-10);
      }

      // b and x as blocks of larger matrices (outer stride ≠ n) and a different column count.
      Eigen::MatrixXd big_b = RandomRhs(n + 5, 4, 14);
      big_b.block(2, 0, n, 3) = b;
      Eigen::MatrixXd big_x = Eigen::MatrixXd::Zero(n + 7, 5);
      REQUIRE(solver->Solve(big_b.block(2, 0, n, 3), big_x.block(3, 1, n, 3), context).success());
      const Eigen::MatrixXd strided = big_x.block(3, 1, n, 3);
      if (solver->is_direct()) {
        CHECK(BitwiseEqual(strided, first));
      } else {
        CHECK(RelativeDifference(strided, first) < 1e-10);
      }
      CHECK((big_x.col(0).array() == 0.0).all());
      CHECK((big_x.col(4).array() == 0.0).all());
      Eigen::MatrixXd one_column = Eigen::MatrixXd::Zero(n, 1);
      REQUIRE(solver->Solve(b.col(1), one_column, context).success());
      CHECK(RelativeDifference(one_column, first.col(1)) < 1e-12);

      // The same object factors another matrix of another size.
      const SparseMatrix other = PinnedGridLaplacian(30, 25, 15);
      solver->Factorize(other, context);
      const Eigen::MatrixXd other_b = RandomRhs(other.rows(), 3, 16);
      Eigen::MatrixXd other_x = Eigen::MatrixXd::Zero(other.rows(), 3);
      REQUIRE(solver->Solve(other_b, other_x, context).success());
      CHECK(RelativeResidual(other, other_b, other_x) < 1e-10);

      // Eigen's uncompressed storage (free space between columns) gives the same answer.
      SparseMatrix uncompressed = a;
      uncompressed.uncompress();
      uncompressed.reserve(Eigen::VectorXi::Constant(n, 3));
      REQUIRE(!uncompressed.isCompressed());
      solver->Factorize(uncompressed, context);
      Eigen::MatrixXd third = Eigen::MatrixXd::Zero(n, 3);
      REQUIRE(solver->Solve(b, third, context).success());
      CHECK(RelativeDifference(third, first) < 1e-12);
    }
  }
}

TEST_CASE("linear solvers: an empty system", "[solvers]") {
  const auto registry = LinearSolverRegistry();
  for (const auto& name : registry.Names()) {
    DYNAMIC_SECTION(name) {
      auto solver = MakeSolver(registry, name);
      const Context context;
      solver->Factorize(SparseMatrix(0, 0), context);
      Eigen::MatrixXd x(0, 3);
      CHECK(solver->Solve(Eigen::MatrixXd(0, 3), x, context).success());
    }
  }
}

TEST_CASE("linear solvers: misuse is an InternalError", "[solvers]") {
  const auto registry = LinearSolverRegistry();
  const SparseMatrix a = PinnedGridLaplacian(8, 8, 17);
  for (const auto& name : registry.Names()) {
    DYNAMIC_SECTION(name) {
      auto solver = MakeSolver(registry, name);
      const Context context;
      Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
      CHECK_THROWS_AS(solver->Solve(RandomRhs(a.rows(), 3, 1), x, context), InternalError);
      CHECK_THROWS_AS(solver->Factorize(SparseMatrix(3, 4), context), InternalError);
      solver->Factorize(a, context);
      Eigen::MatrixXd wrong = Eigen::MatrixXd::Zero(a.rows() + 1, 3);
      CHECK_THROWS_AS(solver->Solve(RandomRhs(a.rows() + 1, 3, 2), wrong, context), InternalError);
      Eigen::MatrixXd wrong_columns = Eigen::MatrixXd::Zero(a.rows(), 2);
      CHECK_THROWS_AS(solver->Solve(RandomRhs(a.rows(), 3, 2), wrong_columns, context),
                      InternalError);
    }
  }
}

TEST_CASE("linear solvers: matrices that are not positive definite are rejected", "[solvers]") {
  const auto registry = LinearSolverRegistry();
  for (const auto& name : registry.Names()) {
    for (const auto& [label, a] : NotPositiveDefiniteMatrices()) {
      DYNAMIC_SECTION(name << " on " << label) {
        auto solver = MakeSolver(registry, name);
        const Context context;
        if (solver->is_direct()) {
          CHECK_THROWS_WITH(solver->Factorize(a, context),
                            Catch::Contains("not positive definite"));
          CHECK_THROWS_AS(solver->Factorize(a, context), NumericalError);
          // A failed factorization leaves nothing to solve with.
          Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
          CHECK_THROWS_AS(solver->Solve(RandomRhs(a.rows(), 3, 3), x, context), InternalError);
        } else {
          // Iterative solvers may only notice while iterating: a NumericalError or a failed
          // summary, both saying so.
          solver = MakeAccurateSolver(registry, name);
          try {
            solver->Factorize(a, context);
            Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
            const SolveSummary summary = solver->Solve(RandomRhs(a.rows(), 3, 3), x, context);
            CHECK_FALSE(summary.success());
            CHECK_THAT(summary.message, Catch::Contains("positive definite"));
          } catch (const NumericalError& error) {
            CHECK_THAT(error.what(), Catch::Contains("positive definite"));
          }
        }
      }
    }
  }
}

TEST_CASE("linear solvers: the not-positive-definite error names the offending row", "[solvers]") {
  // The hub's pivot is bad: the message must name row 0 of A, not its column in the factor.
  const SparseMatrix a = IndefiniteArrowMatrix();
  const auto registry = LinearSolverRegistry();
  for (const auto& name : registry.Names()) {
    DYNAMIC_SECTION(name) {
      auto solver = MakeSolver(registry, name);
      if (!solver->is_direct()) continue;
      const Context context;
      CHECK_THROWS_WITH(solver->Factorize(a, context),
                        Catch::Contains("column 11 of the factor (row 0 of the 12×12 matrix"));
    }
  }
}

TEST_CASE("linear solvers: singular PSD matrices fail loudly, never with silent NaN", "[solvers]") {
  const auto registry = LinearSolverRegistry();
  for (const auto& name : registry.Names()) {
    for (const auto& [label, a] : SingularMatrices()) {
      DYNAMIC_SECTION(name << " on " << label) {
        auto solver = MakeSolver(registry, name);
        const Context context;
        // A random b is not in the range of A, so no answer can be a success.
        const Eigen::MatrixXd b = RandomRhs(a.rows(), 3, 18);
        if (solver->is_direct()) {
          CHECK_THROWS_WITH(solver->Factorize(a, context), Catch::Contains("positive definite"));
        } else {
          solver = MakeAccurateSolver(registry, name);
          try {
            solver->Factorize(a, context);
            Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
            const SolveSummary summary = solver->Solve(b, x, context);
            if (summary.success()) {
              // An iterative solver may also run out of iterations; then its report must say
              // that it did not converge, with the residual it really reached.
              CHECK(x.allFinite());
              CHECK(summary.relative_residual > kConformanceTolerance);
              CHECK(summary.relative_residual == Approx(RelativeResidual(a, b, x)).epsilon(0.01));
            } else {
              CHECK_FALSE(summary.message.empty());
            }
          } catch (const NumericalError&) {
            SUCCEED("NumericalError");
          }
        }
      }
    }
  }
}

TEST_CASE("linear solvers: unknown options are rejected, listing the valid ones", "[solvers]") {
  const auto registry = LinearSolverRegistry();
  for (const auto& name : registry.Names()) {
    DYNAMIC_SECTION(name) {
      CHECK_THROWS_AS(MakeSolver(registry, name, "no_such_option = 1"), ConfigError);
      CHECK_THROWS_WITH(MakeSolver(registry, name, "no_such_option = 1"),
                        Catch::Contains("no_such_option") && Catch::Contains("valid options"));
      for (const auto& option : registry.DescribeOptions(name)) {
        INFO(option.key);
        CHECK(!option.help.empty());
        CHECK_THROWS_WITH(MakeSolver(registry, name, "no_such_option = 1"),
                          Catch::Contains(option.key));
      }
      // Selected through a table's `type` key, as experiment configs do.
      const ConfigNode table =
          ConfigNode::Parse("[solver]\ntype = \"" + name + "\"\n", "<test>").Child("solver");
      CHECK(registry.Create(table, "none") != nullptr);
    }
  }
}

TEST_CASE("linear solvers: check_residual reports the residual", "[solvers]") {
  const auto registry = LinearSolverRegistry();
  const SparseMatrix a = PinnedGridLaplacian(30, 30, 19);
  const Eigen::MatrixXd b = RandomRhs(a.rows(), 3, 20);
  for (const auto& name : registry.Names()) {
    bool has_option = false;
    for (const auto& option : registry.DescribeOptions(name)) {
      has_option = has_option || option.key == "check_residual";
    }
    if (!has_option) continue;
    DYNAMIC_SECTION(name) {
      const Context context;
      auto checked = MakeSolver(registry, name, "check_residual = true");
      checked->Factorize(a, context);
      Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
      const SolveSummary summary = checked->Solve(b, x, context);
      CHECK(summary.success());
      CHECK(summary.relative_residual > 0.0);
      // Same evaluation order as the solvers (b − A x accumulated from b rounds differently).
      Eigen::MatrixXd residual = a * x;
      residual = b - residual;
      double expected = 0.0;
      for (int j = 0; j < 3; ++j)
        expected = std::max(expected, residual.col(j).norm() / b.col(j).norm());
      CHECK(summary.relative_residual == Approx(expected).epsilon(1e-12));
      CHECK(summary.relative_residual < 1e-10);

      if (checked->is_direct()) {  // Iterative solvers always know their residual.
        auto unchecked = MakeSolver(registry, name);
        unchecked->Factorize(a, context);
        CHECK(unchecked->Solve(b, x, context).relative_residual == 0.0);
      }
    }
  }
}

}  // namespace harap::testing
