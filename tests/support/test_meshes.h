// SPDX-License-Identifier: MIT
#pragma once

#include <utility>
#include <vector>

#include "framework/mesh.h"
#include "framework/optimizer.h"

namespace harap::testing {

/// A regular grid of nx×ny vertices on [0,1]² (z = 0), each quad split into two triangles.
Mesh Grid(int nx, int ny);

/// Grid(nx, ny) marked planar: a 2D triangle mesh (z = 0) for the per-element energy.
Mesh PlanarGrid(int nx, int ny);

/// A box of nx×ny×nz vertices on [0,1]³, each grid cube split into `tets_per_cube` = 6
/// tetrahedra around its main diagonal (Kuhn) or 5 (a middle tetrahedron and four corners,
/// mirrored in a checkerboard so faces match). Every tetrahedron is positively oriented.
Mesh TetBox(int nx, int ny, int nz, int tets_per_cube = 6);

/// The mesh with every vertex moved by a deterministic random offset of up to `amount` × the
/// smallest grid spacing 1/(n−1) of `n` (in the plane for planar meshes): irregular elements,
/// obtuse angles and negative cotangent weights, still valid for amount < ~0.25.
Mesh Jittered(Mesh mesh, int n, double amount, unsigned seed);

/// The mesh with its vertices in a deterministic random order: input vertex v becomes
/// (*moved_to)[v] if given; the elements keep their order and the order of their corners.
Mesh Shuffled(Mesh mesh, unsigned seed, std::vector<Index>* moved_to = nullptr);

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
/// `tube`'s hard handles plus `groups` soft groups of 3 consecutive vertices on its side (away
/// from the end rings of `segments` vertices), each pulled outwards by 5% of its distance from
/// the axis with weights 0.5, 1.5, ..., 4.5 in turn; where the groups go is drawn from `seed`.
Constraints WithSoftGroups(const BentTube& tube, int segments, int groups, unsigned seed);

/// A TetBox(nx, ny, nz) stretched to `height` along z, its bottom layer fixed and its top layer
/// turned by `angle` about the box's vertical axis: a twisting problem for the per-element energy.
struct TwistedTetBar {
  TwistedTetBar(int nx, int ny, int nz, double height, double angle);
  TwistedTetBar(const TwistedTetBar&) = delete;  // problem.mesh points at mesh
  TwistedTetBar& operator=(const TwistedTetBar&) = delete;

  Mesh mesh;
  DeformationProblem problem;
};

/// A PlanarGrid(nx, ny), its left column (x = 0) fixed and its right column (x = 1) moved by
/// `shift` in the plane: an in-plane shearing problem for the per-element energy.
struct ShearedPlanarGrid {
  ShearedPlanarGrid(int nx, int ny, const Eigen::Vector2d& shift);
  ShearedPlanarGrid(const ShearedPlanarGrid&) = delete;
  ShearedPlanarGrid& operator=(const ShearedPlanarGrid&) = delete;

  Mesh mesh;
  DeformationProblem problem;
};

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
