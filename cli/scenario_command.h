// SPDX-License-Identifier: MIT
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace harap {

struct ScenarioCommandArguments {
  std::string mesh;
  std::string kind = "bend";
  std::string out;
  int refine = 0;
  double handle_fraction = 0.05;
};

/// `harap scenario MESH --kind K [--refine N] [--fraction F] [--out S.toml]`: a deformation
/// scenario generated from the mesh alone (scenario_generator.h), written to `out` (the mesh
/// named relative to it) or printed (the mesh named by its absolute path).
CLI::App* AddScenarioCommand(CLI::App& app, ScenarioCommandArguments& args);
int ScenarioCommand(const ScenarioCommandArguments& args);

}  // namespace harap
