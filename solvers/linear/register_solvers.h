// SPDX-License-Identifier: MIT
#pragma once

#include "framework/linear_solver.h"
#include "framework/registry.h"

namespace harap {

/// Adds every LinearSolver implementation of this module to `registry` (the module's one list).
void RegisterLinearSolvers(Registry<LinearSolver>& registry);

}  // namespace harap
