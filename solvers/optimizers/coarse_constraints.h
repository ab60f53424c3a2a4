// SPDX-License-Identifier: MIT
#pragma once

#include <vector>

#include "framework/energy.h"
#include "framework/hierarchy.h"
#include "framework/level_solver.h"

namespace harap {

/// Maps the finest-level constraints to level `level` through the hierarchy's vertex maps (the
/// paper's Section 4): the constrained coarse vertices with the mean target and the mean rest
/// offset of their finest-level members, so that target_c(R_c) = mean_target − R_c · mean_offset.
LevelConstraints MapConstraints(const MeshHierarchy& hierarchy, int level,
                                const Constraints& finest);

/// Fills constraints.incident_elements from `mesh` (the elements around each constrained vertex,
/// in increasing order): what a per-element energy's coarse targets need (Eq. 11).
void FindIncidentElements(const Mesh& mesh, LevelConstraints& constraints);

/// Writes the target of every constrained vertex into `positions`: exact targets as they are;
/// coarse ones as target_c(R_c), R_c the vertex's rotation from `rotations` (for per-element
/// energies the projected mean of its incident elements' rotations, Eq. 11), or the identity if
/// `rotations` is null.
void PlaceConstrainedVertices(const LevelConstraints& constraints, RotationSite site,
                              const Rotations* rotations, Positions& positions);

/// `constraints` with vertices and incident elements renumbered (a level solver's own
/// numbering: new_vertex[v], new_element[e]).
LevelConstraints RenumberedConstraints(const LevelConstraints& constraints,
                                       const std::vector<Index>& new_vertex,
                                       const std::vector<Index>& new_element);

}  // namespace harap
