// SPDX-License-Identifier: MIT
#include "tests/support/level_energies.h"

#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

namespace harap::testing {

void LevelEnergies::Record(Context& context) {
  context.iteration_callback = [this](const IterationSummary& s) {
    by_level[s.level].push_back(s.energy);
    return CallbackAction::kContinue;
  };
}

OptimizeResult LevelEnergies::RunHierarchicalWithFixedTargets(const DeformationProblem& problem,
                                                              int min_vertices,
                                                              const std::string& tables) {
  const TestSetup setup(fmt::format(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-7\ntargets_follow_rotations = false\n"
      "[hierarchy]\nmin_vertices = {}\n{}",
      min_vertices, tables));
  Context context;
  Record(context);
  return setup.MakeOptimizer()->Optimize(problem, setup.factory, context);
}

bool LevelEnergies::MonotonePerLevel() const {
  for (const auto& [level, trace] : by_level) {
    for (size_t i = 1; i < trace.size(); ++i) {
      if (trace[i] > trace[i - 1] * (1.0 + 1e-12) + 1e-15) return false;
    }
  }
  return true;
}

}  // namespace harap::testing
