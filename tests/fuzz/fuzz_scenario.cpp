// SPDX-License-Identifier: MIT
// The scenario parser (TOML text → mesh + handles). Relative paths resolve against
// tests/fuzz/scenario_files/, which holds a few tiny meshes and an index file the seeds name.
#include "framework/io/scenario.h"
#include "tests/fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // Keep every input cheap: big built-in meshes and deep refinement are legitimate requests
  // that only cost time and memory, not bugs.
  harap::ScenarioLimits limits;
  limits.max_builtin_vertices = 20000;
  limits.max_elements = 100000;
  try {
    const harap::Scenario scenario =
        harap::ParseScenario(harap::fuzzing::AsText(data, size), "fuzz.toml",
                             HARAP_FUZZ_SCENARIO_FILES, limits);
    harap::fuzzing::CheckAndRepair(scenario.mesh, scenario.MergedConstraints());
  } catch (const harap::ConfigError&) {
  } catch (const harap::InputError&) {
  }
  return 0;
}
