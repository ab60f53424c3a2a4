// SPDX-License-Identifier: MIT
#pragma once

#include <filesystem>
#include <string>

#include "io/handle_colors.h"
#include "io/scenario.h"

namespace harap {

/// `harap handles SCENARIO.toml [--out handles.ply]`: what a scenario's handles select and where
/// they go, without solving. The text (returned) gives the mesh's bounding box and per handle its
/// vertex count, centroid, selection and motion, plus vertices several handles select.
std::string DescribeHandles(const Scenario& scenario);

/// Writes the rest mesh as binary PLY with per-vertex colours: each handle's vertices in its own
/// colour (HandleColor), free vertices grey; a vertex several handles select takes the first
/// one's colour, as its target does.
void WriteHandlesPly(const std::filesystem::path& file, const Scenario& scenario);

/// The command: loads the scenario, prints DescribeHandles, writes WriteHandlesPly to `out`
/// (if not empty; must end in .ply). Returns the exit code.
int HandlesCommand(const std::string& scenario_file, const std::string& out);

}  // namespace harap
