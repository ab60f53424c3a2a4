// SPDX-License-Identifier: MIT
#include "solvers/optimizers/register_optimizers.h"

#include <memory>

#include "solvers/optimizers/admm_elements.h"
#include "solvers/optimizers/hierarchical_optimizer.h"
#include "solvers/optimizers/local_global_solver.h"

namespace harap {

void RegisterLevelSolvers(Registry<LevelSolver>& registry) {
  registry.Add(std::string(LocalGlobalSolver::kName),
               "local/global ARAP iterations [Sorkine & Alexa 2007] with optional Anderson "
               "acceleration or Newton steps; the paper's level solver",
               &LocalGlobalSolver::Create);
  registry.Add("admm_pd",
               "rotation-unaware ADMM for the per-element ARAP energy [Overby et al. 2017, ADMM "
               "⊇ Projective Dynamics]; energy `elements`",
               &AdmmLevelSolver::CreateAdmmPd);
  registry.Add("wrapd",
               "rotation-aware ADMM with an L-BFGS global step, WRAPD's ARAP mode [Brown & "
               "Narain 2021]; energy `elements`, tetrahedra",
               &AdmmLevelSolver::CreateWrapd);
}

void RegisterOptimizers(Registry<Optimizer>& registry, const Registry<LevelSolver>& level_solvers) {
  const auto solvers = std::make_shared<const Registry<LevelSolver>>(level_solvers);
  registry.Add("classic",
               "classic single-level local/global ARAP [Sorkine & Alexa 2007], the paper's "
               "baseline (level solver local_global on the input mesh)",
               HierarchicalOptimizer::OneLevelFactory(solvers, "local_global"));
  registry.Add(std::string(HierarchicalOptimizer::kName),
               "hierarchical (cascadic) ARAP: coarsest level first, rotations up-sampled level by "
               "level [Meyer, Bickel & Alexa, Algorithm 2]; any level solver (`inner`)",
               HierarchicalOptimizer::Factory(solvers));
  // The flat ADMM optimizers: their level solvers on the input mesh.
  for (const char* admm : {"admm_pd", "wrapd"}) {
    registry.Add(admm, level_solvers.Description(admm) + " (on the input mesh)",
                 HierarchicalOptimizer::OneLevelFactory(solvers, admm));
  }
}

}  // namespace harap
