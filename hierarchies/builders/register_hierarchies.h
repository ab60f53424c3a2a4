// SPDX-License-Identifier: MIT
#pragma once

#include "framework/hierarchy.h"
#include "framework/registry.h"

namespace harap {

/// Adds every Hierarchy implementation of this module to `registry` (the module's one list).
void RegisterHierarchies(Registry<Hierarchy>& registry);

}  // namespace harap
