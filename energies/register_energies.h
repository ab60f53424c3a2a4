// SPDX-License-Identifier: MIT
#pragma once

#include "framework/energy.h"
#include "framework/registry.h"

namespace harap {

/// Adds every Energy implementation of this module to `registry` (the module's one list).
void RegisterEnergies(Registry<Energy>& registry);

}  // namespace harap
