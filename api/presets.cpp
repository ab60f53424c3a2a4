// SPDX-License-Identifier: MIT
#include "api/presets.h"

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

// The table at a dotted path (empty if absent).
ConfigNode TableAt(const ConfigNode& config, std::string_view dotted_path) {
  ConfigNode node = config;
  while (!dotted_path.empty()) {
    const size_t dot = dotted_path.find('.');
    node = node.Child(dotted_path.substr(0, dot));
    if (dot == std::string_view::npos) break;
    dotted_path.remove_prefix(dot + 1);
  }
  return node;
}

// The value of option `key` of `table` ("" if absent): a lookup, not an option read for a check.
std::string StringAt(const ConfigNode& table, std::string_view key) {
  return OptionReader(table).Get(key, std::string(), "");
}

}  // namespace

const std::vector<Preset>& Presets() {
  // "fast": measured on all five shared scenes and smooth ARAP on two (docs/results.md, "Solver
  // choice and presets").
  static const std::vector<Preset> presets = {
      {"fast",
       "the fastest configuration measured at tolerance 1e-6: the hierarchical optimizer with "
       "the adaptive solver on the input mesh's level, expecting 4 global steps there (from the "
       "up-sampled start), so that CHOLMOD's analysis picks warm-started CG where factoring "
       "costs more than that, and if it factors, solves with the supernodal factor itself "
       "(converting it for faster solves does not pay off in so few); Cholesky on the coarse "
       "levels, whose solutions must be accurate (paper Section 5.2); fixed coarse constraint "
       "targets and Anderson acceleration (5), "
       "which then takes effect and halves the coarse levels' iterations; the coarse levels "
       "stopped at 0.3 times the tolerance, so that the finest level starts nearer a minimum and "
       "stops at a lower energy (docs/solvers.md, Presets)",
       {{"optimizer.type", "\"hierarchical\""}},
       {{"solver.level_0.type", "\"adaptive\""},
        {"solver.level_0.expected_solves", "4"},
        {"solver.level_0.direct.mode", "\"supernodal\""},
        {"optimizer.targets_follow_rotations", "false"}},
       {{"optimizer.anderson", "5"}, {"optimizer.coarse_tolerance_factor", "0.3"}}},
      {"hierarchical",
       "the paper's plain hierarchical method (Algorithm 2 with the default options)",
       {{"optimizer.type", "\"hierarchical\""}},
       {},
       {}},
  };
  return presets;
}

std::string ApplyPreset(ConfigNode& config, const std::string& flag) {
  std::string name = StringAt(config, "preset");
  // The preset's settings replace the key, so the run config's check need not know it.
  config.Remove("preset");
  if (!flag.empty()) name = flag;
  if (name.empty()) return name;
  const Preset* preset = nullptr;
  std::vector<std::string> names;
  for (const Preset& candidate : Presets()) {
    names.push_back(candidate.name);
    if (candidate.name == name) preset = &candidate;
  }
  if (preset == nullptr) {
    throw ConfigError(
        fmt::format("unknown preset '{}'; valid presets: {}", name, fmt::join(names, ", ")));
  }
  // The type the preset gives table `table` ("" if none), as a TOML literal.
  const auto preset_type = [&](std::string_view table) {
    for (const auto* list : {&preset->settings, &preset->hierarchical_settings}) {
      for (const auto& [key, value] : *list) {
        if (key == fmt::format("{}.type", table)) return value;
      }
    }
    return std::string();
  };
  const auto apply = [&](const std::vector<std::pair<std::string, std::string>>& settings) {
    for (const auto& [key, value] : settings) {
      if (Sets(config, key)) continue;
      // An option in a table whose type the preset chose (or in a subtable of it, e.g.
      // solver.level_0.direct) applies only to that type: another type chosen by the user would
      // reject it.
      std::string table = key.substr(0, key.rfind('.'));
      std::string type = preset_type(table);
      while (type.empty() && table.find('.') != std::string::npos) {
        table.resize(table.rfind('.'));
        type = preset_type(table);
      }
      if (!type.empty() && key != table + ".type" &&
          fmt::format("\"{}\"", StringAt(TableAt(config, table), "type")) != type) {
        continue;
      }
      config.Set(key, value);
    }
  };
  apply(preset->settings);
  const ConfigNode optimizer = config.Child("optimizer");
  if (StringAt(optimizer, "type") == "hierarchical") {
    apply(preset->hierarchical_settings);
    // Another level solver (admm_pd, wrapd) reads none of local_global's options.
    if (!optimizer.Has("inner") || StringAt(optimizer, "inner") == "local_global") {
      apply(preset->local_global_settings);
    }
  }
  return name;
}

}  // namespace harap
