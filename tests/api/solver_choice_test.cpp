// SPDX-License-Identifier: MIT
// The [solver.small_systems] rule of the component factory, the per-level solve statistics and
// the --diagnostics spectra in the report.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "api/builtins.h"
#include "api/component_factory.h"
#include "api/deform.h"
#include "framework/error.h"

using namespace harap;

namespace {

const char* kScenario = R"(
mesh = { builtin = "cylinder", vertices = 3000 }
[[handle]]
select.slab = { axis = "z", from = 0.0, to = 0.03 }
[[handle]]
select.slab = { axis = "z", from = 0.97, to = 1.0 }
rotate = { axis = [1.0, 0.0, 0.0], degrees = 60.0 }
translate = [0.0, 0.2, -0.1]
)";

RegistryComponentFactory Factory(const Registries& registries, const std::string& toml) {
  return RegistryComponentFactory(registries, ConfigNode::Parse(toml, "test config"));
}

}  // namespace

TEST_CASE("solver.small_systems chooses the solver by system size", "[experiments]") {
  const Registries registries = MakeBuiltinRegistries();
  const auto factory = Factory(registries,
                               "[solver]\ntype = \"gauss_seidel\"\nmax_iterations = 3\n"
                               "[solver.small_systems]\nmax_unknowns = 1000\n"
                               "type = \"eigen_ldlt\"\n");
  CHECK(factory.MakeLinearSolver(2, 10)->is_direct());
  CHECK(factory.MakeLinearSolver(1, 1000)->is_direct());
  CHECK_FALSE(factory.MakeLinearSolver(0, 1001)->is_direct());
  CHECK(factory.solver_name_for(1000) == "eigen_ldlt");
  CHECK(factory.solver_name_for(1001) == "gauss_seidel");
  CHECK(factory.solver_name() == "gauss_seidel");

  // Without the table every system gets [solver]'s solver.
  const auto plain = Factory(registries, "[solver]\ntype = \"cg\"\n");
  CHECK_FALSE(plain.MakeLinearSolver(3, 5)->is_direct());
  CHECK(plain.solver_name_for(5) == "cg");
}

TEST_CASE("solver.small_systems is validated when the factory is made", "[experiments]") {
  const Registries registries = MakeBuiltinRegistries();
  CHECK_THROWS_WITH(Factory(registries, "[solver.small_systems]\ntype = \"eigen_ldlt\"\n"),
                    Catch::Contains("max_unknowns"));
  CHECK_THROWS_WITH(Factory(registries, "[solver.small_systems]\nmax_unknowns = -5\n"),
                    Catch::Contains("max_unknowns") && Catch::Contains("-5"));
  CHECK_THROWS_WITH(
      Factory(registries,
              "[solver]\ntype = \"cg\"\n[solver.small_systems]\nmax_unknowns = 10\nmode = 3\n"
              "type = \"eigen_ldlt\"\n"),
      Catch::Contains("mode"));
  CHECK_THROWS_WITH(
      Factory(registries, "[solver.small_systems]\nmax_unknowns = 10\ntype = \"nope\"\n"),
      Catch::Contains("nope") && Catch::Contains("eigen_ldlt"));
  CHECK_THROWS_AS(Factory(registries, "[solver]\ntype = \"cg\"\nsmall_systems = 5\n"), ConfigError);
  // An option of the large-system solver is still checked with the rule present.
  CHECK_THROWS_WITH(Factory(registries,
                            "[solver]\ntype = \"cg\"\nsweeps = 3\n[solver.small_systems]\n"
                            "max_unknowns = 10\n"),
                    Catch::Contains("sweeps"));
  const auto options = DescribeSmallSystemsOptions();
  REQUIRE(options.size() == 2);
  CHECK(options[0].key == "max_unknowns");
  CHECK(options[1].key == "type");
}

TEST_CASE("RunDeform reports solve statistics and, with diagnostics, level spectra",
          "[experiments]") {
  const Registries registries = MakeBuiltinRegistries();
  const Scenario scenario = ParseScenario(kScenario, "inline", ".");
  ConfigNode config;
  config.Set("optimizer.type", "\"hierarchical\"");
  config.Set("solver.type", "\"cg\"");
  config.Set("solver.small_systems.max_unknowns", "800");
  config.Set("solver.small_systems.type", "\"eigen_ldlt\"");
  DeformOptions options;
  options.diagnostics = true;
  const DeformOutcome outcome = RunDeform(registries, scenario, config, options);
  const auto report = nlohmann::json::parse(DeformReportJson(scenario, outcome, false));
  const auto& levels = report["levels"];
  REQUIRE(levels.size() >= 2);
  for (const auto& level : levels) {
    INFO(level.dump());
    for (const char* key :
         {"unknowns", "solver", "solves", "solver_iterations", "max_relative_residual",
          "last_relative_residual", "solve_seconds", "spectrum"}) {
      CHECK(level.contains(key));
    }
    const bool direct = level["unknowns"].get<int>() <= 800;
    CHECK(level["solver"] == (direct ? "eigen_ldlt" : "cg"));
    CHECK(level["solves"] == level["iterations"]);
    for (const char* matrix : {"matrix", "jacobi"}) {
      const auto& spectrum = level["spectrum"][matrix];
      const double lambda_min = spectrum["lambda_min"], lambda_max = spectrum["lambda_max"];
      CHECK(lambda_min > 0.0);
      CHECK(lambda_max > lambda_min);
      CHECK(spectrum["condition_number"].get<double>() ==
            Approx(lambda_max / lambda_min).epsilon(1e-12));
    }
    // Jacobi scaling of a Laplacian-like matrix: λ_max of D^-1/2 A D^-1/2 lies near 2.
    CHECK(level["spectrum"]["jacobi"]["lambda_max"].get<double>() < 2.5);
  }
  // Without diagnostics no spectrum is computed.
  const DeformOutcome plain = RunDeform(registries, scenario, config, {});
  CHECK(plain.spectra.empty());
}
