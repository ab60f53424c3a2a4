// SPDX-License-Identifier: MIT
#pragma once

#include "framework/optimizer.h"
#include "framework/registry.h"

namespace harap {

/// Adds every Optimizer implementation of this module to `registry` (the module's one list).
void RegisterOptimizers(Registry<Optimizer>& registry);

}  // namespace harap
