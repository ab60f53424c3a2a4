// SPDX-License-Identifier: MIT
// Reading a scenario file's text (TOML) into what it asks for, without reading any file it
// names: the mesh source (mesh_sourcing.h) and the handles (handle_selection.h). Every value is
// checked here, so a typo fails before a mesh is loaded. Internal to harap::io.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io/handle_selection.h"
#include "io/mesh_sourcing.h"
#include "io/scenario.h"

namespace harap::io_internal {

/// A scenario file as written: everything but the contents of the files it names.
struct ScenarioDescription {
  MeshSpec mesh;
  std::optional<BenchmarkHandlesSpec> benchmark;
  std::vector<HandleSpec> handles;
  std::vector<StiffnessSpec> stiffness;
  std::optional<bool> planar;
  std::string planar_where;
};

/// Reads scenario text (FORMAT.md, docs/input.md); relative paths are resolved against
/// `base_directory`; `source` names the text in messages ("file:line:column: ..."). Throws
/// ConfigError for syntax errors, unknown keys, bad values and values beyond `limits`.
ScenarioDescription ReadScenarioText(std::string_view toml_text, const std::string& source,
                                     const std::filesystem::path& base_directory,
                                     const ScenarioLimits& limits);

/// One [[edit]] of a handle-edit file as written (scenario.h's LoadHandleEdits selects it).
struct HandleEditSpec {
  int frame = 0;
  bool add = true;
  std::string name;   ///< The added handle's name, or the one to remove.
  HandleSpec handle;  ///< add: written like a scenario's [[handle]] (no motion needed)
};

/// Reads a handle-edit file's text (docs/session.md): [[edit]] entries with frame = N and
/// add = { a [[handle]] table } or remove = "name". ConfigError naming file:line:column and the
/// edit for anything wrong.
std::vector<HandleEditSpec> ReadHandleEditsText(std::string_view toml_text,
                                                const std::string& source,
                                                const std::filesystem::path& base_directory);

}  // namespace harap::io_internal
