// SPDX-License-Identifier: MIT
#pragma once

#include "framework/types.h"

namespace harap {

/// Area-weighted unit vertex normals of the triangles `triangles` at `positions` (each triangle
/// adds its cross product, twice its area along its normal, to its corners): zero for a vertex
/// without a non-degenerate triangle.
Positions VertexNormals(const Positions& positions, const Elements& triangles);

}  // namespace harap
