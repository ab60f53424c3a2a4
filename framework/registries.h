// SPDX-License-Identifier: MIT
#pragma once

#include "framework/energy.h"
#include "framework/hierarchy.h"
#include "framework/level_solver.h"
#include "framework/linear_solver.h"
#include "framework/optimizer.h"
#include "framework/registry.h"
#include "framework/upsampler.h"

namespace harap {

/// One registry per plug point. Filled by each module's register function, called only from the
/// composition root (api/builtins.cpp); tests may build their own.
struct Registries {
  Registry<Optimizer> optimizers{"optimizer"};
  /// Per-level solvers of the optimizers (`optimizer.inner`). The optimizers keep a copy of it
  /// as it was when they were registered (RegisterOptimizers), so register level solvers first.
  Registry<LevelSolver> level_solvers{"level solver"};
  Registry<Energy> energies{"energy"};
  Registry<LinearSolver> linear_solvers{"solver"};
  Registry<Hierarchy> hierarchies{"hierarchy"};
  Registry<Upsampler> upsamplers{"upsampler"};
};

}  // namespace harap
