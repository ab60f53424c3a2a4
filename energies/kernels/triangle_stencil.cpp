// SPDX-License-Identifier: MIT
#include "energies/kernels/triangle_stencil.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <utility>

#include "energies/kernels/mesh_adjacency.h"
#include "framework/error.h"

namespace harap {

std::vector<std::array<Index, 9>> TriangleEntryPositions(const SparseMatrix& pattern,
                                                         const Elements& triangles) {
  std::vector<std::array<Index, 9>> positions(triangles.rows());
  const Index* inner = pattern.innerIndexPtr();
  // The face's three rows, in ascending order, are found in each corner's (sorted) column by one
  // forward walk that stops at each in turn (the same positions as EntryPosition per pair, a
  // third of the column walks and no binary searches).
  tbb::parallel_for(tbb::blocked_range<Index>(0, static_cast<Index>(triangles.rows()), 4096),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index f = range.begin(); f != range.end(); ++f) {
                        const Index v[3] = {triangles(f, 0), triangles(f, 1), triangles(f, 2)};
                        int by_row[3] = {0, 1, 2};  // corners by ascending vertex index
                        if (v[by_row[0]] > v[by_row[1]]) std::swap(by_row[0], by_row[1]);
                        if (v[by_row[1]] > v[by_row[2]]) std::swap(by_row[1], by_row[2]);
                        if (v[by_row[0]] > v[by_row[1]]) std::swap(by_row[0], by_row[1]);
                        auto& at = positions[f];
                        for (int b = 0; b < 3; ++b) {
                          auto [p, end] = ColumnRange(pattern, v[b]);
                          for (const int a : by_row) {
                            while (p < end && inner[p] < v[a]) ++p;
                            HARAP_CHECK(p < end && inner[p] == v[a],
                                        "entry ({}, {}) is not in the sparsity pattern", v[a],
                                        v[b]);
                            at[3 * a + b] = p;
                          }
                        }
                      }
                    });
  return positions;
}

void RequireTriangleMesh(const Mesh& mesh, std::string_view energy_name) {
  if (mesh.kind() != ElementKind::kTriangle || mesh.simplex_size() != 3) {
    throw InputError(
        fmt::format("energy '{}' works on triangle meshes, but the mesh has {} "
                    "vertices per element; use the per-element energy for "
                    "tetrahedral meshes",
                    energy_name, mesh.simplex_size()));
  }
}

}  // namespace harap
