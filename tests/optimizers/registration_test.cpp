// SPDX-License-Identifier: MIT
// Registration (solvers/optimizers/registration.h) against a brute-force closest-point search, so
// these tests see the driver alone (spatial/'s search has its own tests).
#include "solvers/optimizers/registration.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "framework/error.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

// The closest of a set of points, by looking at every one.
class BruteForcePoints final : public ClosestPointSearch {
 public:
  explicit BruteForcePoints(Positions points) : points_(std::move(points)) {}
  void FindClosest(const Positions& queries, std::vector<ClosestPoint>& out,
                   const Context& /*context*/) const override {
    out.assign(queries.rows(), ClosestPoint{});
    for (Index q = 0; q < queries.rows(); ++q) {
      Index best = 0;
      (points_.rowwise() - queries.row(q)).rowwise().squaredNorm().minCoeff(&best);
      out[q].point = points_.row(best).transpose();
      out[q].distance = (points_.row(best) - queries.row(q)).norm();
      out[q].element = best;
    }
  }
  bool has_normals() const override { return false; }
  bool is_mesh() const override { return false; }
  Index num_points() const override { return points_.rows(); }
  const Positions& points() const override { return points_; }
  const Positions& point_normals() const override { return no_normals_; }

 private:
  Positions points_;
  Positions no_normals_ = Positions(0, 3);
};

// The symmetric correspondences' search over the source's vertices.
std::unique_ptr<ClosestPointSearch> BruteForceOver(const Positions& points) {
  return std::make_unique<BruteForcePoints>(points);
}

// Points on the triangles of `mesh` at `positions`: the corners and `per_edge` points along each
// edge, so the target is denser than the source but holds no source vertex's exact partner
// beyond the corners.
Positions DenseSamples(const Mesh& mesh, const Positions& positions, int per_edge) {
  std::vector<Eigen::Vector3d> samples;
  for (Index v = 0; v < positions.rows(); ++v) samples.emplace_back(positions.row(v));
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = positions.row(mesh.elements(f, k));
      const Eigen::Vector3d b = positions.row(mesh.elements(f, (k + 1) % 3));
      for (int s = 1; s <= per_edge; ++s) {
        const double t = static_cast<double>(s) / (per_edge + 1);
        samples.push_back((1.0 - t) * a + t * b);
      }
    }
  }
  Positions points(static_cast<Index>(samples.size()), 3);
  for (size_t i = 0; i < samples.size(); ++i) points.row(static_cast<Index>(i)) = samples[i];
  return points;
}

double MeanVertexError(const Positions& a, const Positions& b) {
  return (a - b).rowwise().norm().mean();
}

struct RegistrationSetup {
  explicit RegistrationSetup(const std::string& toml = "[hierarchy]\nmin_vertices = 60\n")
      : setup(toml),
        level_solver(setup.registries.level_solvers.Create("local_global", ConfigNode())) {}
  RegistrationResult Run(const RegistrationProblem& problem, RegistrationOptions options,
                         const Context& context = Context()) const {
    return Register(problem, options, *level_solver, setup.factory, context);
  }
  TestSetup setup;
  std::unique_ptr<LevelSolver> level_solver;
};

}  // namespace

TEST_CASE("registration recovers an ARAP deformation from a point cloud, flat and hierarchical",
          "[optimizers][registration]") {
  // The known answer: a bent tube solved by classic ARAP, sampled as points.
  BentTube tube(40, 16, 2.0, 0.9, Eigen::Vector3d(0.0, 0.5, -0.3));
  TestSetup classic("[optimizer]\ntype = \"classic\"\ntolerance = 1e-9\nmax_iterations = 3000\n");
  const Positions answer =
      classic.MakeOptimizer()->Optimize(tube.problem, classic.factory, Context()).positions;
  const BruteForcePoints target(DenseSamples(tube.mesh, answer, 6));
  RegistrationProblem problem;
  problem.source = &tube.mesh;
  problem.target = &target;
  problem.make_point_search = BruteForceOver;
  const double diagonal = BoundingBoxDiagonal(tube.mesh);
  const double rest_error = MeanVertexError(tube.mesh.vertices, answer);
  RegistrationSetup setup;
  for (const bool hierarchical : {false, true}) {
    DYNAMIC_SECTION("hierarchical " << hierarchical) {
      RegistrationOptions options;
      options.hierarchical = hierarchical;
      const RegistrationResult result = setup.Run(problem, options);
      const double error = MeanVertexError(result.run.positions, answer);
      INFO("rest error " << rest_error / diagonal << ", registered " << error / diagonal
                         << ", updates " << result.correspondence_updates);
      // A tube is nearly symmetric about its axis, so vertices may slide along the surface the
      // target points do not pin down: the bound is on the vertex error's drop, the residual
      // (distance to the target) must be small.
      CHECK(error < (hierarchical ? 0.1 : 0.5) * rest_error);
      // Flat runs stop at max_updates here, still far from converged.
      CHECK(result.residual_rms < (hierarchical ? 0.003 : 0.03) * diagonal);
      CHECK(result.correspondences.kept >= tube.mesh.num_vertices() - 2);
      CHECK(result.arap_energy >= 0.0);
      CHECK(result.arap_energy <= result.run.energy);
      CHECK(result.run.levels.size() == (hierarchical ? result.run.levels.size() : 1u));
      if (hierarchical) CHECK(result.run.levels.size() > 1);
    }
  }
}

TEST_CASE("registration refuses bad input before solving", "[optimizers][registration]") {
  BentTube tube(10, 8, 1.0, 0.5, Eigen::Vector3d::Zero());
  const BruteForcePoints target(tube.mesh.vertices);
  RegistrationSetup setup;
  RegistrationProblem problem;
  problem.source = &tube.mesh;
  problem.target = &target;
  SECTION("a landmark out of range") {
    problem.landmarks.indices = {tube.mesh.num_vertices()};
    problem.landmarks.targets = Positions::Zero(1, 3);
    CHECK_THROWS_WITH(setup.Run(problem, {}),
                      Catch::Contains("landmark 1") && Catch::Contains("out of range"));
  }
  SECTION("a landmark at NaN") {
    problem.landmarks.indices = {0};
    problem.landmarks.targets = Positions::Constant(1, 3, std::nan(""));
    CHECK_THROWS_WITH(setup.Run(problem, {}), Catch::Contains("not finite"));
  }
  SECTION("an empty target") {
    const BruteForcePoints empty{Positions(0, 3)};
    problem.target = &empty;
    CHECK_THROWS_WITH(setup.Run(problem, {}), Catch::Contains("target is empty"));
  }
  SECTION("a planar source") {
    Mesh planar = tube.mesh;
    planar.planar = true;
    problem.source = &planar;
    CHECK_THROWS_WITH(setup.Run(problem, {}), Catch::Contains("planar"));
  }
}

TEST_CASE("a target beyond the rejection distance leaves the source where it is",
          "[optimizers][registration]") {
  BentTube tube(10, 8, 1.0, 0.5, Eigen::Vector3d::Zero());
  Positions far = tube.mesh.vertices;
  far.col(0).array() += 100.0;
  const BruteForcePoints target(far);
  RegistrationProblem problem;
  problem.source = &tube.mesh;
  problem.target = &target;
  RegistrationSetup setup;
  const RegistrationResult result = setup.Run(problem, {});
  CHECK(result.correspondences.kept == 0);
  CHECK(result.correspondences.too_far == tube.mesh.num_vertices());
  CHECK((result.run.positions - tube.mesh.vertices).cwiseAbs().maxCoeff() < 1e-9);
}

TEST_CASE("landmarks pull their vertices", "[optimizers][registration]") {
  BentTube tube(10, 8, 1.0, 0.5, Eigen::Vector3d::Zero());
  Positions shifted = tube.mesh.vertices;
  shifted.col(1).array() += 0.3;  // beyond max_distance: only the landmarks act
  const BruteForcePoints target(shifted);
  RegistrationProblem problem;
  problem.source = &tube.mesh;
  problem.target = &target;
  problem.landmarks.indices = {0, tube.mesh.num_vertices() - 1};
  problem.landmarks.targets.resize(2, 3);
  problem.landmarks.targets << shifted.row(0), shifted.row(tube.mesh.num_vertices() - 1);
  RegistrationSetup setup;
  RegistrationOptions options;
  options.max_distance = 0.01;
  const RegistrationResult result = setup.Run(problem, options);
  // Two landmarks translate the whole (rigid) tube.
  CHECK(MeanVertexError(result.run.positions, shifted) < 0.01);
}
