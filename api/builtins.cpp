// SPDX-License-Identifier: MIT
#include "api/builtins.h"

#include "energies/register_energies.h"
#include "hierarchies/builders/register_hierarchies.h"
#include "hierarchies/upsamplers/register_upsamplers.h"
#include "solvers/linear/register_solvers.h"
#include "solvers/optimizers/register_optimizers.h"

namespace harap {

Registries MakeBuiltinRegistries() {
  Registries registries;
  RegisterLevelSolvers(registries.level_solvers);
  RegisterOptimizers(registries.optimizers, registries.level_solvers);
  RegisterEnergies(registries.energies);
  RegisterLinearSolvers(registries.linear_solvers);
  RegisterHierarchies(registries.hierarchies);
  RegisterUpsamplers(registries.upsamplers);
  return registries;
}

}  // namespace harap
