// SPDX-License-Identifier: MIT
#include "energies/kernels/mesh_adjacency.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "framework/error.h"
#include "framework/mesh_topology.h"

namespace harap {

SparseMatrix AdjacencyPattern(Index num_vertices, const Elements& elements) {
  const VertexAdjacency adjacency =
      VertexAdjacency::Build(num_vertices, elements, /*include_self=*/true);
  SparseMatrix pattern(num_vertices, num_vertices);
  pattern.resizeNonZeros(static_cast<Index>(adjacency.neighbors.size()));
  std::copy(adjacency.offsets.begin(), adjacency.offsets.end(), pattern.outerIndexPtr());
  std::copy(adjacency.neighbors.begin(), adjacency.neighbors.end(), pattern.innerIndexPtr());
  std::fill_n(pattern.valuePtr(), adjacency.neighbors.size(), 0.0);
  return pattern;
}

Index EntryPosition(const SparseMatrix& a, Index row, Index col) {
  const Index* begin = a.innerIndexPtr() + a.outerIndexPtr()[col];
  const Index* end = a.innerIndexPtr() + a.outerIndexPtr()[col + 1];
  const Index* it = std::lower_bound(begin, end, row);
  HARAP_CHECK(it != end && *it == row, "entry ({}, {}) is not in the sparsity pattern", row, col);
  return static_cast<Index>(it - a.innerIndexPtr());
}

std::vector<Index> TransposePositions(const SparseMatrix& a) {
  // Walking the columns in order, the rows of column r that point back are met in ascending
  // order too, so a cursor per column finds each mirror entry in O(1) (a symmetric pattern;
  // one without the mirror entry fails the check, as EntryPosition would).
  const Index n = static_cast<Index>(a.outerSize());
  const Index* outer = a.outerIndexPtr();
  const Index* inner = a.innerIndexPtr();
  std::vector<Index> mirror(a.nonZeros(), 0);
  std::vector<Index> cursor(outer, outer + n);
  for (Index col = 0; col < n; ++col) {
    const auto [begin, end] = ColumnRange(a, col);
    for (Index p = begin; p < end; ++p) {
      const Index row = inner[p];
      Index& q = cursor[row];
      HARAP_CHECK(q < ColumnRange(a, row).second && inner[q] == col,
                  "entry ({}, {}) is not in the sparsity pattern", col, row);
      mirror[p] = q++;
    }
  }
  return mirror;
}

}  // namespace harap
