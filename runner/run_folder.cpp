// SPDX-License-Identifier: MIT
#include "runner/run_folder.h"

#include <fmt/format.h>

#include <fstream>
#include <sstream>

#include "framework/error.h"

namespace harap::runner_internal {

std::string ReadText(const std::filesystem::path& file) {
  std::ifstream stream(file, std::ios::binary);
  std::stringstream buffer;
  buffer << stream.rdbuf();
  return buffer.str();
}

nlohmann::json ReadJson(const std::filesystem::path& file) {
  try {
    return nlohmann::json::parse(ReadText(file));
  } catch (const nlohmann::json::exception& error) {
    throw InputError(fmt::format("{}: {}", file.string(), error.what()));
  }
}

nlohmann::json ReadPlan(const std::filesystem::path& dir) {
  const std::filesystem::path plan_file = dir / "experiment.json";
  if (!std::filesystem::exists(plan_file)) {
    throw InputError(fmt::format("{}: no experiment.json (not a harap run folder)", dir.string()));
  }
  return ReadJson(plan_file);
}

}  // namespace harap::runner_internal
