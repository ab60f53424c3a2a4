// SPDX-License-Identifier: MIT
#include "view/scenario_source.h"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <sstream>

#include "framework/error.h"
#include "io/mesh_io.h"

namespace harap::view {

namespace {

// Scenario files name files relative to themselves; the exported scenario is written elsewhere,
// so those names become absolute.
void MakePathsAbsolute(toml::node& node, const std::filesystem::path& base) {
  if (auto* text = node.as_string()) {
    const std::filesystem::path path(text->get());
    if (path.is_relative())
      *text = std::filesystem::absolute(base / path).lexically_normal().string();
  }
}

std::string Inline(toml::node& node) {
  if (auto* table = node.as_table()) table->is_inline(true);
  std::ostringstream out;
  node.visit([&](auto& value) { out << value; });
  return out.str();
}

}  // namespace

ViewSource LoadViewSource(const std::filesystem::path& file, const ConfigNode& run_config,
                          int threads) {
  ViewSource source;
  source.run_config = run_config;
  source.threads = threads;
  const std::string extension = file.extension().string();
  if (extension != ".toml") {
    Scenario& scenario = source.scenario;
    scenario.mesh = ReadMesh(file, &scenario.notes);
    scenario.file = file;
    scenario.mesh_source = file.string();
    DecidePlanar(scenario, std::nullopt, file.string());
    source.mesh_toml = fmt::format(
        "mesh = \"{}\"\n", std::filesystem::absolute(file).lexically_normal().generic_string());
    return source;
  }
  source.scenario = LoadScenario(file);
  // The scenario's own top-level keys (mesh, refine, planar, initial, ...) but its handles.
  toml::table table;
  try {
    table = toml::parse_file(file.string());
  } catch (const toml::parse_error& error) {
    throw ConfigError(fmt::format("{}: {}", file.string(), error.description()));
  }
  const std::filesystem::path base = file.parent_path();
  for (auto& [key, value] : table) {
    if (key.str() == "handle" || key.str() == "units") continue;
    if (key.str() == "mesh" || key.str() == "initial") MakePathsAbsolute(value, base);
    if (auto* mesh = value.as_table(); mesh && key.str() == "mesh") {
      if (auto* surface = mesh->get("tetrahedralize")) MakePathsAbsolute(*surface, base);
    }
    source.mesh_toml += fmt::format("{} = {}\n", key.str(), Inline(value));
  }
  return source;
}

}  // namespace harap::view
