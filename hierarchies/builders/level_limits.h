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
  /// How min_vertices bounds the coarsest level.
  enum class Coarsest {
    /// Levels are added until one has at most min_vertices vertices (the coarsest is the first
    /// level at or below the bound).
    kAtMost,
    /// No level with fewer than min_vertices vertices is added (the coarsest is the last level at
    /// or above the bound): the paper's setting, "the coarsest level is chosen to have at least
    /// 750 vertices" (Sec. 7, Table 1).
    kAtLeast,
  };
  /// The bound on the coarsest level's vertices (≥ 0; the paper uses 750), as `coarsest` says.
  int min_vertices = 750;
  Coarsest coarsest = Coarsest::kAtMost;
  /// At most this many levels, level 0 included (≥ 0; 0 = no limit).
  int max_levels = 0;

  /// Reads min_vertices, coarsest and max_levels (checked: ConfigError naming the key).
  void ReadLimits(OptionReader node);
  /// Whether a new coarsest level of `vertices` vertices is kept (coarsest = at_least drops one
  /// below min_vertices).
  bool KeepsLevel(Index vertices) const {
    return coarsest == Coarsest::kAtMost || vertices >= min_vertices;
  }
  /// One line per violated limit, worded as RangeProblems words them.
  std::vector<std::string> LimitProblems() const;
};

/// Throws ConfigError "invalid <hierarchy> hierarchy options: <p1>; <p2>" unless `problems` is
/// empty: the one error a builder's Options::Validate raises.
void ThrowIfInvalidOptions(std::string_view hierarchy, const std::vector<std::string>& problems);

/// The hierarchy every builder starts from: the input mesh as level 0, no maps yet.
MeshHierarchy InputLevelOnly(const Mesh& mesh);

/// Removes the coarsest level (a builder made it and LevelLimits::KeepsLevel refused it): the
/// level above becomes the coarsest, whose maps to a coarser level are empty.
void DropCoarsestLevel(MeshHierarchy& hierarchy);

}  // namespace harap
