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
  tbb::parallel_for(tbb::blocked_range<Index>(0, static_cast<Index>(triangles.rows()), 4096),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index f = range.begin(); f != range.end(); ++f) {
                        for (int a = 0; a < 3; ++a) {
                          for (int b = 0; b < 3; ++b) {
                            positions[f][3 * a + b] =
                                EntryPosition(pattern, triangles(f, a), triangles(f, b));
                          }
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
