// SPDX-License-Identifier: MIT
#pragma once

#include <filesystem>

#include "view/page_session.h"

namespace harap::view {

/// What `harap view FILE` shows: a scenario file (its mesh and handles), or a mesh file alone
/// (no handles yet; the page adds them). Throws InputError or ConfigError as `harap deform`
/// does for a bad file.
ViewSource LoadViewSource(const std::filesystem::path& file, const ConfigNode& run_config,
                          int threads);

}  // namespace harap::view
