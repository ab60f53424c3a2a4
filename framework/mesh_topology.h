// SPDX-License-Identifier: MIT
#pragma once

#include <vector>

#include "framework/types.h"

namespace harap {

/// Which elements each vertex belongs to, in compressed rows (the one vertex → element incidence
/// the energies, up-samplers and optimizers share instead of each counting it again).
///
/// The corners around vertex v are corners[p] for p in [offsets[v], offsets[v + 1]), in element
/// order; corner c = t · simplex_size + k is the k-th vertex of element t. Vertices no element
/// references have an empty range.
///
///   const VertexIncidence incidence = VertexIncidence::Build(mesh.num_vertices(), mesh.elements);
///   for (Index p = incidence.offsets[v]; p < incidence.offsets[v + 1]; ++p)
///     sum += rotations[incidence.element(p)];
struct VertexIncidence {
  int simplex_size = 0;
  std::vector<Index> offsets;  ///< num_vertices + 1 entries
  std::vector<Index> corners;  ///< one per corner of every element

  /// The element and the corner within it of entry p of `corners`.
  Index element(Index p) const { return corners[p] / simplex_size; }
  int corner(Index p) const { return corners[p] % simplex_size; }
  Index num_vertices() const { return static_cast<Index>(offsets.size()) - 1; }

  /// A counting sort of the corners by vertex: O(#corners), no per-vertex allocation.
  static VertexIncidence Build(Index num_vertices, const Elements& elements);
};

/// The vertices that share an element with each vertex (the 1-ring, or "i and j are adjacent"),
/// in compressed rows: neighbors[p] for p in [offsets[v], offsets[v + 1]), sorted and distinct.
/// With `include_self` every vertex (also unreferenced ones) is its own neighbour: the sparsity
/// pattern of every global-step matrix (diagonal included).
struct VertexAdjacency {
  std::vector<Index> offsets;  ///< num_vertices + 1 entries
  std::vector<Index> neighbors;

  Index num_vertices() const { return static_cast<Index>(offsets.size()) - 1; }

  /// Parallel (TBB) per-vertex sorting in the caller's task arena; deterministic.
  static VertexAdjacency Build(Index num_vertices, const Elements& elements, bool include_self);
};

/// The boundary triangles of a tetrahedral mesh (faces of exactly one tetrahedron), oriented
/// outwards for positively oriented tetrahedra, in the order of their tetrahedra.
Elements BoundaryTriangles(const Elements& tetrahedra);

}  // namespace harap
