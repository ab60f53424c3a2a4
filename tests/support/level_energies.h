// SPDX-License-Identifier: MIT
#pragma once

#include <map>
#include <string>
#include <vector>

#include "framework/context.h"
#include "framework/optimizer.h"
#include "tests/support/test_meshes.h"

namespace harap::testing {

/// Records the energy of every local/global iteration by hierarchy level, through the context's
/// iteration callback.
struct LevelEnergies {
  /// Installs the recording callback in `context`; `this` must outlive the run.
  void Record(Context& context);
  /// Runs `hierarchical` on `problem` (octree down to `min_vertices`, tolerance 1e-7) with fixed
  /// coarse targets (targets_follow_rotations = false: every level is then a plain local/global
  /// run, which must be monotone) and the further config tables `tables`, recording.
  OptimizeResult RunHierarchicalWithFixedTargets(const DeformationProblem& problem,
                                                 int min_vertices, const std::string& tables);
  /// True if no level's energy ever increases (relative slack 1e-12 for rounding).
  bool MonotonePerLevel() const;

  std::map<int, std::vector<double>> by_level;
};

}  // namespace harap::testing
