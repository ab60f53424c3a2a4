// SPDX-License-Identifier: MIT
// What every registered level solver promises (framework/level_solver.h), checked on each one
// by name: it places its own constrained vertices, lowers the energy from the start, reports the
// energy of the state it returns, keeps its state between solves (moved targets need no new
// Constrain), and says clearly when it cannot do handle edits.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "framework/error.h"
#include "framework/level_solver.h"
#include "solvers/optimizers/local_global_solver.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

// The largest distance of a constrained vertex from its target.
double TargetError(const Positions& positions, const std::vector<Index>& vertices,
                   const Positions& targets) {
  double error = 0.0;
  for (size_t k = 0; k < vertices.size(); ++k) {
    error =
        std::max(error, (positions.row(vertices[k]) - targets.row(static_cast<Index>(k))).norm());
  }
  return error;
}

}  // namespace

TEST_CASE("level solvers: the contract, for every registered one", "[optimizers][level_solver]") {
  // A twisted tetrahedral bar and the per-element energy: every built-in level solver runs it.
  const TwistedTetBar bar(4, 4, 9, 3.0, M_PI / 3);
  const TestSetup setup("[energy]\ntype = \"elements\"\n");
  const Context context;
  for (const std::string& name : setup.registries.level_solvers.Names()) {
    DYNAMIC_SECTION(name) {
      const std::unique_ptr<LevelSolver> prototype =
          setup.registries.level_solvers.Create(name, ConfigNode());
      const std::unique_ptr<LevelSolver> solver = prototype->CreateAnother();
      solver->Precompute(LevelSetup{&bar.mesh, nullptr, 0, false}, setup.factory, context);
      const Constraints& constraints = bar.problem.constraints;
      const ConstrainSummary constrained =
          solver->Constrain(LevelConstraints::Exact(constraints, false), setup.factory, context);
      CHECK(constrained.factored);
      CHECK(solver->num_unknowns() ==
            bar.mesh.num_vertices() - static_cast<Index>(constraints.indices.size()));

      // From the rest positions: the solver moves the constrained vertices itself.
      LevelState state;
      state.positions = bar.mesh.vertices;
      LevelState start = state;
      start.positions = InitialPositions(bar.problem);
      const double start_energy = solver->FitRotations(start, context);
      LevelSolveRequest request;
      request.max_iterations = 200;
      request.diagonal = BoundingBoxDiagonal(bar.mesh);
      const LevelSolveResult first = solver->Solve(state, request, context);
      CHECK(TargetError(state.positions, constraints.indices, constraints.targets) == 0.0);
      CHECK(first.iterations > 0);
      CHECK(std::isfinite(first.energy));
      CHECK(first.energy < 0.5 * start_energy);
      // The reported energy is the returned state's (rotations fitted to it).
      LevelState check = state;
      CHECK(solver->FitRotations(check, context) == Approx(first.energy).epsilon(1e-9));

      // Kept state: new targets without a new Constrain().
      Positions moved = constraints.targets;
      moved.col(1).array() += 0.05;
      solver->MoveTargets(moved);
      const LevelSolveResult second = solver->Solve(state, request, context);
      CHECK(TargetError(state.positions, constraints.indices, moved) == 0.0);
      CHECK(std::isfinite(second.energy));

      // Interactive sessions: supported, or a clear ConfigError up front.
      const std::unique_ptr<LevelSolver> editable = prototype->CreateAnother();
      try {
        editable->Precompute(LevelSetup{&bar.mesh, nullptr, 0, true}, setup.factory, context);
        editable->Constrain(LevelConstraints::Exact(constraints, false), setup.factory, context);
        LevelState edited;
        edited.positions = bar.mesh.vertices;
        editable->Solve(edited, request, context);
        CHECK(TargetError(edited.positions, constraints.indices, constraints.targets) == 0.0);
      } catch (const ConfigError& error) {
        CHECK_THAT(error.what(), Catch::Contains("handle edits"));
      }
    }
  }
}

TEST_CASE("level solvers: ADMM reports inverted elements as a named measure",
          "[optimizers][level_solver]") {
  const TwistedTetBar bar(4, 4, 9, 3.0, M_PI / 3);
  for (const char* config :
       {"[optimizer]\ntype = \"wrapd\"\nmax_iterations = 30\n",
        "[optimizer]\ntype = \"classic\"\nanderson = 3\nmax_iterations = 30\n"}) {
    DYNAMIC_SECTION(config) {
      const TestSetup setup(std::string(config) + "[energy]\ntype = \"elements\"\n");
      const OptimizeResult result =
          setup.MakeOptimizer()->Optimize(bar.problem, setup.factory, Context());
      REQUIRE(result.levels.size() == 1);
      const LevelResult& level = result.levels.front();
      const bool admm = std::string(config).find("wrapd") != std::string::npos;
      CHECK(level.measures.count("inverted_elements") == (admm ? 1u : 0u));
      CHECK(level.measures.count("accelerated_iterations") == (admm ? 0u : 1u));
      CHECK(level.Measure("newton_steps") == -1.0);  // not counted: absent
    }
  }
}
