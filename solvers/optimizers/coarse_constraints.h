// SPDX-License-Identifier: MIT
#pragma once

#include <vector>

#include "framework/energy.h"
#include "framework/hierarchy.h"
#include "framework/optimizer.h"

namespace harap {

/// The constraints of one coarse level (the paper's Section 4, "Constraints"): the constrained
/// coarse vertices with the mean target and the mean rest offset of their finest-level members,
/// so that target_c(R_c) = mean_target − R_c · mean_offset.
struct LevelConstraints {
  std::vector<Index> vertices;
  Positions mean_target;  ///< #vertices×3
  Positions mean_offset;  ///< #vertices×3: mean of v̄_m − v̄_c over the members m
  std::vector<std::vector<Index>> incident_elements;  ///< per-element energies only
  /// The level is planar: per-element rotations average to a rotation of the plane.
  bool planar = false;
};

/// Maps the finest-level constraints to level `level` through the hierarchy's vertex maps.
LevelConstraints MapConstraints(const MeshHierarchy& hierarchy, int level,
                                const Constraints& finest);

/// Writes target_c(R_c) of every constrained vertex into `positions`; R_c is the vertex's rotation
/// from `rotations` (for per-element energies the projected mean of its incident elements'
/// rotations, Eq. 11), or the identity if `rotations` is null.
void PlaceConstrainedVertices(const LevelConstraints& constraints, RotationSite site,
                              const Rotations* rotations, Positions& positions);

}  // namespace harap
