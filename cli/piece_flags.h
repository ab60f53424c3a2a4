// SPDX-License-Identifier: MIT
// The command-line flags that choose the pieces and set their options, shared by the commands
// that solve (`harap deform`, `hierarchy`, `drag`), so that they read them the same way.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "framework/config.h"

namespace harap {

struct PieceFlags {
  std::string config_file;  ///< --config: TOML tables of options.
  std::string optimizer, energy, solver, hierarchy, upsampler;  ///< --optimizer ... --upsampler
  std::optional<double> tolerance;                              ///< --tolerance
  std::optional<int> max_iterations;                            ///< --max-iterations
  std::vector<std::string> settings;                            ///< --set KEY=VALUE, in order
  std::string preset;  ///< --preset NAME (api/presets.h); below all of the above

  /// The run config: the --config file, then the shortcut flags, then each --set in order (later
  /// ones win), then the preset (--preset, else the config's `preset` key) for the keys none of
  /// them set. A mesh given as --config, or a --set without '=', is a ConfigError/InputError
  /// saying what was expected.
  ConfigNode BuildConfig() const;
};

}  // namespace harap
