// SPDX-License-Identifier: MIT
// Where a scenario's mesh comes from: `mesh = "file"`, `mesh = { builtin = ... }` or
// `mesh = { tetrahedralize = "file" | { builtin = ... }, ... }`, then `refine` rounds of Loop
// subdivision, and the start configuration `initial = "file"`. The TOML side is
// scenario_reading.h; this side reads the files and builds the mesh. Internal to harap::io.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "framework/config.h"
#include "io/scenario.h"

namespace harap::io_internal {

/// What `mesh`, `refine` and `initial` ask for, with where each is written (for messages).
struct MeshSpec {
  enum class Kind { kFile, kBuiltin, kTetrahedralize };
  Kind kind = Kind::kFile;
  std::string where;           ///< of `mesh`
  std::filesystem::path file;  ///< kFile, or kTetrahedralize of a surface file (resolved)
  /// kBuiltin, kTetrahedralize: the `mesh` table (builtin parameters, tetrahedralize options);
  /// its unknown keys are rejected when the mesh is built.
  ConfigNode parameters;
  /// kBuiltin: "builtin builtin=cylinder vertices=100"; kTetrahedralize of a built-in surface:
  /// the same of the `tetrahedralize` table.
  std::string builtin_description;
  bool tetrahedralize_builtin = false;  ///< kTetrahedralize: the surface is a built-in table
  std::string tetrahedralize_where;
  int refine = 0;  ///< Loop subdivision rounds
  std::string refine_where;
  std::optional<std::filesystem::path> initial;
  std::string initial_where;
};

/// Builds `scenario.mesh` (and `mesh_source`, `notes`, `initial`) as `spec` says. `limits` bound
/// what `refine` may make. Problems with the text's values are ConfigErrors, problems with the
/// files named InputErrors; each names where the key is written.
void SourceMesh(const MeshSpec& spec, const ScenarioLimits& limits, Scenario& scenario);

}  // namespace harap::io_internal
