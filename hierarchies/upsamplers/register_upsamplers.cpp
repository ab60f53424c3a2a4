// SPDX-License-Identifier: MIT
#include "hierarchies/upsamplers/register_upsamplers.h"

#include "hierarchies/upsamplers/cell_upsampler.h"

namespace harap {

void RegisterUpsamplers(Registry<Upsampler>& registry) {
  registry.Add(std::string(CellUpsampler::kRotationsName),
               "coarse cell rotations to the fine vertices (Eq. 7); the finer level starts with "
               "a global solve (default)",
               &CellUpsampler::CreateRotations);
  registry.Add(std::string(CellUpsampler::kPositionsName),
               "fine positions moved rigidly with their coarse cell (Eq. 6); the finer level "
               "starts with a local step",
               &CellUpsampler::CreatePositions);
  registry.Add(std::string(CellUpsampler::kSmoothedRotationsName),
               "rotations as 'rotations', then averaged over the fine 1-ring and projected to "
               "SO(3) (Fig. 16)",
               &CellUpsampler::CreateSmoothedRotations);
}

}  // namespace harap
