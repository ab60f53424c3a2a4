// SPDX-License-Identifier: MIT
// Named option sets for common goals: `harap deform --preset fast`, or `preset = "fast"` at the
// top of a run config (`--config`). A preset sits below everything else: an option the config
// file, a shortcut flag (--optimizer, --tolerance, ...) or a --set gives wins over the preset's.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "framework/config.h"

namespace harap {

struct Preset {
  std::string name;
  std::string description;
  /// Config keys and TOML literals, for any optimizer.
  std::vector<std::pair<std::string, std::string>> settings;
  /// Set only when the run's optimizer is "hierarchical" (the preset's own type, unless a flag
  /// or the config chose another).
  std::vector<std::pair<std::string, std::string>> hierarchical_settings;
  /// Set only when, besides, the hierarchical optimizer's level solver (`optimizer.inner`) is
  /// local_global, the default: options only that level solver reads, or measured with it only.
  std::vector<std::pair<std::string, std::string>> local_global_settings;
};

/// Every preset (docs/solvers.md lists them).
const std::vector<Preset>& Presets();

/// Applies the preset named by `flag` (if not empty) or else by the config's top-level `preset`
/// key, which it removes (the settings stand in for it): each of the preset's settings whose key
/// `config` does not set yet. An unknown name is a ConfigError listing the valid ones.
/// Returns the preset's name ("" for none).
std::string ApplyPreset(ConfigNode& config, const std::string& flag);

}  // namespace harap
