// SPDX-License-Identifier: MIT
#include "solvers/optimizers/register_optimizers.h"

#include "solvers/optimizers/classic_optimizer.h"
#include "solvers/optimizers/hierarchical_optimizer.h"

namespace harap {

void RegisterOptimizers(Registry<Optimizer>& registry) {
  registry.Add(std::string(ClassicOptimizer::kName),
               "classic single-level local/global ARAP [Sorkine & Alexa 2007], the paper's "
               "baseline",
               &ClassicOptimizer::Create);
  registry.Add(std::string(HierarchicalOptimizer::kName),
               "hierarchical (cascadic) ARAP: coarsest level first, rotations up-sampled level by "
               "level [Meyer, Bickel & Alexa, Algorithm 2]",
               &HierarchicalOptimizer::Create);
}

}  // namespace harap
