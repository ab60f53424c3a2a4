// SPDX-License-Identifier: MIT
#pragma once

#include "framework/level_solver.h"
#include "framework/optimizer.h"
#include "framework/registry.h"

namespace harap {

/// Adds every LevelSolver implementation of this module to `registry` (`optimizer.inner`).
void RegisterLevelSolvers(Registry<LevelSolver>& registry);

/// Adds every Optimizer implementation of this module to `registry`. The optimizers create their
/// level solvers from a copy of `level_solvers` as it is now: register those first.
void RegisterOptimizers(Registry<Optimizer>& registry, const Registry<LevelSolver>& level_solvers);

}  // namespace harap
