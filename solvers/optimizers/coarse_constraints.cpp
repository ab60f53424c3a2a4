// SPDX-License-Identifier: MIT
#include "solvers/optimizers/coarse_constraints.h"

#include "framework/rotation.h"

namespace harap {


LevelConstraints MapConstraints(const MeshHierarchy& hierarchy, int level,
                                const Constraints& finest) {
  const Mesh& mesh = hierarchy.levels[level].mesh;
  const Mesh& input = hierarchy.levels[0].mesh;
  std::vector<int> count(mesh.num_vertices(), 0);
  Positions sum_target = Positions::Zero(mesh.num_vertices(), 3);
  Positions sum_offset = Positions::Zero(mesh.num_vertices(), 3);
  for (size_t k = 0; k < finest.indices.size(); ++k) {
    const Index m = finest.indices[k];
    const Index c = hierarchy.MapFinestVertex(m, level);
    if (c == kNoVertex) continue;
    ++count[c];
    sum_target.row(c) += finest.targets.row(k);
    sum_offset.row(c) += input.vertices.row(m) - mesh.vertices.row(c);
  }
  LevelConstraints result;
  result.planar = mesh.planar;
  for (Index c = 0; c < mesh.num_vertices(); ++c) {
    if (count[c] > 0) result.vertices.push_back(c);
  }
  result.mean_target.resize(result.vertices.size(), 3);
  result.mean_offset.resize(result.vertices.size(), 3);
  for (size_t k = 0; k < result.vertices.size(); ++k) {
    const Index c = result.vertices[k];
    result.mean_target.row(k) = sum_target.row(c) / count[c];
    result.mean_offset.row(k) = sum_offset.row(c) / count[c];
  }
  return result;
}

namespace {

// Vertex rotation of constrained vertex k: the site rotation for per-vertex energies, else the
// projected mean of its incident elements' rotations (Eq. 11).
Eigen::Matrix3d ConstrainedVertexRotation(const LevelConstraints& constraints, size_t k,
                                          RotationSite site, const Rotations& rotations) {
  if (site == RotationSite::kVertex) return rotations[constraints.vertices[k]];
  const auto& elements = constraints.incident_elements[k];
  if (elements.empty()) return Eigen::Matrix3d::Identity();
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (Index e : elements) sum += rotations[e];
  return NearestRotation(sum, constraints.planar);
}

}  // namespace

void PlaceConstrainedVertices(const LevelConstraints& constraints, RotationSite site,
                              const Rotations* rotations, Positions& positions) {
  for (size_t k = 0; k < constraints.vertices.size(); ++k) {
    Eigen::RowVector3d target = constraints.mean_target.row(k);
    if (rotations) {
      const Eigen::Matrix3d r = ConstrainedVertexRotation(constraints, k, site, *rotations);
      target -= (r * constraints.mean_offset.row(k).transpose()).transpose();
    } else {
      target -= constraints.mean_offset.row(k);
    }
    positions.row(constraints.vertices[k]) = target;
  }
}


}  // namespace harap
