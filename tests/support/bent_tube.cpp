// SPDX-License-Identifier: MIT
#include "tests/support/bent_tube.h"

#include <Eigen/Geometry>

#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

namespace harap::testing {

BentTube::BentTube(int rings, int segments, double height, double angle,
                   const Eigen::Vector3d& shift)
    : mesh(Tube(rings, segments)) {
  mesh.vertices.col(2) *= height;
  problem.mesh = &mesh;
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()).toRotationMatrix();
  for (int s = 0; s < segments; ++s) problem.constraints.indices.push_back(s);
  for (int s = 0; s < segments; ++s) {
    problem.constraints.indices.push_back((rings - 1) * segments + s);
  }
  problem.constraints.targets.resize(problem.constraints.indices.size(), 3);
  for (size_t k = 0; k < problem.constraints.indices.size(); ++k) {
    Eigen::Vector3d p = mesh.vertices.row(problem.constraints.indices[k]);
    if (k >= static_cast<size_t>(segments)) p = turn * p + shift;
    problem.constraints.targets.row(k) = p.transpose();
  }
}

void LevelEnergies::Record(Context& context) {
  context.iteration_callback = [this](const IterationSummary& s) {
    by_level[s.level].push_back(s.energy);
    return CallbackAction::kContinue;
  };
}

OptimizeResult LevelEnergies::RunHierarchicalWithFixedTargets(const DeformationProblem& problem,
                                                              int min_vertices,
                                                              const std::string& tables) {
  const TestSetup setup(fmt::format(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-7\nupdate_constraints = false\n"
      "[hierarchy]\nmin_vertices = {}\n{}",
      min_vertices, tables));
  Context context;
  Record(context);
  return setup.MakeOptimizer()->Optimize(problem, setup.factory, context);
}

bool LevelEnergies::MonotonePerLevel() const {
  for (const auto& [level, trace] : by_level) {
    for (size_t i = 1; i < trace.size(); ++i) {
      if (trace[i] > trace[i - 1] * (1.0 + 1e-12) + 1e-15) return false;
    }
  }
  return true;
}

}  // namespace harap::testing
