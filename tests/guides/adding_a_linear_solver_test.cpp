// SPDX-License-Identifier: MIT
// The example of docs/adding-a-linear-solver.md, built and run by the suite: a solver written as
// the guide says, registered by name and used by the optimizers through the normal machinery.
// The guide quotes the marked regions word for word (checked below).
#include <catch2/catch.hpp>
#include <cmath>

#include "api/builtins.h"
#include "framework/error.h"
#include "tests/guides/guide_support.h"
#include "tests/support/test_meshes.h"

// [guide:solver-header]
#include <Eigen/Cholesky>
#include <string_view>

#include "framework/config.h"
#include "framework/linear_solver.h"

namespace harap {

/// Dense Cholesky factorization A = L Lᵀ (Eigen's LLT): O(n³), for small systems and as the
/// simplest possible example of a solver.
class DenseCholeskySolver final : public LinearSolver {
 public:
  static constexpr std::string_view kName = "dense_cholesky";

  struct Options {
    /// Largest system it accepts (a dense n×n factor: 8n² bytes).
    int max_unknowns = 5000;
    static Options FromConfig(OptionReader node);
  };

  explicit DenseCholeskySolver(const Options& options) : LinearSolver(kName), options_(options) {}
  bool is_direct() const override { return true; }

 private:
  // LinearSolver's public Factorize() and Solve() have checked the call (square matrix, sizes,
  // a factorization before solving); they time it and reject non-finite solutions.
  void FactorizeImpl(const SparseMatrix& a, const Context& context) override;
  SolveSummary SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
                         const Context& context) override;

  Options options_;
  Eigen::LLT<Eigen::MatrixXd> llt_;
};

}  // namespace harap
// [/guide:solver-header]

namespace harap {

// [guide:solver-source]
DenseCholeskySolver::Options DenseCholeskySolver::Options::FromConfig(OptionReader node) {
  Options options;
  options.max_unknowns =
      node.Get("max_unknowns", options.max_unknowns, "largest system to factor (dense: 8 n² bytes)",
               Range::AtLeast(1));
  node.RejectUnknownKeys();
  return options;
}

void DenseCholeskySolver::FactorizeImpl(const SparseMatrix& a, const Context& /*context*/) {
  if (a.rows() > options_.max_unknowns) {
    throw NumericalError(
        fmt::format("dense_cholesky: {} unknowns exceed max_unknowns = {}; use "
                    "a sparse solver",
                    a.rows(), options_.max_unknowns));
  }
  llt_.compute(Eigen::MatrixXd(a));
  if (llt_.info() != Eigen::Success) {
    throw NumericalError("dense_cholesky: the matrix is not positive definite");
  }
}

SolveSummary DenseCholeskySolver::SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b,
                                            Eigen::Ref<Eigen::MatrixXd> x,
                                            const Context& /*context*/) {
  x = llt_.solve(b);
  SolveSummary summary;
  summary.outcome = SolveOutcome::kSolved;  // a factorization; the residual is not measured
  return summary;
}
// [/guide:solver-source]

}  // namespace harap

using namespace harap;
using namespace harap::testing;

namespace {

// As solvers/linear/register_solvers.cpp's RegisterLinearSolvers.
void RegisterExampleSolver(Registry<LinearSolver>& registry) {
  // [guide:solver-register]
  registry.Add<DenseCholeskySolver>("dense Cholesky (Eigen's LLT) for small systems");
  // [/guide:solver-register]
}

Registries RegistriesWithExample() {
  Registries registries = MakeBuiltinRegistries();
  RegisterExampleSolver(registries.linear_solvers);
  return registries;
}

}  // namespace

TEST_CASE("guide adding-a-linear-solver: the base class checks, times and records", "[guides]") {
  const Registries registries = RegistriesWithExample();
  REQUIRE(registries.linear_solvers.Contains("dense_cholesky"));
  const auto options = registries.linear_solvers.DescribeOptions("dense_cholesky");
  REQUIRE(options.size() == 1);
  CHECK_THAT(options[0].help, Catch::Contains("(>= 1)"));
  const ConfigNode bad = ConfigNode::Parse("[solver]\nmax_unknowns = 0\n", "t");
  CHECK_THROWS_WITH(registries.linear_solvers.Create("dense_cholesky", bad.Child("solver")),
                    Catch::Contains("option 'solver.max_unknowns' is 0, which is not >= 1"));

  auto solver = registries.linear_solvers.Create("dense_cholesky", ConfigNode());
  const Context context;
  Eigen::MatrixXd b = Eigen::MatrixXd::Ones(4, 3), x = Eigen::MatrixXd::Zero(4, 3);
  CHECK_THROWS_AS(solver->Solve(b, x, context), InternalError);  // not factored yet
  SparseMatrix a(4, 4);
  for (int i = 0; i < 4; ++i) {
    a.insert(i, i) = 2.0 + i;
    if (i > 0) a.insert(i, i - 1) = a.insert(i - 1, i) = -1.0;
  }
  solver->Factorize(a, context);
  const SolveSummary summary = solver->Solve(b, x, context);
  CHECK(summary.outcome == SolveOutcome::kSolved);
  CHECK((Eigen::MatrixXd(a) * x - b).norm() < 1e-12);
  CHECK(solver->statistics().solves == 1);
  Eigen::MatrixXd wrong(3, 3);
  CHECK_THROWS_AS(solver->Solve(wrong, x, context), InternalError);  // size checked by the base
  SparseMatrix singular(2, 2);
  singular.insert(0, 0) = 1.0;
  singular.insert(1, 1) = -1.0;
  CHECK_THROWS_AS(solver->Factorize(singular, context), NumericalError);
  CHECK_FALSE(solver->factorized());
}

TEST_CASE("guide adding-a-linear-solver: optimizers run with the example", "[guides]") {
  const Registries registries = RegistriesWithExample();
  const BentTube tube(16, 12, 2.0, M_PI / 4, Eigen::Vector3d(0.0, 0.4, -0.2));
  const std::string tables = "[optimizer]\ntype = \"classic\"\nmax_iterations = 30\n";
  const OptimizeResult dense =
      RunConfigured(registries, tube.problem, tables + "[solver]\ntype = \"dense_cholesky\"\n");
  const OptimizeResult sparse =
      RunConfigured(registries, tube.problem, tables + "[solver]\ntype = \"eigen_ldlt\"\n");
  CHECK(dense.levels.at(0).linear_solves.solves > 0);
  CHECK((dense.positions - sparse.positions).cwiseAbs().maxCoeff() < 1e-8);
  CHECK(dense.energy == Approx(sparse.energy).epsilon(1e-9));
}

TEST_CASE("guide adding-a-linear-solver: the guide quotes the example as it is", "[guides]") {
  const std::string doc = "docs/adding-a-linear-solver.md";
  const std::string example = "tests/guides/adding_a_linear_solver_test.cpp";
  for (const char* region : {"solver-header", "solver-source", "solver-register"}) {
    DYNAMIC_SECTION(region) { CheckGuideQuotes(doc, example, region); }
  }
}
