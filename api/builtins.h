// SPDX-License-Identifier: MIT
#pragma once

#include "framework/registries.h"

namespace harap {

/// Every built-in optimizer, energy, solver, hierarchy and upsampler, registered by name. The
/// only caller of the modules' register functions (tests and benchmarks call this too).
Registries MakeBuiltinRegistries();

}  // namespace harap
