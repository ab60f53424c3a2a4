// SPDX-License-Identifier: MIT
#include "framework/mesh_topology.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace harap {

VertexIncidence VertexIncidence::Build(Index num_vertices, const Elements& elements) {
  VertexIncidence incidence;
  incidence.simplex_size = static_cast<int>(elements.cols());
  const Index* corner_vertex = elements.data();  // row-major: corner c is entry c
  const Index num_corners = static_cast<Index>(elements.size());
  incidence.offsets.assign(num_vertices + 1, 0);
  for (Index c = 0; c < num_corners; ++c) ++incidence.offsets[corner_vertex[c] + 1];
  for (Index v = 0; v < num_vertices; ++v) incidence.offsets[v + 1] += incidence.offsets[v];
  incidence.corners.resize(num_corners);
  std::vector<Index> fill(incidence.offsets.begin(), incidence.offsets.end() - 1);
  for (Index c = 0; c < num_corners; ++c) incidence.corners[fill[corner_vertex[c]]++] = c;
  return incidence;
}

VertexAdjacency VertexAdjacency::Build(Index num_vertices, const Elements& elements,
                                       bool include_self) {
  const int size = static_cast<int>(elements.cols());
  const Index num_elements = static_cast<Index>(elements.rows());
  // Counting sort of the (vertex, neighbour) pairs by vertex: size − 1 per corner (+ the vertex
  // itself), then sort/unique each short row in parallel. Much faster than a vector per vertex
  // or triplets for million-vertex meshes.
  const Index self = include_self ? 1 : 0;
  std::vector<Index> count(num_vertices + 1, 0);
  for (Index e = 0; e < num_elements; ++e) {
    for (int a = 0; a < size; ++a) count[elements(e, a) + 1] += size - 1;
  }
  for (Index v = 0; v < num_vertices; ++v) count[v + 1] += count[v] + self;
  std::vector<Index> rows(count[num_vertices]);
  std::vector<Index> fill(count.begin(), count.end() - 1);
  if (include_self) {
    for (Index v = 0; v < num_vertices; ++v) rows[fill[v]++] = v;
  }
  for (Index e = 0; e < num_elements; ++e) {
    for (int a = 0; a < size; ++a) {
      const Index v = elements(e, a);
      for (int b = 0; b < size; ++b) {
        if (b != a) rows[fill[v]++] = elements(e, b);
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
  VertexAdjacency adjacency;
  adjacency.offsets.assign(num_vertices + 1, 0);
  for (Index v = 0; v < num_vertices; ++v) {
    adjacency.offsets[v + 1] = adjacency.offsets[v] + unique_count[v];
  }
  adjacency.neighbors.resize(adjacency.offsets[num_vertices]);
  tbb::parallel_for(tbb::blocked_range<Index>(0, num_vertices, 1024),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index v = range.begin(); v != range.end(); ++v) {
                        std::copy_n(rows.begin() + count[v], unique_count[v],
                                    adjacency.neighbors.begin() + adjacency.offsets[v]);
                      }
                    });
  return adjacency;
}

}  // namespace harap
