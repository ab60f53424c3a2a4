// SPDX-License-Identifier: MIT
#pragma once

#include <vector>

#include "framework/context.h"
#include "framework/mesh.h"

namespace harap {

/// One level of a nested mesh hierarchy (the paper's T_l, V_l).
///
/// Numbering: Hierarchy::Build returns level 0 as the input mesh, in the input's numbering, and
/// each coarse level in the order the builder made it. The optimizers' level cascade renumbers
/// every level once for memory locality (solvers/optimizers/level_cascade.h): the hierarchy it
/// stores, the upsamplers' states and the level solvers' states and constraints are all in that
/// level numbering, and only the cascade's users map to and from the input's numbering.
struct HierarchyLevel {
  /// The level's rest mesh: its own compact vertex set (coarse rest positions) and elements
  /// indexing it. Level 0 is the input mesh itself (renumbered in a cascade).
  Mesh mesh;

  /// For each vertex of this level, the vertex of the next coarser level (l+1) that represents it
  /// (the paper's i ~_l j). Vertices whose cluster did not survive to level l+1 map to the
  /// closest surviving coarse vertex in this level's vertex–edge graph; vertices with no path to
  /// any surviving vertex map to kNoVertex. Empty on the coarsest level.
  std::vector<Index> coarse_vertex;

  /// For each vertex of this level: 1 if coarse_vertex is its own cluster, 0 if it is the
  /// closest-surviving substitute (or kNoVertex). Empty on the coarsest level.
  std::vector<unsigned char> in_cluster;
};

/// The levels, finest first: levels[0] is the input mesh, levels.back() the coarsest (numbering:
/// see HierarchyLevel).
struct MeshHierarchy {
  std::vector<HierarchyLevel> levels;

  int num_levels() const { return static_cast<int>(levels.size()); }
  /// The vertex of level `level` that finest-level vertex `vertex` maps to (composing the maps),
  /// or kNoVertex.
  Index MapFinestVertex(Index vertex, int level) const {
    for (int l = 0; l < level && vertex != kNoVertex; ++l) vertex = levels[l].coarse_vertex[vertex];
    return vertex;
  }
};

/// Builds a nested hierarchy of coarser meshes (octree clustering, edge collapse, ...).
///
/// Contract: the result has at least one level; levels[0].mesh equals the input; every level's
/// coarse_vertex map has one entry per vertex of that level. Build() is const and may be called
/// for several meshes.
class Hierarchy {
 public:
  virtual ~Hierarchy() = default;
  virtual MeshHierarchy Build(const Mesh& mesh, const Context& context) const = 0;

 protected:
  Hierarchy() = default;
};

}  // namespace harap
