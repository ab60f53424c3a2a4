// SPDX-License-Identifier: MIT
#pragma once

#include "framework/mesh.h"
#include "framework/optimizer.h"

namespace harap::testing {

/// A regular grid of nx×ny vertices on [0,1]² (z = 0), each quad split into two triangles.
Mesh Grid(int nx, int ny);

/// A closed, subdivided icosahedron of unit radius (`subdivisions` = 0 gives 12 vertices).
Mesh Icosphere(int subdivisions);

/// An open tube of radius 0.25 along z (length 1) with `rings` × `segments` vertices.
Mesh Tube(int rings, int segments);

/// A Tube(rings, segments) stretched to `height`, its bottom ring fixed and its top ring turned by
/// `angle` about the x axis and shifted by `shift`: a bending problem for the optimizers.
struct BentTube {
  BentTube(int rings, int segments, double height, double angle, const Eigen::Vector3d& shift);
  BentTube(const BentTube&) = delete;  // problem.mesh points at mesh
  BentTube& operator=(const BentTube&) = delete;

  Mesh mesh;
  DeformationProblem problem;
};

/// Two meshes side by side in one (vertex indices of `b` shifted).
Mesh Concatenate(const Mesh& a, const Mesh& b);

/// A random rotation (deterministic for `seed`).
Eigen::Matrix3d RandomRotation(unsigned seed);

/// Rest positions moved by a smooth non-rigid map (bend + twist) of strength `amount`.
Positions SmoothlyDeformed(const Positions& rest, double amount);

}  // namespace harap::testing
