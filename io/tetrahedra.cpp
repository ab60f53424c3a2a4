// SPDX-License-Identifier: MIT
#include "io/tetrahedra.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace harap {

double TetrahedronDeterminant(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  return (b - a).dot((c - a).cross(d - a));
}

TetrahedronOrientation OrientTetrahedra(Mesh& mesh) {
  TetrahedronOrientation result;
  if (mesh.kind() != ElementKind::kTetrahedron) return result;
  // Relative flatness below which the determinant is rounding noise (see the header).
  constexpr double kFlatness = 1e-12;
  for (Index t = 0; t < mesh.num_elements(); ++t) {
    auto corner = [&](int a) -> Eigen::Vector3d {
      return mesh.vertices.row(mesh.elements(t, a)).transpose();
    };
    const Eigen::Vector3d p = corner(0);
    const Eigen::Vector3d q = corner(1);
    const Eigen::Vector3d r = corner(2);
    const Eigen::Vector3d s = corner(3);
    const double det = TetrahedronDeterminant(p, q, r, s);
    const double scale = (q - p).norm() * (r - p).norm() * (s - p).norm();
    if (!(std::abs(det) > kFlatness * scale)) {
      result.degenerate.push_back(t);
    } else if (det < 0.0) {
      std::swap(mesh.elements(t, 2), mesh.elements(t, 3));
      ++result.reoriented;
    }
  }
  return result;
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
