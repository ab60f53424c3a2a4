// SPDX-License-Identifier: MIT
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "framework/config.h"
#include "framework/hierarchy.h"

namespace harap {

/// When a hierarchy builder stops adding levels: the part of the options every builder shares,
/// so its keys, help texts, defaults and checks are written once. A builder's Options derives
/// from it (fields stay `options.min_vertices`, `options.max_levels`).
struct LevelLimits {
  /// Stop once the coarsest level has at most this many vertices (≥ 0; the paper uses 750).
  int min_vertices = 750;
  /// At most this many levels, level 0 included (≥ 0; 0 = no limit).
  int max_levels = 0;

  /// Reads min_vertices and max_levels (range-checked: ConfigError naming the key).
  void ReadLimits(OptionReader node);
  /// One line per violated limit, worded as RangeProblems words them.
  std::vector<std::string> LimitProblems() const;
};

/// Throws ConfigError "invalid <hierarchy> hierarchy options: <p1>; <p2>" unless `problems` is
/// empty: the one error a builder's Options::Validate raises.
void ThrowIfInvalidOptions(std::string_view hierarchy, const std::vector<std::string>& problems);

/// The hierarchy every builder starts from: the input mesh as level 0, no maps yet.
MeshHierarchy InputLevelOnly(const Mesh& mesh);

}  // namespace harap
