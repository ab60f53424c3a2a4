// SPDX-License-Identifier: MIT
#include "framework/mesh.h"

#include <cmath>

#include "framework/error.h"

namespace harap {

void ValidateMesh(const Mesh& mesh, std::string_view what) {
  const int size = mesh.simplex_size();
  if (mesh.num_elements() > 0 && size != 3 && size != 4) {
    throw InputError(
        fmt::format("{}: elements have {} vertices; only triangles (3) and "
                    "tetrahedra (4) are supported",
                    what, size));
  }
  if (mesh.num_vertices() == 0) throw InputError(fmt::format("{}: the mesh has no vertices", what));
  if (mesh.num_elements() == 0) {
    throw InputError(
        fmt::format("{}: the mesh has no {}", what, size == 4 ? "tetrahedra" : "faces"));
  }
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    for (int d = 0; d < 3; ++d) {
      if (!std::isfinite(mesh.vertices(v, d))) {
        throw InputError(fmt::format("{}: vertex {} has a non-finite coordinate ({}, {}, {})", what,
                                     v, mesh.vertices(v, 0), mesh.vertices(v, 1),
                                     mesh.vertices(v, 2)));
      }
    }
  }
  const Index n = mesh.num_vertices();
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 0; a < size; ++a) {
      const Index v = mesh.elements(e, a);
      if (v < 0 || v >= n) {
        throw InputError(
            fmt::format("{}: element {} references vertex {}, but the mesh has {} "
                        "vertices (valid: 0..{})",
                        what, e, v, n, n - 1));
      }
      for (int b = 0; b < a; ++b) {
        if (mesh.elements(e, b) == v) {
          throw InputError(fmt::format("{}: element {} uses vertex {} twice", what, e, v));
        }
      }
    }
  }
  if (mesh.planar) {
    for (Index v = 0; v < n; ++v) {
      if (mesh.vertices(v, 2) != 0.0) {
        throw InputError(fmt::format("{}: planar mesh has vertex {} with z = {} (must be 0)", what,
                                     v, mesh.vertices(v, 2)));
      }
    }
  }
}

std::vector<bool> ReferencedVertices(const Mesh& mesh) {
  std::vector<bool> referenced(mesh.num_vertices(), false);
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 0; a < mesh.simplex_size(); ++a) referenced[mesh.elements(e, a)] = true;
  }
  return referenced;
}

double BoundingBoxDiagonal(const Mesh& mesh) {
  const std::vector<bool> referenced = ReferencedVertices(mesh);
  const bool any = std::find(referenced.begin(), referenced.end(), true) != referenced.end();
  Eigen::RowVector3d lo = Eigen::RowVector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::RowVector3d hi = -lo;
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (any && !referenced[v]) continue;
    lo = lo.cwiseMin(mesh.vertices.row(v));
    hi = hi.cwiseMax(mesh.vertices.row(v));
  }
  return mesh.num_vertices() == 0 ? 0.0 : (hi - lo).norm();
}

}  // namespace harap
