// SPDX-License-Identifier: MIT
// The scenario parser (TOML text → mesh + handles). Relative paths resolve against
// tests/fuzz/scenario_files/, which holds a few tiny meshes and an index file the seeds name.
#include "io/scenario.h"
#include "tests/fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // Keep every input cheap: big built-in meshes and deep refinement are legitimate requests
  // that only cost time and memory, not bugs. (With 100K elements, a refined plane took 13 s
  // under ASan and coverage instrumentation on a loaded machine: a libFuzzer timeout.)
  harap::ScenarioLimits limits;
  limits.max_builtin_vertices = 5000;
  limits.max_elements = 20000;
  try {
    const harap::Scenario scenario = harap::ParseScenario(
        harap::fuzzing::AsText(data, size), "fuzz.toml", HARAP_FUZZ_SCENARIO_FILES, limits);
    harap::fuzzing::CheckAndRepair(scenario.mesh, scenario.MergedConstraints());
  } catch (const harap::ConfigError&) {
  } catch (const harap::InputError&) {
  }
  return 0;
}
