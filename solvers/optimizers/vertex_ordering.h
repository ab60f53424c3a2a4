// SPDX-License-Identifier: MIT
#pragma once

#include <vector>

#include "framework/hierarchy.h"
#include "framework/mesh.h"

namespace harap {

/// A renumbering of a mesh for memory locality: vertices sorted along a Morton (z-order) curve of
/// their rest positions, elements by their smallest new vertex index. The local step and the
/// right-hand side gather data of neighbouring vertices and sites; in file order (e.g. after Loop
/// subdivision, which appends edge vertices after the original ones) neighbours sit megabytes
/// apart and those gathers are cache misses. Measured on the 173K armadillo: see
/// docs/benchmarks.md.
struct MeshOrdering {
  std::vector<Index> old_vertex;   ///< new index → input index
  std::vector<Index> new_vertex;   ///< input index → new index
  std::vector<Index> old_element;  ///< new element index → input element index
  std::vector<Index> new_element;  ///< input element index → new element index
  Mesh mesh;                       ///< the renumbered mesh

  /// Rows of `input` (#V×k, input order) in the new order (in parallel, like ToOld).
  Positions ToNew(const Positions& input) const;
  /// Rows of `renumbered` in the input order, into `out` (resized if needed; no allocation when
  /// it has the size already: a session maps every frame's result out). In parallel: call it
  /// inside the run's Context::Run.
  void ToOld(const Positions& renumbered, Positions& out) const;
};

MeshOrdering LocalityOrdering(const Mesh& mesh);

/// Renumbers a hierarchy built on the input mesh (Hierarchy::Build) for locality: level 0 by
/// `finest` (LocalityOrdering of the input mesh), every coarse level by its own
/// LocalityOrdering; the vertex maps between the levels follow. Each level's mesh is then what
/// LocalityOrdering makes of the level as built, so the level solvers' arithmetic does not depend
/// on where the renumbering happens. Returns, per coarse level, index as built → new index (empty
/// for level 0: that is finest.new_vertex).
std::vector<std::vector<Index>> RenumberForLocality(const MeshOrdering& finest,
                                                    MeshHierarchy& hierarchy);

}  // namespace harap
