// SPDX-License-Identifier: MIT
// Deforms a built-in cylinder with hierarchical ARAP through harap's library API, as
// `harap deform` does: a scenario (here from TOML text; ScenarioFromArrays takes arrays), a run
// config naming the pieces, RunDeform, the report.
#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "api/builtins.h"
#include "api/deform.h"
#include "framework/error.h"
#include "io/scenario.h"

int main(int argc, char** argv) {
  const int vertices = argc > 1 ? std::atoi(argv[1]) : 2000;
  try {
    const harap::Registries registries = harap::MakeBuiltinRegistries();
    const std::string scenario_text = fmt::format(R"(
      mesh = {{ builtin = "cylinder", vertices = {} }}
      [[handle]]
      name = "bottom"
      select.slab = {{ axis = "z", from = 0.0, to = 0.02 }}
      [[handle]]
      name = "top"
      select.slab = {{ axis = "z", from = 0.98, to = 1.0 }}
      rotate = {{ axis = [1.0, 0.0, 0.0], degrees = 90.0 }}
      translate = [0.0, 0.35, -0.3]
    )",
                                                  vertices);
    const harap::Scenario scenario = harap::ParseScenario(scenario_text, "<example>", ".");
    const harap::ConfigNode config = harap::ConfigNode::Parse(R"(
      [optimizer]
      type = "hierarchical"
      tolerance = 1e-6
    )",
                                                              "<example config>");
    const harap::DeformOutcome outcome =
        harap::RunDeform(registries, scenario, config, harap::DeformOptions{});
    const harap::OptimizeResult& result = outcome.result;
    std::printf("%d vertices: energy %.9e after %d iterations (%s), %.3f s\n",
                scenario.mesh.num_vertices(), result.energy, result.iterations,
                result.converged ? "converged" : "not converged", result.timings.total);
    return result.converged ? 0 : 1;
  } catch (const harap::Error& error) {
    std::fprintf(stderr, "error: %s\n", error.what());
    return 1;
  }
}
