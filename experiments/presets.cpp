// SPDX-License-Identifier: MIT
#include "experiments/presets.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "framework/error.h"

namespace harap {
namespace {

// Whether `config` sets the dotted key (tables along the way included).
bool Sets(const ConfigNode& config, std::string_view dotted_key) {
  ConfigNode node = config;
  while (true) {
    const size_t dot = dotted_key.find('.');
    const std::string_view part = dotted_key.substr(0, dot);
    if (!node.Has(part)) return false;
    if (dot == std::string_view::npos) return true;
    node = node.Child(part);
    dotted_key.remove_prefix(dot + 1);
  }
}

}  // namespace

const std::vector<Preset>& Presets() {
  // "fast": measured on armadillo-bend, tolerance 1e-6 (docs/results.md, issue 23).
  static const std::vector<Preset> presets = {
      {"fast",
       "the fastest configuration measured at tolerance 1e-6: the hierarchical optimizer with "
       "fixed coarse targets, looser coarse levels, and CG instead of a factorization on the "
       "input mesh's level (docs/results.md, issue 23)",
       {{"optimizer.type", "\"hierarchical\""}},
       {{"optimizer.update_constraints", "false"},
        {"optimizer.coarse_tolerance", "1e-5"},
        {"solver.level_0.type", "\"cg\""}}},
      {"hierarchical",
       "the paper's plain hierarchical method (Algorithm 2 with the default options)",
       {{"optimizer.type", "\"hierarchical\""}},
       {}},
  };
  return presets;
}

std::string ApplyPreset(ConfigNode& config, const std::string& flag) {
  std::string name = config.Get("preset", std::string(),
                                "a named option set (fast, hierarchical; docs/solvers.md); the "
                                "config's own options win over it");
  if (!flag.empty()) name = flag;
  if (name.empty()) return name;
  const Preset* preset = nullptr;
  std::vector<std::string> names;
  for (const Preset& candidate : Presets()) {
    names.push_back(candidate.name);
    if (candidate.name == name) preset = &candidate;
  }
  if (preset == nullptr) {
    throw ConfigError(fmt::format("unknown preset '{}'; valid presets: {}", name,
                                  fmt::join(names, ", ")));
  }
  for (const auto& [key, value] : preset->settings) {
    if (!Sets(config, key)) config.Set(key, value);
  }
  const ConfigNode optimizer = config.Child("optimizer");
  if (optimizer.Has("type") &&
      optimizer.Get("type", std::string(), "which optimizer to use") == "hierarchical") {
    for (const auto& [key, value] : preset->hierarchical_settings) {
      if (!Sets(config, key)) config.Set(key, value);
    }
  }
  return name;
}

}  // namespace harap
