// SPDX-License-Identifier: MIT
#include "cli/scenario_command.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "framework/error.h"
#include "io/scenario_generator.h"

namespace harap {

CLI::App* AddScenarioCommand(CLI::App& app, ScenarioCommandArguments& args) {
  auto* command = app.add_subcommand(
      "scenario",
      "make a deformation scenario from a mesh alone: one handle held, one moved, at the two "
      "ends of the longest principal axis (look at it with harap handles)");
  command->add_option("mesh", args.mesh, "mesh file (any format harap reads)")->required();
  command->add_option("--kind", args.kind,
                      fmt::format("motion of the moved handle: {} (default bend)",
                                  fmt::join(ScenarioKindNames(), ", ")));
  command->add_option("--refine", args.refine,
                      "Loop subdivision rounds written into the scenario (default 0)");
  command->add_option("--fraction", args.handle_fraction,
                      "vertices per handle as a fraction of the mesh's largest component "
                      "(default 0.05)");
  command->add_option("--out", args.out, "scenario TOML file to write (default: print it)");
  return command;
}

int ScenarioCommand(const ScenarioCommandArguments& args) {
  namespace fs = std::filesystem;
  ScenarioGeneratorOptions options;
  options.kind = ParseScenarioKind(args.kind);
  if (args.refine < 0 || args.refine > 3) {
    throw ConfigError(fmt::format("--refine {} is outside 0..3", args.refine));
  }
  options.refine = args.refine;
  options.handle_fraction = args.handle_fraction;
  const fs::path mesh = fs::absolute(args.mesh).lexically_normal();
  if (!fs::exists(mesh)) throw InputError(fmt::format("{}: no such mesh file", args.mesh));
  if (args.out.empty()) {
    std::fputs(GenerateScenarioForFile(mesh, mesh.generic_string(), options).c_str(), stdout);
    return 0;
  }
  if (fs::path(args.out).extension() != ".toml") {
    throw ConfigError(fmt::format("--out {}: a scenario file ends in .toml", args.out));
  }
  const fs::path out = fs::absolute(args.out).lexically_normal();
  const std::string text = GenerateScenarioForFile(
      mesh, mesh.lexically_relative(out.parent_path()).generic_string(), options);
  std::ofstream file(out, std::ios::binary);
  file << text;
  if (!file) throw InputError(fmt::format("{}: cannot write the scenario", args.out));
  return 0;
}

}  // namespace harap
