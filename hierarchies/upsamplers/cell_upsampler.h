// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/upsampler.h"

namespace harap {

/// The paper's up-samplers (Section 5.1, Fig. 16), which all transfer per cell: a coarse vertex
/// stands for the fine vertices of its octree cell (or, for dropped vertices, the closest
/// surviving one). Registered under three names:
///   - `rotations` (Eq. 7, the default): each fine vertex takes its cell's rotation; the finer
///     level starts with a global step.
///   - `positions` (Eq. 6): fine positions move rigidly with their cell,
///     u_j = u_i + R_i (v̄_j − v̄_i); the finer level starts with a local step.
///   - `smoothed_rotations`: as `rotations`, then each fine rotation is averaged with its 1-ring
///     and projected to the nearest rotation, `passes` times.
/// Per-element energies (Section 6) go through vertex rotations: Eq. (11) to average element
/// rotations to vertices, Eq. (12) back to the fine elements.
class CellUpsampler final : public Upsampler {
 public:
  static constexpr std::string_view kRotationsName = "rotations";
  static constexpr std::string_view kPositionsName = "positions";
  static constexpr std::string_view kSmoothedRotationsName = "smoothed_rotations";

  enum class Mode { kRotations, kPositions, kSmoothedRotations };

  struct Options {
    Mode mode = Mode::kRotations;
    int passes = 1;  ///< smoothed_rotations only: smoothing passes over the fine 1-ring (>= 1).
    static Options FromConfig(OptionReader node, Mode mode);
  };

  explicit CellUpsampler(const Options& options) : options_(options) {}

  UpsampleOutput output() const override {
    return options_.mode == Mode::kPositions ? UpsampleOutput::kPositions
                                             : UpsampleOutput::kRotations;
  }
  void Upsample(const HierarchyLevel& fine, const HierarchyLevel& coarse, RotationSite site,
                const LevelState& coarse_state, LevelState& fine_state,
                const Context& context) const override;
  /// "rotations" at vertex sites: the prolonged rotations are the coarse vertex's, copied
  /// (elements average the vertex rotations, "smoothed_rotations" smooths them).
  bool RotationsFollowCoarseVertex(RotationSite site) const override {
    return options_.mode == Mode::kRotations && site == RotationSite::kVertex;
  }

 private:
  Options options_;
};

}  // namespace harap
