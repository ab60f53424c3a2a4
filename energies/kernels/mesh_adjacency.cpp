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
  std::vector<Index> mirror(a.nonZeros());
  tbb::parallel_for(tbb::blocked_range<Index>(0, static_cast<Index>(a.outerSize()), 1024),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index col = range.begin(); col != range.end(); ++col) {
                        for (Index p = a.outerIndexPtr()[col]; p < a.outerIndexPtr()[col + 1];
                             ++p) {
                          mirror[p] = EntryPosition(a, col, a.innerIndexPtr()[p]);
                        }
                      }
                    });
  return mirror;
}

}  // namespace harap
