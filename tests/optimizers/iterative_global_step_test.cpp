// SPDX-License-Identifier: MIT
// Classic and hierarchical ARAP with every linear solver as the global step: the energy
// decreases, and the per-level solve statistics are reported.
#include <catch2/catch.hpp>

#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

// A tube (1440 vertices, height 3) with its bottom ring fixed and its top ring turned and shifted.
constexpr int kRings = 60, kSegments = 24;
struct SmallBentTube : BentTube {
  SmallBentTube() : BentTube(kRings, kSegments, 3.0, M_PI / 2, Eigen::Vector3d(0.0, 0.8, -1.0)) {}
};

const char* const kSolvers[] = {"gauss_seidel", "cg", "chebyshev", "eigen_ldlt"};

}  // namespace

TEST_CASE("classic ARAP with each solver: the energy decreases monotonically", "[optimizers]") {
  SmallBentTube tube;
  for (const char* solver : kSolvers) {
    DYNAMIC_SECTION(solver) {
      TestSetup setup(
          fmt::format("[optimizer]\ntype = \"classic\"\ntolerance = 0\n"
                      "max_iterations = 40\n[solver]\ntype = \"{}\"\n",
                      solver));
      EnergyTrace trace;
      const OptimizeResult result = OptimizeWithTrace(setup, tube.problem, trace);
      const std::vector<double>& energies = trace[0];
      REQUIRE(energies.size() == 40);
      // The global step lowers E(U, R) for fixed R however inexactly it solves (each method
      // reduces the A-norm error), and the local step lowers it for fixed U.
      CheckEnergiesNeverIncrease(trace);
      CHECK(energies.front() > 1.5 * energies.back());
      REQUIRE(result.levels.size() == 1);
      const LevelResult& level = result.levels[0];
      CHECK(level.unknowns == tube.mesh.num_vertices() - 2 * kSegments);
      CHECK(level.linear_solves.solves == 40);
      CHECK(level.linear_solves.seconds > 0.0);
      if (std::string(solver) != "eigen_ldlt") {
        CHECK(level.linear_solves.iterations > 40);
        CHECK(level.linear_solves.max_relative_residual > 0.0);
        CHECK(level.linear_solves.max_relative_residual >=
              level.linear_solves.last_relative_residual);
      } else {
        CHECK(level.linear_solves.iterations == 0);
      }
    }
  }
}

TEST_CASE("hierarchical ARAP with each solver: the energy decreases on every level",
          "[optimizers]") {
  SmallBentTube tube;
  for (const char* solver : kSolvers) {
    DYNAMIC_SECTION(solver) {
      // Fixed coarse targets make each level a plain local/global run, which must be monotone.
      TestSetup setup(fmt::format(
          "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-7\nmax_iterations = 60\n"
          "targets_follow_rotations = false\n[hierarchy]\nmin_vertices = 100\n[solver]\ntype = "
          "\"{}\"\n",
          solver));
      EnergyTrace energies;
      const OptimizeResult result = OptimizeWithTrace(setup, tube.problem, energies);
      REQUIRE(result.levels.size() >= 3);
      CheckEnergiesNeverIncrease(energies);
      for (const LevelResult& level : result.levels) {
        CHECK(level.linear_solves.solves == level.iterations);
        CHECK(level.unknowns > 0);
        CHECK(level.unknowns <= level.vertices);
      }
      CHECK(result.positions.allFinite());
    }
  }
}

TEST_CASE("the per-level solver rule picks the small-system solver by size", "[optimizers]") {
  SmallBentTube tube;
  // Levels up to 600 unknowns are factored, larger ones use CG.
  TestSetup setup(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-7\n[hierarchy]\nmin_vertices = 100\n"
      "[solver]\ntype = \"cg\"\n[solver.small_systems]\nmax_unknowns = 600\n"
      "type = \"eigen_ldlt\"\n");
  const OptimizeResult result =
      setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, Context());
  REQUIRE(result.levels.size() >= 3);
  bool saw_direct = false, saw_iterative = false;
  for (const LevelResult& level : result.levels) {
    const bool direct = level.unknowns <= 600;
    CHECK(setup.factory.solver_name_for(level.unknowns) == (direct ? "eigen_ldlt" : "cg"));
    // Direct solves report no iterations.
    CHECK((level.linear_solves.iterations == 0) == direct);
    saw_direct = saw_direct || direct;
    saw_iterative = saw_iterative || !direct;
  }
  CHECK(saw_direct);
  CHECK(saw_iterative);
}
