// SPDX-License-Identifier: MIT
// Soft targets (Constraints::weights): the data term Σ w ‖u − t‖² added to A and B.
#include <catch2/catch.hpp>
#include <cmath>

#include "framework/error.h"
#include "solvers/optimizers/coarse_constraints.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

// The tube's top ring soft with `weight`, its bottom ring hard.
DeformationProblem WithSoftTop(const DeformationProblem& hard, int segments, double weight) {
  DeformationProblem soft = hard;
  soft.constraints.weights.assign(soft.constraints.indices.size(), Constraints::kHardWeight);
  for (size_t k = 0; k < soft.constraints.indices.size(); ++k) {
    if (soft.constraints.indices[k] >= segments) soft.constraints.weights[k] = weight;
  }
  return soft;
}

double MaxTargetDistance(const OptimizeResult& result, const Constraints& constraints) {
  double largest = 0.0;
  for (size_t k = 0; k < constraints.indices.size(); ++k) {
    largest = std::max(largest, (result.positions.row(constraints.indices[k]) -
                                 constraints.targets.row(static_cast<Index>(k)))
                                    .norm());
  }
  return largest;
}

}  // namespace

TEST_CASE("soft targets: very large weights reproduce hard handles", "[optimizers][soft]") {
  BentTube tube(30, 16, 1.5, 1.0, Eigen::Vector3d(0.0, 0.4, -0.2));
  const DeformationProblem soft = WithSoftTop(tube.problem, 16, 1e9);
  for (const char* optimizer : {"classic", "hierarchical"}) {
    DYNAMIC_SECTION(optimizer) {
      TestSetup setup(
          fmt::format("[optimizer]\ntype = \"{}\"\ntolerance = 1e-12\nmax_iterations = 3000\n"
                      "[hierarchy]\nmin_vertices = 60\n",
                      optimizer));
      const OptimizeResult hard_result =
          setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, Context());
      const OptimizeResult soft_result =
          setup.MakeOptimizer()->Optimize(soft, setup.factory, Context());
      INFO("hard " << hard_result.energy << ", soft " << soft_result.energy);
      CHECK(std::abs(soft_result.energy - hard_result.energy) <= 1e-6 * hard_result.energy);
      CHECK(MaxTargetDistance(soft_result, soft.constraints) < 1e-6);
      // Soft vertices start at rest, not at their targets: the pull brought them there.
      if (std::string(optimizer) == "classic") {
        CHECK((soft_result.positions - hard_result.positions).cwiseAbs().maxCoeff() < 1e-5);
      }
    }
  }
}

TEST_CASE("soft targets: the weight trades the pull against rigidity", "[optimizers][soft]") {
  BentTube tube(30, 16, 1.5, 1.0, Eigen::Vector3d(0.0, 0.4, -0.2));
  TestSetup setup("[optimizer]\ntype = \"classic\"\ntolerance = 1e-10\nmax_iterations = 3000\n");
  double previous_distance = std::numeric_limits<double>::infinity();
  for (const double weight : {1e-3, 1e-1, 10.0, 1e3}) {
    const DeformationProblem soft = WithSoftTop(tube.problem, 16, weight);
    const OptimizeResult result = setup.MakeOptimizer()->Optimize(soft, setup.factory, Context());
    const double distance = MaxTargetDistance(result, soft.constraints);
    INFO("weight " << weight << ": distance " << distance);
    CHECK(distance < previous_distance);
    CHECK(result.positions.allFinite());
    // The hard ring stays exactly where it was put.
    for (Index s = 0; s < 16; ++s) {
      CHECK(result.positions.row(s) == tube.problem.constraints.targets.row(s));
    }
    previous_distance = distance;
  }
  // A weak pull barely moves a piece held at the other end; a strong one nearly reaches.
  CHECK(previous_distance < 1e-2);
}

TEST_CASE("soft targets alone hold a free piece: nothing is pinned", "[optimizers][soft]") {
  // All constraints soft: the soft vertices anchor the component, so no vertex is pinned and a
  // rigid motion of the targets is reproduced exactly (ARAP and the data term both vanish).
  const Mesh mesh = Icosphere(2);
  const Eigen::Matrix3d turn = RandomRotation(7);
  const Eigen::RowVector3d shift(0.3, -0.2, 0.5);
  DeformationProblem problem;
  problem.mesh = &mesh;
  for (Index v = 0; v < mesh.num_vertices(); v += 7) problem.constraints.indices.push_back(v);
  const Index count = static_cast<Index>(problem.constraints.indices.size());
  problem.constraints.targets.resize(count, 3);
  for (Index k = 0; k < count; ++k) {
    problem.constraints.targets.row(k) =
        mesh.vertices.row(problem.constraints.indices[k]) * turn.transpose() + shift;
  }
  problem.constraints.weights.assign(count, 2.0);
  TestSetup setup("[optimizer]\ntype = \"classic\"\ntolerance = 1e-14\nmax_iterations = 5000\n");
  const OptimizeResult result = setup.MakeOptimizer()->Optimize(problem, setup.factory, Context());
  CHECK(result.constraints.free_components == 0);
  CHECK(result.constraints.constrained_vertices == 0);
  const Positions expected = (mesh.vertices * turn.transpose()).rowwise() + shift;
  CHECK((result.positions - expected).cwiseAbs().maxCoeff() < 1e-5);
  CHECK(result.energy < 1e-9);
}

TEST_CASE("soft targets: hundreds of small handle groups, hard and soft mixed, hierarchical",
          "[optimizers][soft]") {
  BentTube tube(100, 40, 4.0, M_PI / 2, Eigen::Vector3d(0.0, 1.0, -1.5));
  // 300 groups of 3 neighbouring vertices on the tube's side, each pulled outwards a little.
  DeformationProblem problem = tube.problem;
  problem.constraints = WithSoftGroups(tube, 40, 300, 3);
  const Constraints& c = problem.constraints;

  TestSetup setup(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-8\n[hierarchy]\nmin_vertices = 200\n");
  EnergyTrace trace;
  const OptimizeResult result = OptimizeWithTrace(setup, problem, trace);
  // The same bend without the soft groups: where their vertices would be without the pull.
  const OptimizeResult unpulled =
      setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, Context());
  REQUIRE(result.levels.size() >= 3);
  CHECK(result.positions.allFinite());
  CHECK(result.converged);
  CHECK(trace[0].size() >= 1);
  // Hard handles exactly at their targets; the soft ones moved towards theirs.
  double without_pull = 0.0, remaining = 0.0;
  for (size_t k = 0; k < c.indices.size(); ++k) {
    const Eigen::RowVector3d target = c.targets.row(static_cast<Index>(k));
    if (c.is_hard(k)) {
      CHECK(result.positions.row(c.indices[k]) == target);
    } else {
      remaining += (result.positions.row(c.indices[k]) - target).norm();
      without_pull += (unpulled.positions.row(c.indices[k]) - target).norm();
    }
  }
  INFO("summed distance to the soft targets: " << remaining << ", without them " << without_pull);
  CHECK(remaining < 0.5 * without_pull);
  CHECK(result.constraints.constrained_vertices == 80);
}

TEST_CASE("soft targets map to coarse levels by summed weight and weighted mean",
          "[optimizers][soft]") {
  BentTube tube(40, 20, 2.0, 0.5, Eigen::Vector3d(0.0, 0.2, 0.0));
  TestSetup setup("[hierarchy]\nmin_vertices = 100\n");
  const MeshHierarchy hierarchy = setup.factory.MakeHierarchy()->Build(tube.mesh, Context());
  REQUIRE(hierarchy.levels.size() >= 2);
  Constraints finest;
  double total = 0.0;
  for (Index v = 100; v < 400; ++v) {
    finest.indices.push_back(v);
    finest.weights.push_back(1.0 + static_cast<double>(v % 3));
    total += finest.weights.back();
  }
  finest.targets = Positions::Zero(static_cast<Index>(finest.indices.size()), 3);
  for (Index k = 0; k < finest.targets.rows(); ++k) finest.targets(k, 0) = 1.0 + (k % 2);
  const int level = static_cast<int>(hierarchy.levels.size()) - 1;
  const LevelConstraints mapped = MapConstraints(hierarchy, level, finest);
  CHECK(mapped.vertices.empty());
  double coarse_total = 0.0;
  for (double w : mapped.soft.weights) coarse_total += w;
  CHECK(coarse_total == Approx(total));
  // Each coarse target is a weighted mean of x = 1 and x = 2.
  for (Index k = 0; k < mapped.soft.targets.rows(); ++k) {
    CHECK(mapped.soft.targets(k, 0) >= 1.0);
    CHECK(mapped.soft.targets(k, 0) <= 2.0);
  }
}

TEST_CASE("soft targets: bad weights are clear errors; ADMM and Newton refuse them",
          "[optimizers][soft]") {
  BentTube tube(10, 8, 1.0, 0.5, Eigen::Vector3d(0.0, 0.2, 0.0));
  TestSetup classic("[optimizer]\ntype = \"classic\"\n");
  for (const double bad : {0.0, -1.0, std::nan("")}) {
    const DeformationProblem problem = WithSoftTop(tube.problem, 8, bad);
    CHECK_THROWS_WITH(classic.MakeOptimizer()->Optimize(problem, classic.factory, Context()),
                      Catch::Contains("soft handle's weight must be > 0"));
  }
  const DeformationProblem soft = WithSoftTop(tube.problem, 8, 1.0);
  TestSetup newton("[optimizer]\ntype = \"classic\"\nnewton = 10\n");
  CHECK_THROWS_WITH(newton.MakeOptimizer()->Optimize(soft, newton.factory, Context()),
                    Catch::Contains("Newton"));
  TwistedTetBar bar(2, 2, 4, 2.0, 0.5);
  DeformationProblem soft_bar = bar.problem;
  soft_bar.constraints.weights.assign(soft_bar.constraints.indices.size(), 1.0);
  TestSetup admm("[optimizer]\ntype = \"admm_pd\"\n[energy]\ntype = \"elements\"\n");
  CHECK_THROWS_WITH(admm.MakeOptimizer()->Optimize(soft_bar, admm.factory, Context()),
                    Catch::Contains("local/global level solver"));
}
