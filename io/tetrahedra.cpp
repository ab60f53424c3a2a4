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

}  // namespace harap
