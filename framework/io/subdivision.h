// SPDX-License-Identifier: MIT
#pragma once

#include "framework/mesh.h"

namespace harap {

/// `steps` rounds of Loop subdivision (OpenMesh's LoopT). Needs a manifold triangle mesh; other
/// input throws InputError saying so. Unreferenced vertices are dropped.
Mesh LoopSubdivide(const Mesh& mesh, int steps);

}  // namespace harap
