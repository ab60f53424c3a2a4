// SPDX-License-Identifier: MIT
#include "framework/vertex_normals.h"

#include <Eigen/Geometry>

namespace harap {

Positions VertexNormals(const Positions& positions, const Elements& triangles) {
  Positions normals = Positions::Zero(positions.rows(), 3);
  for (Index f = 0; f < triangles.rows(); ++f) {
    const Eigen::Vector3d a = positions.row(triangles(f, 0));
    const Eigen::Vector3d b = positions.row(triangles(f, 1));
    const Eigen::Vector3d c = positions.row(triangles(f, 2));
    const Eigen::Vector3d area_normal = (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) normals.row(triangles(f, k)) += area_normal.transpose();
  }
  for (Index v = 0; v < normals.rows(); ++v) {
    const double norm = normals.row(v).norm();
    if (norm > 0.0) normals.row(v) /= norm;
  }
  return normals;
}

}  // namespace harap
