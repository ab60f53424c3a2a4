// SPDX-License-Identifier: MIT
#include "framework/level_solver.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "framework/error.h"

namespace harap {

void GatherRotations(const std::vector<Index>& source, const Rotations& gathered, Rotations& out,
                     const Context& context) {
  out.resize(source.size());
  context.Run([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, source.size(), 4096),
                      [&](const tbb::blocked_range<size_t>& range) {
                        for (size_t v = range.begin(); v != range.end(); ++v) {
                          const Index c = source[v];
                          out[v] = c == kNoVertex ? Rotation::Identity() : gathered[c];
                        }
                      });
  });
}

LevelSolveResult LevelSolver::GlobalStepFromGathered(LevelState& /*state*/,
                                                     const std::vector<Index>& /*source*/,
                                                     const Rotations& /*coarse*/,
                                                     const Context& /*context*/) {
  throw InputError("this level solver takes no gathered rotations (accepts_gathered_rotations)");
}

}  // namespace harap
