// SPDX-License-Identifier: MIT
#include "energies/kernels/triangle_stencil.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "energies/kernels/mesh_adjacency.h"
#include "framework/error.h"

namespace harap {

std::vector<std::array<Index, 9>> TriangleEntryPositions(const SparseMatrix& pattern,
                                                         const Elements& triangles) {
  std::vector<std::array<Index, 9>> positions(triangles.rows());
  const Index* inner = pattern.innerIndexPtr();
  // One pass over each corner's column finds the face's three rows in it (the same positions as
  // EntryPosition per pair, a third of the column walks).
  tbb::parallel_for(tbb::blocked_range<Index>(0, static_cast<Index>(triangles.rows()), 4096),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index f = range.begin(); f != range.end(); ++f) {
                        const Index v[3] = {triangles(f, 0), triangles(f, 1), triangles(f, 2)};
                        auto& at = positions[f];
                        at.fill(-1);
                        for (int b = 0; b < 3; ++b) {
                          const auto [begin, end] = ColumnRange(pattern, v[b]);
                          for (Index p = begin; p < end; ++p) {
                            for (int a = 0; a < 3; ++a) {
                              if (inner[p] == v[a]) at[3 * a + b] = p;
                            }
                          }
                        }
                        for (int k = 0; k < 9; ++k) {
                          HARAP_CHECK(at[k] >= 0,
                                      "entry ({}, {}) is not in the sparsity pattern",
                                      v[k / 3], v[k % 3]);
                        }
                      }
                    });
  return positions;
}

void RequireTriangleMesh(const Mesh& mesh, std::string_view energy_name) {
  if (mesh.kind() != ElementKind::kTriangle || mesh.simplex_size() != 3) {
    throw InputError(fmt::format("energy '{}' works on triangle meshes, but the mesh has {} "
                                 "vertices per element; use the per-element energy for "
                                 "tetrahedral meshes",
                                 energy_name, mesh.simplex_size()));
  }
}

}  // namespace harap
