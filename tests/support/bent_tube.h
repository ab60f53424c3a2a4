// SPDX-License-Identifier: MIT
#pragma once

#include <map>
#include <string>
#include <vector>

#include "framework/context.h"
#include "framework/optimizer.h"

namespace harap::testing {

/// The bending problem several optimizer and energy tests share: a tube (Tube(rings, segments)
/// stretched to `height` along z) with its bottom ring fixed and its top ring turned about x by
/// `angle` (radians) and shifted by `shift`. Constraints list the bottom ring, then the top ring.
/// Not copyable: `problem.mesh` points at `mesh`.
struct BentTube {
  BentTube(int rings, int segments, double height, double angle, const Eigen::Vector3d& shift);
  BentTube(const BentTube&) = delete;
  BentTube& operator=(const BentTube&) = delete;

  Mesh mesh;
  DeformationProblem problem;
};

/// Records the energy of every local/global iteration by hierarchy level, through the context's
/// iteration callback.
struct LevelEnergies {
  /// Installs the recording callback in `context`; `this` must outlive the run.
  void Record(Context& context);
  /// Runs `hierarchical` on `problem` (octree down to `min_vertices`, tolerance 1e-7) with fixed
  /// coarse targets (update_constraints = false: every level is then a plain local/global run,
  /// which must be monotone) and the further config tables `tables`, recording.
  OptimizeResult RunHierarchicalWithFixedTargets(const DeformationProblem& problem,
                                                 int min_vertices, const std::string& tables);
  /// True if no level's energy ever increases (relative slack 1e-12 for rounding).
  bool MonotonePerLevel() const;

  std::map<int, std::vector<double>> by_level;
};

}  // namespace harap::testing
