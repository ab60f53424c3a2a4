// SPDX-License-Identifier: MIT
#pragma once

#include "framework/registry.h"
#include "framework/upsampler.h"

namespace harap {

/// Adds every Upsampler implementation of this module to `registry` (the module's one list).
void RegisterUpsamplers(Registry<Upsampler>& registry);

}  // namespace harap
