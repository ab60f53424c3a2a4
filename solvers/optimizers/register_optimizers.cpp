// SPDX-License-Identifier: MIT
#include "solvers/optimizers/register_optimizers.h"

#include <memory>

#include "solvers/optimizers/admm_elements.h"
#include "solvers/optimizers/hierarchical_optimizer.h"
#include "solvers/optimizers/local_global_solver.h"

namespace harap {

namespace {

// The options parser of a one-level optimizer: level solver `inner` on the input mesh.
auto OneLevel(std::shared_ptr<const Registry<LevelSolver>> level_solvers, std::string_view inner) {
  return [level_solvers, inner = std::string(inner)](OptionReader node) {
    return HierarchicalOptimizer::Options::OneLevel(node, *level_solvers, inner);
  };
}

}  // namespace

void RegisterLevelSolvers(Registry<LevelSolver>& registry) {
  // Level solvers read their options from the optimizer's table, which the optimizer's parser
  // checks for unknown keys.
  registry.AddParsed<LocalGlobalSolver>(
      std::string(LocalGlobalSolver::kName),
      "local/global ARAP iterations [Sorkine & Alexa 2007] with optional Anderson "
      "acceleration or Newton steps; the paper's level solver",
      &ReadLocalGlobalOptions);
  registry.AddParsed<AdmmLevelSolver>(
      "admm_pd",
      "rotation-unaware ADMM for the per-element ARAP energy [Overby et al. 2017, ADMM "
      "⊇ Projective Dynamics]; energy `elements`",
      [](OptionReader node) { return ReadAdmmOptions(node, AdmmVariant::kProjectiveDynamics); });
  registry.AddParsed<AdmmLevelSolver>(
      "wrapd",
      "rotation-aware ADMM with an L-BFGS global step, WRAPD's ARAP mode [Brown & "
      "Narain 2021]; energy `elements`, tetrahedra",
      [](OptionReader node) { return ReadAdmmOptions(node, AdmmVariant::kRotationAware); });
}

void RegisterOptimizers(Registry<Optimizer>& registry, const Registry<LevelSolver>& level_solvers) {
  const auto solvers = std::make_shared<const Registry<LevelSolver>>(level_solvers);
  registry.AddParsed<HierarchicalOptimizer>(
      "classic",
      "classic single-level local/global ARAP [Sorkine & Alexa 2007], the paper's "
      "baseline (level solver local_global on the input mesh)",
      OneLevel(solvers, LocalGlobalSolver::kName));
  registry.AddParsed<HierarchicalOptimizer>(
      std::string(HierarchicalOptimizer::kName),
      "hierarchical (cascadic) ARAP: coarsest level first, rotations up-sampled level by "
      "level [Meyer, Bickel & Alexa, Algorithm 2]; any level solver (`inner`)",
      [solvers](OptionReader node) {
        return HierarchicalOptimizer::Options::FromConfig(node, *solvers);
      });
  // The flat ADMM optimizers: their level solvers on the input mesh.
  for (const char* admm : {"admm_pd", "wrapd"}) {
    registry.AddParsed<HierarchicalOptimizer>(
        admm, level_solvers.Description(admm) + " (on the input mesh)", OneLevel(solvers, admm));
  }
}

}  // namespace harap
