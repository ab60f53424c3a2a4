// SPDX-License-Identifier: MIT
#include "energies/kernels/mesh_adjacency.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "framework/error.h"

namespace harap {

SparseMatrix AdjacencyPattern(Index num_vertices, const Elements& elements) {
  const int size = static_cast<int>(elements.cols());
  const Index num_elements = static_cast<Index>(elements.rows());
  // Counting sort of the (row, col) pairs by column: 1 + size·(size−1) entries per element at
  // most per column, then sort/unique each short column. Much faster than triplets for
  // million-vertex meshes.
  std::vector<Index> count(num_vertices + 1, 0);
  for (Index e = 0; e < num_elements; ++e) {
    for (int a = 0; a < size; ++a) count[elements(e, a) + 1] += size - 1;
  }
  for (Index v = 0; v < num_vertices; ++v) count[v + 1] += count[v] + 1;  // +1: the diagonal
  std::vector<Index> rows(count[num_vertices]);
  std::vector<Index> fill(count.begin(), count.end() - 1);
  for (Index v = 0; v < num_vertices; ++v) rows[fill[v]++] = v;
  for (Index e = 0; e < num_elements; ++e) {
    for (int a = 0; a < size; ++a) {
      const Index col = elements(e, a);
      for (int b = 0; b < size; ++b) {
        if (b != a) rows[fill[col]++] = elements(e, b);
      }
    }
  }
  std::vector<Index> unique_count(num_vertices);
  tbb::parallel_for(tbb::blocked_range<Index>(0, num_vertices, 1024),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index v = range.begin(); v != range.end(); ++v) {
                        auto begin = rows.begin() + count[v], end = rows.begin() + count[v + 1];
                        std::sort(begin, end);
                        unique_count[v] = static_cast<Index>(std::unique(begin, end) - begin);
                      }
                    });
  SparseMatrix pattern(num_vertices, num_vertices);
  Index nnz = 0;
  for (Index v = 0; v < num_vertices; ++v) nnz += unique_count[v];
  pattern.resizeNonZeros(nnz);
  Index* outer = pattern.outerIndexPtr();
  outer[0] = 0;
  for (Index v = 0; v < num_vertices; ++v) outer[v + 1] = outer[v] + unique_count[v];
  tbb::parallel_for(tbb::blocked_range<Index>(0, num_vertices, 1024),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index v = range.begin(); v != range.end(); ++v) {
                        std::copy_n(rows.begin() + count[v], unique_count[v],
                                    pattern.innerIndexPtr() + outer[v]);
                        std::fill_n(pattern.valuePtr() + outer[v], unique_count[v], 0.0);
                      }
                    });
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
