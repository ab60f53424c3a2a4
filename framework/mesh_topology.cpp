// SPDX-License-Identifier: MIT
#include "framework/mesh_topology.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>

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

Elements BoundaryTriangles(const Elements& tetrahedra) {
  // Outward faces of a positive tetrahedron (a, b, c, d): the faces opposite d, c, b and a.
  constexpr int kFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const Index num_faces = 4 * static_cast<Index>(tetrahedra.rows());
  std::vector<std::array<Index, 3>> sorted(static_cast<size_t>(num_faces));
  std::vector<Index> order(static_cast<size_t>(num_faces));
  for (Index t = 0; t < tetrahedra.rows(); ++t) {
    for (int f = 0; f < 4; ++f) {
      std::array<Index, 3> key = {tetrahedra(t, kFaces[f][0]), tetrahedra(t, kFaces[f][1]),
                                  tetrahedra(t, kFaces[f][2])};
      std::sort(key.begin(), key.end());
      sorted[4 * t + f] = key;
      order[4 * t + f] = 4 * t + f;
    }
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](Index x, Index y) { return sorted[x] < sorted[y]; });
  std::vector<Index> boundary;
  for (size_t k = 0; k < order.size();) {
    size_t end = k + 1;
    while (end < order.size() && sorted[order[end]] == sorted[order[k]]) ++end;
    if (end == k + 1) boundary.push_back(order[k]);
    k = end;
  }
  std::sort(boundary.begin(), boundary.end());
  Elements triangles(static_cast<Index>(boundary.size()), 3);
  for (size_t k = 0; k < boundary.size(); ++k) {
    const Index t = boundary[k] / 4;
    const int f = static_cast<int>(boundary[k] % 4);
    for (int a = 0; a < 3; ++a) triangles(static_cast<Index>(k), a) = tetrahedra(t, kFaces[f][a]);
  }
  return triangles;
}

}  // namespace harap
