// SPDX-License-Identifier: MIT
#include "cli/piece_flags.h"

#include <fmt/format.h>

#include "api/presets.h"
#include "cli/output_checks.h"
#include "framework/error.h"

namespace harap {

ConfigNode PieceFlags::BuildConfig() const {
  RefuseMeshAsToml(config_file, "--config", kConfigFileKinds);
  ConfigNode config = config_file.empty() ? ConfigNode::Parse("", "<command line>")
                                          : ConfigNode::ParseFile(config_file);
  const auto set_type = [&](const char* table, const std::string& name) {
    if (!name.empty()) config.Set(fmt::format("{}.type", table), fmt::format("\"{}\"", name));
  };
  set_type("optimizer", optimizer);
  set_type("energy", energy);
  set_type("solver", solver);
  set_type("hierarchy", hierarchy);
  set_type("upsampler", upsampler);
  if (tolerance) config.Set("optimizer.tolerance", fmt::format("{}", *tolerance));
  if (max_iterations) config.Set("optimizer.max_iterations", fmt::format("{}", *max_iterations));
  for (const auto& setting : settings) {
    const auto eq = setting.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw ConfigError(
          fmt::format("--set '{}': expected KEY=VALUE, e.g. energy.lambda=0.5", setting));
    }
    config.Set(setting.substr(0, eq), setting.substr(eq + 1));
  }
  ApplyPreset(config, preset);
  return config;
}

}  // namespace harap
