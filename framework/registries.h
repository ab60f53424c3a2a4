// SPDX-License-Identifier: MIT
#pragma once

#include "framework/energy.h"
#include "framework/hierarchy.h"
#include "framework/linear_solver.h"
#include "framework/optimizer.h"
#include "framework/registry.h"
#include "framework/upsampler.h"

namespace harap {

/// One registry per plug point. Filled by each module's register function, called only from the
/// composition root (experiments/builtins.cpp); tests may build their own.
struct Registries {
  Registry<Optimizer> optimizers{"optimizer"};
  Registry<Energy> energies{"energy"};
  Registry<LinearSolver> linear_solvers{"solver"};
  Registry<Hierarchy> hierarchies{"hierarchy"};
  Registry<Upsampler> upsamplers{"upsampler"};
};

}  // namespace harap
