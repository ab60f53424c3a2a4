// SPDX-License-Identifier: MIT
#include "solvers/optimizers/newton_cg.h"

#include <catch2/catch.hpp>

#include "framework/error.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

std::string Config(const char* optimizer, const char* energy, int newton, int max_iterations,
                   const char* hessian = "projected") {
  // Coarse targets that follow the rotations switch Newton steps off while they move; fixed
  // ones keep every level a plain minimization.
  const std::string fixed_targets =
      std::string(optimizer) == "hierarchical" ? "targets_follow_rotations = false\n" : "";
  return fmt::format(
      "[optimizer]\ntype = \"{}\"\ntolerance = 1e-12\nmax_iterations = {}\n"
      "newton = {}\nnewton_hessian = \"{}\"\n{}[energy]\ntype = \"{}\"\n",
      optimizer, max_iterations, newton, newton > 0 ? hessian : "projected", fixed_targets, energy);
}

}  // namespace

TEST_CASE("local/global with Newton steps: monotone, same minimum, far fewer iterations",
          "[optimizers][newton]") {
  // A tube of 24 rings, its far end turned by 0.6 rad and shifted: a bend with one minimum
  // (plain and Newton runs end at the same state), where the plain iteration's tail is slow.
  const BentTube tube(24, 16, 2.0, 0.6, Eigen::Vector3d(0.0, 0.3, -0.1));
  for (const char* optimizer : {"classic", "hierarchical"}) {
    for (const char* energy : {"spokes_and_rims", "spokes", "smooth_arap"}) {
      for (const char* hessian : {"projected", "exact"}) {
        DYNAMIC_SECTION(optimizer << " with " << energy << ", " << hessian << " Hessian") {
          EnergyTrace plain_trace, newton_trace;
          const OptimizeResult plain = OptimizeWithTrace(
              TestSetup(Config(optimizer, energy, 0, 5000)), tube.problem, plain_trace);
          const OptimizeResult newton = OptimizeWithTrace(
              TestSetup(Config(optimizer, energy, 20, 5000, hessian)), tube.problem, newton_trace);
          CheckEnergiesNeverIncrease(newton_trace);
          REQUIRE(plain.converged);
          REQUIRE(newton.converged);
          CHECK(newton.energy == Approx(plain.energy).epsilon(1e-6));
          CHECK((newton.positions - plain.positions).cwiseAbs().maxCoeff() < 1e-3);
          INFO("iterations: plain " << plain.iterations << ", Newton " << newton.iterations);
          CHECK(5 * newton.iterations < plain.iterations);
          // Every finest-level iteration took a Newton step (each kept the sufficient decrease),
          // or most with the trust region, which rejects a step now and then while it adapts its
          // radius; the report says how many Hessian products they used.
          const LevelResult& finest = newton.levels.front();
          CHECK(finest.level == 0);
          CHECK(finest.Measure("newton_steps") >=
                (std::string(hessian) == "exact" ? finest.iterations / 2 : finest.iterations - 1));
          CHECK(finest.Measure("hessian_products") >= finest.Measure("newton_steps"));
          CHECK(plain.levels.front().Measure("newton_steps") == -1);
        }
      }
    }
  }
}

TEST_CASE("local/global with Newton steps: a harder bend ends no higher than plain steps",
          "[optimizers][newton]") {
  // Turned by 1.2 rad the tube has several local minima; the plain iteration and the Newton
  // steps may end in different ones, and here the Newton run's is lower.
  const BentTube tube(24, 16, 2.0, 1.2, Eigen::Vector3d(0.0, 0.4, -0.2));
  EnergyTrace plain_trace, newton_trace;
  const OptimizeResult plain = OptimizeWithTrace(
      TestSetup(Config("classic", "spokes_and_rims", 0, 5000)), tube.problem, plain_trace);
  const OptimizeResult newton = OptimizeWithTrace(
      TestSetup(Config("classic", "spokes_and_rims", 20, 5000)), tube.problem, newton_trace);
  CheckEnergiesNeverIncrease(newton_trace);
  REQUIRE(newton.converged);
  CHECK(newton.energy <= plain.energy * (1.0 + 1e-9));
  CHECK(newton.iterations < plain.iterations);
}

TEST_CASE("local/global with Newton steps: per-element energies, volumetric and planar",
          "[optimizers][newton]") {
  // The tetrahedral bar twisted by 60° and a planar grid sheared: the per-element energy's
  // rotation derivative, also in the plane.
  const TwistedTetBar bar(4, 4, 10, 3.0, M_PI / 3);
  const ShearedPlanarGrid sheet(12, 8, Eigen::Vector2d(0.2, 0.6));
  for (const DeformationProblem* problem : {&bar.problem, &sheet.problem}) {
    DYNAMIC_SECTION((problem == &bar.problem ? "tetrahedra" : "planar triangles")) {
      EnergyTrace plain_trace, newton_trace;
      const OptimizeResult plain = OptimizeWithTrace(
          TestSetup(Config("classic", "elements", 0, 5000)), *problem, plain_trace);
      const OptimizeResult newton = OptimizeWithTrace(
          TestSetup(Config("classic", "elements", 20, 5000)), *problem, newton_trace);
      CheckEnergiesNeverIncrease(newton_trace);
      REQUIRE(plain.converged);
      REQUIRE(newton.converged);
      CHECK(newton.energy == Approx(plain.energy).epsilon(1e-6));
      INFO("iterations: plain " << plain.iterations << ", Newton " << newton.iterations);
      CHECK(newton.iterations < plain.iterations);
    }
  }
}

TEST_CASE("Newton steps: configuration errors name the problem", "[optimizers][newton]") {
  const BentTube tube(8, 8, 2.0, 0.5, Eigen::Vector3d(0.0, 0.2, 0.0));
  const auto optimize = [&](const std::string& toml) {
    const TestSetup setup(toml);
    return setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, Context());
  };
  CHECK_THROWS_WITH(optimize("[optimizer]\ntype = \"classic\"\nnewton = 10\nanderson = 5\n"),
                    Catch::Contains("newton") && Catch::Contains("anderson"));
  CHECK_THROWS_WITH(optimize("[optimizer]\ntype = \"hierarchical\"\nnewton = -1\n"),
                    Catch::Contains("newton") && Catch::Contains(">= 0"));
  // smooth_arap fitting its rotations to the spokes-and-rims part only: R(u) does not minimize
  // the energy, so there is no Newton step on E(u, R(u)).
  CHECK_THROWS_AS(optimize("[optimizer]\ntype = \"classic\"\nnewton = 10\n[energy]\n"
                           "type = \"smooth_arap\"\nrotation_fit = \"spokes_and_rims\"\n"),
                  ConfigError);
}
