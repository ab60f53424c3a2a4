// SPDX-License-Identifier: MIT
// The composition root resolves a run's tables once: the factory builds from parsed options (not
// from the document), and combinations of pieces that cannot work fail before any work.
#include "api/component_factory.h"

#include <catch2/catch.hpp>

#include "api/builtins.h"
#include "framework/error.h"

using namespace harap;

TEST_CASE("the component factory builds from the options resolved at its construction",
          "[experiments]") {
  const Registries registries = MakeBuiltinRegistries();
  ConfigNode config = ConfigNode::Parse(
      "[solver]\ntype = \"eigen_ldlt\"\n[solver.level_1]\ntype = \"gauss_seidel\"\n", "test");
  const RegistryComponentFactory factory(registries, config);
  // Edits of the document after resolution change nothing the factory makes.
  config.Set("solver.type", "cg");
  config.Set("solver.level_1.type", "eigen_ldlt");
  config.Set("energy.type", "no_such_energy");
  CHECK(factory.solver_name() == "eigen_ldlt");
  CHECK(factory.MakeLinearSolver(0, 100)->is_direct());
  CHECK(factory.solver_name_for(1, 100) == "gauss_seidel");
  CHECK_FALSE(factory.MakeLinearSolver(1, 100)->is_direct());
  CHECK(factory.energy_name() == "spokes_and_rims");
  CHECK(factory.MakeEnergy() != nullptr);
}

TEST_CASE("pieces that cannot work together fail when the run is resolved, naming the option",
          "[experiments]") {
  const Registries registries = MakeBuiltinRegistries();
  const auto check = [&](const std::string& toml) {
    const ConfigNode config = ConfigNode::Parse(toml, "test config");
    const RegistryComponentFactory factory(registries, config);
    MakeOptimizer(registries, config)->CheckComponents(factory);
  };
  // Newton steps need the rotations to minimize the energy.
  CHECK_THROWS_WITH(check("[optimizer]\nnewton = 5\n[energy]\ntype = \"smooth_arap\"\n"
                          "rotation_fit = \"spokes_and_rims\"\n"),
                    Catch::Contains("optimizer.newton") && Catch::Contains("newton = 0"));
  CHECK_NOTHROW(check("[optimizer]\nnewton = 5\n[energy]\ntype = \"smooth_arap\"\n"));
  // The ADMM level solvers minimize the per-element energy.
  CHECK_THROWS_WITH(check("[optimizer]\ntype = \"admm_pd\"\n[energy]\ntype = \"spokes\"\n"),
                    Catch::Contains("energy `elements`"));
  CHECK_THROWS_WITH(check("[optimizer]\ntype = \"hierarchical\"\ninner = \"wrapd\"\n"),
                    Catch::Contains("energy `elements`"));
  CHECK_NOTHROW(check("[optimizer]\ntype = \"wrapd\"\n[energy]\ntype = \"elements\"\n"));
}

TEST_CASE("a registry resolves a table once into a recipe that makes configured instances",
          "[experiments]") {
  const Registries registries = MakeBuiltinRegistries();
  const ConfigNode table = ConfigNode::Parse("type = \"cg\"\nmax_iterations = 7\n", "test");
  const Recipe<LinearSolver> recipe = registries.linear_solvers.Resolve(table, "cholmod");
  CHECK(recipe.name() == "cg");
  const auto first = recipe.Make();
  const auto second = recipe.Make();
  CHECK(first != second);
  CHECK_FALSE(first->is_direct());
  CHECK_THROWS_WITH(
      registries.linear_solvers.Resolve(ConfigNode::Parse("max_iterations = 0\n", "test"), "cg"),
      Catch::Contains("max_iterations"));
}
