// SPDX-License-Identifier: MIT
#pragma once

#include <utility>
#include <vector>

#include "framework/mesh.h"

namespace harap::testing {

/// A regular grid of nx×ny vertices on [0,1]² (z = 0), each quad split into two triangles.
Mesh Grid(int nx, int ny);

/// A closed, subdivided icosahedron of unit radius (`subdivisions` = 0 gives 12 vertices).
Mesh Icosphere(int subdivisions);

/// An open tube of radius 0.25 along z (length 1) with `rings` × `segments` vertices.
Mesh Tube(int rings, int segments);

/// Grid(n, n) (n odd) cut along x = 0.5 into two halves that share positions but no vertex index,
/// an unwelded seam as in the shared teapot. `seam` receives the (copy, original) vertex pairs.
Mesh SeamedGrid(int n, std::vector<std::pair<Index, Index>>& seam);

/// Two meshes side by side in one (vertex indices of `b` shifted).
Mesh Concatenate(const Mesh& a, const Mesh& b);

/// A random rotation (deterministic for `seed`).
Eigen::Matrix3d RandomRotation(unsigned seed);

/// Rest positions moved by a smooth non-rigid map (bend + twist) of strength `amount`.
Positions SmoothlyDeformed(const Positions& rest, double amount);

}  // namespace harap::testing
