// SPDX-License-Identifier: MIT
#pragma once

#include <array>
#include <string_view>
#include <vector>

#include "framework/mesh.h"
#include "framework/types.h"

namespace harap {

/// For each triangle f = (v0, v1, v2), the positions in `pattern.valuePtr()` of the nine entries
/// (row v_a, column v_b), stored at index 3·a + b, so per-face assembly scatters without searching.
std::vector<std::array<Index, 9>> TriangleEntryPositions(const SparseMatrix& pattern,
                                                         const Elements& triangles);

/// Throws InputError unless `mesh` is a triangle mesh (surface energies), naming the energy.
void RequireTriangleMesh(const Mesh& mesh, std::string_view energy_name);

}  // namespace harap
