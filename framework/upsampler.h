// SPDX-License-Identifier: MIT
#pragma once

#include "framework/context.h"
#include "framework/energy.h"
#include "framework/hierarchy.h"

namespace harap {

/// The solution state on one level: deformed positions and the rotations of the energy's sites.
struct LevelState {
  Positions positions;
  Rotations rotations;
};

/// What an upsampler hands to the finer level, and so which step the finer level starts with.
enum class UpsampleOutput {
  kRotations,  ///< fine rotations are set: the finer level starts with a global step (Eq. 7)
  kPositions,  ///< fine positions are set: the finer level starts with a local step (Eq. 6)
};

/// Turns the solution on a coarse level into the initial state of the next finer level
/// (Section 5.1 of the paper).
///
/// Contract: `fine.coarse_vertex` maps fine vertices to `coarse` vertices (states and levels in
/// one numbering: the level cascade's, HierarchyLevel); `site` says whether
/// the rotations live on vertices or elements of each level. On return `fine_state.rotations`
/// has one rotation per fine site and `fine_state.positions` one row per fine vertex (both are
/// always filled: positions from the coarse solution by Eq. 6 where the output is rotations, so a
/// caller can look at them). Const and thread-safe.
class Upsampler {
 public:
  virtual ~Upsampler() = default;

  virtual UpsampleOutput output() const = 0;

  virtual void Upsample(const HierarchyLevel& fine, const HierarchyLevel& coarse, RotationSite site,
                        const LevelState& coarse_state, LevelState& fine_state,
                        const Context& context) const = 0;

  /// True when the rotations Upsample() produces at `site` are exactly each fine vertex's
  /// coarse vertex's rotation (HierarchyLevel::coarse_vertex; the identity for kNoVertex): no
  /// averaging, no smoothing. Up-sampling through several levels is then one gather along the
  /// composed vertex map (a session's Preview() goes straight from the coarsest level to the
  /// finest so).
  virtual bool RotationsFollowCoarseVertex(RotationSite /*site*/) const { return false; }

 protected:
  Upsampler() = default;
};

}  // namespace harap
