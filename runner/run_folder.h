// SPDX-License-Identifier: MIT
// Reading what `harap run` wrote into a run folder, shared by the runner (merge) and the Slurm
// backend (resubmission, status). Internal to harap::runner.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace harap::runner_internal {

/// The whole of `file` ("" if it cannot be read).
std::string ReadText(const std::filesystem::path& file);

/// `file` parsed as JSON; InputError naming the file when it is not valid JSON.
nlohmann::json ReadJson(const std::filesystem::path& file);

/// DIR/experiment.json, the plan; InputError naming the folder when it is missing (not a run
/// folder) or the file when it is not valid JSON.
nlohmann::json ReadPlan(const std::filesystem::path& dir);

}  // namespace harap::runner_internal
