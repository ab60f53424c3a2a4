// SPDX-License-Identifier: MIT
#include "hierarchies/upsamplers/cell_upsampler.h"

#include "framework/error.h"
#include "hierarchies/upsamplers/upsampling.h"

namespace harap {

CellUpsampler::Options CellUpsampler::Options::FromConfig(OptionReader node, Mode mode) {
  Options options;
  options.mode = mode;
  if (mode == Mode::kSmoothedRotations) {
    options.passes = node.Get("passes", options.passes,
                              "smoothing passes: average over the fine 1-ring, project to SO(3)",
                              Range::AtLeast(1));
  }
  node.RejectUnknownKeys();
  return options;
}

void CellUpsampler::Upsample(const HierarchyLevel& fine, const HierarchyLevel& coarse,
                             RotationSite site, const LevelState& coarse_state,
                             LevelState& fine_state, const Context& context) const {
  const int passes = options_.mode == Mode::kSmoothedRotations ? options_.passes : 0;
  UpsampleCells(fine, coarse, site, coarse_state, passes, fine_state, context);
}

}  // namespace harap
