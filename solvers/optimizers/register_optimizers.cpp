// SPDX-License-Identifier: MIT
#include "solvers/optimizers/register_optimizers.h"

#include "solvers/optimizers/admm_pd_optimizer.h"
#include "solvers/optimizers/classic_optimizer.h"
#include "solvers/optimizers/hierarchical_optimizer.h"
#include "solvers/optimizers/wrapd_optimizer.h"

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
  registry.Add(std::string(AdmmPdOptimizer::kName),
               "rotation-unaware ADMM for the per-element ARAP energy [Overby et al. 2017, ADMM "
               "⊇ Projective Dynamics]; energy `elements`",
               &AdmmPdOptimizer::Create);
  registry.Add(std::string(WrapdOptimizer::kName),
               "rotation-aware ADMM with an L-BFGS global step, WRAPD's ARAP mode [Brown & "
               "Narain 2021]; energy `elements`, tetrahedra",
               &WrapdOptimizer::Create);
}

}  // namespace harap
