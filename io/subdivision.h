// SPDX-License-Identifier: MIT
#pragma once

#include "framework/mesh.h"

namespace harap {

#include <string>

/// `steps` rounds of Loop subdivision of any triangle mesh. Unreferenced vertices are dropped;
/// the mesh's vertices come first (in order), then one new vertex per edge.
/// - Manifold, consistently oriented input: OpenMesh's LoopT.
/// - Anything else (edges with 3 or more triangles, vertices where separate fans meet,
///   inconsistent orientation): harap's Loop variant on the indexed mesh (LoopSubdivideCreased),
///   and `*note` (if given) says so and why. Loop's rules hold wherever the mesh is manifold.
Mesh LoopSubdivide(const Mesh& mesh, int steps, std::string* note = nullptr);

/// Loop subdivision with non-manifold parts as creases (Hoppe et al. 1994's crease rules):
/// an edge with two triangles gets Loop's 3/8-1/8 stencil, any other edge (boundary: 1 triangle,
/// non-manifold: 3 or more) its midpoint; a vertex with no such crease edge and one fan of
/// triangles gets Loop's rule, one with exactly two crease edges the crease rule (3/4, 1/8, 1/8
/// along them), every other vertex (corners, several crease lines, several fans meeting) stays
/// where it is. On manifold meshes this is Loop's scheme with the usual boundary rules.
/// `non_manifold_edges` / `non_manifold_vertices` (if given) receive the counts of the input.
Mesh LoopSubdivideCreased(const Mesh& mesh, int steps, Index* non_manifold_edges = nullptr,
                          Index* non_manifold_vertices = nullptr);

}  // namespace harap
