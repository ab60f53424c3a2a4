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

nlohmann::json ReadPlan(const std::filesystem::path& dir) {
  const std::filesystem::path plan_file = dir / "experiment.json";
  if (!std::filesystem::exists(plan_file)) {
    throw InputError(fmt::format("{}: no experiment.json (not a harap run folder)", dir.string()));
  }
  try {
    return nlohmann::json::parse(ReadText(plan_file));
  } catch (const nlohmann::json::exception& error) {
    throw InputError(fmt::format("{}: {}", plan_file.string(), error.what()));
  }
}

}  // namespace harap::runner_internal
