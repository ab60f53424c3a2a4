// SPDX-License-Identifier: MIT
#pragma once

#include "framework/hierarchy.h"
#include "framework/upsampler.h"

namespace harap {

/// Whether a level's rotations are rotations of the plane: per-element rotations on a planar
/// mesh (the 2D energy). Averages of them are then projected to the nearest rotation of the
/// plane, so they stay exactly in it; every other average to the nearest rotation of space.
bool PlanarRotations(const Mesh& mesh, RotationSite site);

/// Per-vertex rotations of a level: the rotations themselves for per-vertex energies; for
/// per-element energies the average of the incident elements' rotations projected to the nearest
/// rotation (the paper's Eq. 11). Vertices without elements get the identity.
Rotations VertexRotations(const Mesh& mesh, RotationSite site, const Rotations& rotations,
                          const Context& context);

/// The inverse direction: per-element rotations as the projected average of the element's
/// vertex rotations (Eq. 12); a copy for per-vertex energies.
Rotations SiteRotations(const Mesh& mesh, RotationSite site, const Rotations& vertex_rotations,
                        const Context& context);

/// Eq. (7): each fine vertex takes the rotation of the coarse vertex it maps to (identity where
/// it maps to none).
Rotations ProlongRotations(const HierarchyLevel& fine, const Rotations& coarse_vertex_rotations);

/// Eq. (6): u_j = u_i + R_i (v̄_j − v̄_i) for the coarse vertex i of fine vertex j: the members of a
/// cell move rigidly with their representative (rest position where j maps to no coarse vertex).
Positions ProlongPositions(const HierarchyLevel& fine, const HierarchyLevel& coarse,
                           const Positions& coarse_positions,
                           const Rotations& coarse_vertex_rotations);

/// Averages each vertex rotation with its 1-ring neighbours' (edges of `mesh`'s elements), then
/// projects back to the nearest rotation; `passes` times (the smoothed up-sampling of Fig. 16).
void SmoothVertexRotations(const Mesh& mesh, RotationSite site, int passes,
                           Rotations& vertex_rotations, const Context& context);

}  // namespace harap

namespace harap {

/// The common core of the cell-based upsamplers: vertex rotations of the coarse level (Eq. 11 for
/// per-element energies), prolonged to the fine vertices (Eq. 7), optionally smoothed over the
/// fine 1-ring `smoothing_passes` times, then turned into fine site rotations (Eq. 12); fine
/// positions by Eq. (6) from the coarse positions and the (unsmoothed) coarse vertex rotations.
void UpsampleCells(const HierarchyLevel& fine, const HierarchyLevel& coarse, RotationSite site,
                   const LevelState& coarse_state, int smoothing_passes, LevelState& fine_state,
                   const Context& context);

}  // namespace harap
