// SPDX-License-Identifier: MIT
#include "hierarchies/upsamplers/register_upsamplers.h"

#include "hierarchies/upsamplers/cell_upsampler.h"

namespace harap {

namespace {

// The options parser of the up-sampler registered in `mode`.
auto ParseMode(CellUpsampler::Mode mode) {
  return [mode](OptionReader node) { return CellUpsampler::Options::FromConfig(node, mode); };
}

}  // namespace

void RegisterUpsamplers(Registry<Upsampler>& registry) {
  registry.AddParsed<CellUpsampler>(
      std::string(CellUpsampler::kRotationsName),
      "coarse cell rotations to the fine vertices (Eq. 7); the finer level starts with "
      "a global solve (default)",
      ParseMode(CellUpsampler::Mode::kRotations));
  registry.AddParsed<CellUpsampler>(
      std::string(CellUpsampler::kPositionsName),
      "fine positions moved rigidly with their coarse cell (Eq. 6); the finer level "
      "starts with a local step",
      ParseMode(CellUpsampler::Mode::kPositions));
  registry.AddParsed<CellUpsampler>(
      std::string(CellUpsampler::kSmoothedRotationsName),
      "rotations as 'rotations', then averaged over the fine 1-ring and projected to "
      "SO(3) (Fig. 16)",
      ParseMode(CellUpsampler::Mode::kSmoothedRotations));
}

}  // namespace harap
