// SPDX-License-Identifier: MIT
#include "solvers/optimizers/coarse_constraints.h"

#include "framework/error.h"
#include "framework/rotation.h"
#include "framework/stiffness.h"

namespace harap {

LevelConstraints MapConstraints(const MeshHierarchy& hierarchy, int level,
                                const Constraints& finest, const std::vector<Index>* listing) {
  const Mesh& mesh = hierarchy.levels[level].mesh;
  const Mesh& input = hierarchy.levels[0].mesh;
  std::vector<int> count(mesh.num_vertices(), 0);
  Positions sum_target = Positions::Zero(mesh.num_vertices(), 3);
  Positions sum_offset = Positions::Zero(mesh.num_vertices(), 3);
  // Soft members: summed weight and weighted sum of their targets per coarse vertex.
  std::vector<double> soft_weight(mesh.num_vertices(), 0.0);
  Positions soft_sum = Positions::Zero(mesh.num_vertices(), 3);
  for (size_t k = 0; k < finest.indices.size(); ++k) {
    const Index m = finest.indices[k];
    const Index c = hierarchy.MapFinestVertex(m, level);
    if (c == kNoVertex) continue;
    if (!finest.is_hard(k)) {
      soft_weight[c] += finest.weights[k];
      soft_sum.row(c) += finest.weights[k] * finest.targets.row(static_cast<Index>(k));
      continue;
    }
    ++count[c];
    sum_target.row(c) += finest.targets.row(k);
    sum_offset.row(c) += input.vertices.row(m) - mesh.vertices.row(c);
  }
  LevelConstraints result;
  result.planar = mesh.planar;
  const auto listed = [&](Index k) { return listing == nullptr ? k : (*listing)[k]; };
  for (Index k = 0; k < mesh.num_vertices(); ++k) {
    if (count[listed(k)] > 0) result.vertices.push_back(listed(k));
  }
  result.mean_target.resize(result.vertices.size(), 3);
  result.mean_offset.resize(result.vertices.size(), 3);
  for (size_t k = 0; k < result.vertices.size(); ++k) {
    const Index c = result.vertices[k];
    result.mean_target.row(k) = sum_target.row(c) / count[c];
    result.mean_offset.row(k) = sum_offset.row(c) / count[c];
  }
  // Σ_m w_m ‖u_c − t_m‖² = W_c ‖u_c − t̄_c‖² + const with W_c = Σ_m w_m and t̄_c the weighted
  // mean: the coarse vertex stands for its members' pull. A hard member pins the vertex, which
  // makes the soft ones constant there.
  for (Index k = 0; k < mesh.num_vertices(); ++k) {
    const Index c = listed(k);
    if (soft_weight[c] > 0.0 && count[c] == 0) result.soft.vertices.push_back(c);
  }
  result.soft.targets.resize(static_cast<Index>(result.soft.vertices.size()), 3);
  for (size_t k = 0; k < result.soft.vertices.size(); ++k) {
    const Index c = result.soft.vertices[k];
    result.soft.weights.push_back(soft_weight[c]);
    result.soft.targets.row(static_cast<Index>(k)) = soft_sum.row(c) / soft_weight[c];
  }
  return result;
}

void FindIncidentElements(const Mesh& mesh, LevelConstraints& constraints) {
  auto& incident = constraints.incident_elements;
  incident.assign(constraints.vertices.size(), {});
  std::vector<Index> slot(mesh.num_vertices(), kNoVertex);
  for (size_t k = 0; k < constraints.vertices.size(); ++k) {
    slot[constraints.vertices[k]] = static_cast<Index>(k);
  }
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 0; a < mesh.simplex_size(); ++a) {
      if (slot[mesh.elements(e, a)] != kNoVertex) incident[slot[mesh.elements(e, a)]].push_back(e);
    }
  }
}

void PlaceConstrainedVertices(const LevelConstraints& constraints, RotationSite site,
                              const Rotations* rotations, Positions& positions) {
  const bool exact = !constraints.targets_follow_rotations();
  for (size_t k = 0; k < constraints.vertices.size(); ++k) {
    Eigen::RowVector3d target = constraints.mean_target.row(k);
    if (exact) {
      // The input level: the targets themselves.
    } else if (rotations == nullptr) {
      target -= constraints.mean_offset.row(k);
    } else {
      // The vertex's rotation: its own for per-vertex energies, else Eq. 11.
      const auto& elements = constraints.incident_elements;
      const Eigen::Matrix3d r =
          site == RotationSite::kVertex
              ? (*rotations)[constraints.vertices[k]]
              : MeanElementRotation(
                    *rotations, static_cast<Index>(elements[k].size()),
                    [&](Index i) { return elements[k][i]; }, constraints.planar);
      target -= (r * constraints.mean_offset.row(k).transpose()).transpose();
    }
    positions.row(constraints.vertices[k]) = target;
  }
}

void MoveMeanTargets(LevelConstraints& constraints, const Positions& mean_target) {
  HARAP_CHECK(mean_target.rows() == constraints.mean_target.rows(),
              "{} targets for {} constrained vertices", mean_target.rows(),
              constraints.mean_target.rows());
  constraints.mean_target = mean_target;
}

ConstrainSummary FactorGlobalStep(const GlobalStepSystem& system, int level,
                                  const ComponentFactory& factory, const Context& context,
                                  const Stopwatch& clock, std::unique_ptr<LinearSolver>& solver,
                                  Eigen::MatrixXd& rhs, Eigen::MatrixXd& x) {
  solver = factory.MakeLinearSolver(level, system.num_free());
  if (system.num_free() > 0) solver->Factorize(system.system_matrix(), context);
  const double seconds = clock.Seconds();
  if (context.system_callback) context.system_callback(level, system.system_matrix());
  rhs.resize(system.num_unknowns(), 3);
  x.resize(system.num_unknowns(), 3);
  return ConstrainSummary{true, LinearSolver::RefactorRoute::kFull, system.num_unknowns(), seconds};
}

std::vector<double> LevelStiffness(const MeshHierarchy& hierarchy, int level, const Mesh& input,
                                   const std::vector<double>& input_stiffness,
                                   const std::vector<Index>& input_to_level0) {
  if (input_stiffness.empty()) return input_stiffness;
  HARAP_CHECK(level > 0, "the input level's stiffness is the input's");
  const Mesh& mesh = hierarchy.levels[level].mesh;
  const std::vector<double> input_vertex = VertexStiffness(input, input_stiffness);
  std::vector<double> sum(mesh.num_vertices(), 0.0);
  std::vector<int> count(mesh.num_vertices(), 0);
  for (Index m = 0; m < input.num_vertices(); ++m) {
    const Index c = hierarchy.MapFinestVertex(input_to_level0[m], level);
    if (c == kNoVertex) continue;
    sum[c] += input_vertex[m];
    ++count[c];
  }
  for (Index c = 0; c < mesh.num_vertices(); ++c) sum[c] = count[c] > 0 ? sum[c] / count[c] : 1.0;
  return ElementStiffness(mesh, sum);
}

}  // namespace harap
