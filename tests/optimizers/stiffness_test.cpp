// SPDX-License-Identifier: MIT
// Stiffness (DeformationProblem::stiffness): per-element factors multiplying the energy's terms.
#include "framework/stiffness.h"

#include <Eigen/SVD>
#include <catch2/catch.hpp>
#include <cmath>
#include <numeric>

#include "framework/error.h"
#include "solvers/optimizers/coarse_constraints.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

std::string Config(const std::string& optimizer, const std::string& energy) {
  return fmt::format(
      "[optimizer]\ntype = \"{}\"\ntolerance = 1e-10\nmax_iterations = 2000\n[energy]\ntype = "
      "\"{}\"\n[hierarchy]\nmin_vertices = 60\n",
      optimizer, energy);
}

// min over rotations R of Σ_edges ‖e' − R e‖² for triangle f: its own ARAP energy (unit weights),
// computed apart from the energies (Kabsch on the edges and the scaled normals).
double TriangleRigidityError(const Mesh& mesh, const Positions& u, Index f) {
  Eigen::Matrix3d rest, deformed;
  for (int a = 0; a < 3; ++a) {
    const Index i = mesh.elements(f, a), j = mesh.elements(f, (a + 1) % 3);
    rest.col(a) = (mesh.vertices.row(j) - mesh.vertices.row(i)).transpose();
    deformed.col(a) = (u.row(j) - u.row(i)).transpose();
  }
  const Eigen::Vector3d n = rest.col(0).cross(rest.col(1));
  const Eigen::Vector3d n_deformed = deformed.col(0).cross(deformed.col(1));
  Eigen::Matrix3d covariance = deformed * rest.transpose();
  covariance += n_deformed.normalized() * n.normalized().transpose() * rest.col(0).squaredNorm();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d r = svd.matrixU() * d * svd.matrixV().transpose();
  return (deformed - r * rest).squaredNorm();
}

// The configured energy with `stiffness` at positions u, rotations fitted to u.
double EnergyOf(const TestSetup& setup, const Mesh& mesh, const std::vector<double>& stiffness,
                const Positions& u) {
  const std::unique_ptr<Energy> energy = setup.factory.MakeEnergy();
  energy->SetStiffness(stiffness);
  energy->Precompute(mesh, Context());
  Rotations rotations(energy->num_rotations(), Eigen::Matrix3d::Identity());
  return energy->FitRotations(u, rotations, Context());
}

}  // namespace

TEST_CASE("stiffness 1 everywhere reproduces the energy without stiffness, bit for bit",
          "[optimizers][stiffness]") {
  BentTube tube(24, 12, 1.5, 1.0, Eigen::Vector3d(0.0, 0.4, -0.2));
  DeformationProblem ones = tube.problem;
  ones.stiffness.assign(tube.mesh.num_elements(), 1.0);
  for (const char* optimizer : {"classic", "hierarchical"}) {
    for (const char* energy : {"spokes_and_rims", "spokes", "smooth_arap"}) {
      DYNAMIC_SECTION(optimizer << " " << energy) {
        TestSetup setup(Config(optimizer, energy));
        const OptimizeResult plain =
            setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, Context());
        const OptimizeResult stiff =
            setup.MakeOptimizer()->Optimize(ones, setup.factory, Context());
        CHECK(stiff.energy == plain.energy);
        CHECK(stiff.iterations == plain.iterations);
        CHECK(stiff.positions == plain.positions);
      }
    }
  }
  TwistedTetBar bar(2, 2, 5, 2.0, 0.6);
  DeformationProblem bar_ones = bar.problem;
  bar_ones.stiffness.assign(bar.mesh.num_elements(), 1.0);
  TestSetup elements(Config("classic", "elements"));
  CHECK(elements.MakeOptimizer()->Optimize(bar_ones, elements.factory, Context()).energy ==
        elements.MakeOptimizer()->Optimize(bar.problem, elements.factory, Context()).energy);
}

TEST_CASE("a uniform stiffness k scales the energy by k and leaves the solution",
          "[optimizers][stiffness]") {
  BentTube tube(24, 12, 1.5, 1.0, Eigen::Vector3d(0.0, 0.4, -0.2));
  DeformationProblem scaled = tube.problem;
  scaled.stiffness.assign(tube.mesh.num_elements(), 4.0);
  for (const char* optimizer : {"classic", "hierarchical"}) {
    DYNAMIC_SECTION(optimizer) {
      TestSetup setup(Config(optimizer, "spokes_and_rims"));
      const OptimizeResult plain =
          setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, Context());
      const OptimizeResult stiff =
          setup.MakeOptimizer()->Optimize(scaled, setup.factory, Context());
      CHECK(stiff.energy == Approx(4.0 * plain.energy).epsilon(1e-8));
      CHECK((stiff.positions - plain.positions).cwiseAbs().maxCoeff() < 1e-6);
    }
  }
  TwistedTetBar bar(2, 2, 5, 2.0, 0.6);
  DeformationProblem bar_scaled = bar.problem;
  bar_scaled.stiffness.assign(bar.mesh.num_elements(), 4.0);
  TestSetup elements(Config("classic", "elements"));
  const OptimizeResult plain =
      elements.MakeOptimizer()->Optimize(bar.problem, elements.factory, {});
  const OptimizeResult stiff = elements.MakeOptimizer()->Optimize(bar_scaled, elements.factory, {});
  CHECK(stiff.energy == Approx(4.0 * plain.energy).epsilon(1e-8));
  REQUIRE(stiff.measures.count("energy_wrapd") == 1);
  CHECK(stiff.measures.at("energy_wrapd") == Approx(stiff.energy / 2.0).epsilon(1e-6));
}

TEST_CASE("a stiff region deforms less while the handles still reach their targets",
          "[optimizers][stiffness]") {
  // The bent tube's middle third 100 times as stiff: its triangles stay closer to rigid and the
  // bend moves to the soft thirds.
  const int rings = 30, segments = 12;
  BentTube tube(rings, segments, 1.5, 1.2, Eigen::Vector3d(0.0, 0.4, -0.2));
  std::vector<bool> middle(tube.mesh.num_elements(), false);
  DeformationProblem stiff = tube.problem;
  stiff.stiffness.assign(tube.mesh.num_elements(), 1.0);
  const double low = tube.mesh.vertices.col(2).maxCoeff() / 3.0, high = 2.0 * low;
  for (Index f = 0; f < tube.mesh.num_elements(); ++f) {
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      const double z = tube.mesh.vertices(tube.mesh.elements(f, a), 2);
      inside = inside && z >= low && z <= high;
    }
    middle[f] = inside;
    if (inside) stiff.stiffness[f] = 100.0;
  }
  for (const char* optimizer : {"classic", "hierarchical"}) {
    for (const char* energy : {"spokes_and_rims", "spokes"}) {
      DYNAMIC_SECTION(optimizer << " " << energy) {
        TestSetup setup(Config(optimizer, energy));
        const OptimizeResult plain =
            setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, Context());
        const OptimizeResult result = setup.MakeOptimizer()->Optimize(stiff, setup.factory, {});
        double plain_middle = 0.0, stiff_middle = 0.0;
        for (Index f = 0; f < tube.mesh.num_elements(); ++f) {
          if (!middle[f]) continue;
          plain_middle += TriangleRigidityError(tube.mesh, plain.positions, f);
          stiff_middle += TriangleRigidityError(tube.mesh, result.positions, f);
        }
        INFO("middle " << plain_middle << " -> " << stiff_middle);
        CHECK(stiff_middle < 0.2 * plain_middle);
        // Each run minimizes its own energy: the other run's positions cost more in it.
        CHECK(EnergyOf(setup, tube.mesh, {}, result.positions) >= plain.energy * (1 - 1e-9));
        CHECK(EnergyOf(setup, tube.mesh, stiff.stiffness, plain.positions) >=
              result.energy * (1 - 1e-9));
        const Constraints& c = stiff.constraints;
        for (size_t k = 0; k < c.indices.size(); ++k) {
          CHECK((result.positions.row(c.indices[k]) - c.targets.row(static_cast<Index>(k))).norm() <
                1e-12);
        }
      }
    }
  }
}

TEST_CASE("stiffness reaches coarse levels through the clusters", "[optimizers][stiffness]") {
  BentTube tube(30, 16, 1.5, 1.0, Eigen::Vector3d(0.0, 0.4, -0.2));
  TestSetup setup("[hierarchy]\nmin_vertices = 60\n");
  const MeshHierarchy hierarchy = setup.factory.MakeHierarchy()->Build(tube.mesh, Context());
  REQUIRE(hierarchy.num_levels() >= 2);
  const std::vector<double> ones(tube.mesh.num_elements(), 1.0);
  std::vector<double> mixed(tube.mesh.num_elements(), 1.0);
  for (Index f = 0; f < tube.mesh.num_elements() / 2; ++f) mixed[f] = 9.0;
  std::vector<Index> same(tube.mesh.num_vertices());  // the hierarchy's level 0 is the mesh
  std::iota(same.begin(), same.end(), Index{0});
  for (int l = 1; l < hierarchy.num_levels(); ++l) {
    const std::vector<double> uniform = LevelStiffness(hierarchy, l, tube.mesh, ones, same);
    REQUIRE(static_cast<Index>(uniform.size()) == hierarchy.levels[l].mesh.num_elements());
    for (const double s : uniform) CHECK(s == 1.0);
    const std::vector<double> coarse = LevelStiffness(hierarchy, l, tube.mesh, mixed, same);
    const auto [lo, hi] = std::minmax_element(coarse.begin(), coarse.end());
    CHECK(*lo >= 1.0);
    CHECK(*hi <= 9.0);
    CHECK(*hi > 5.0);  // the stiff half stays stiff
    CHECK(*lo < 5.0);  // and the soft half soft
  }
  CHECK(LevelStiffness(hierarchy, 1, tube.mesh, {}, same).empty());
}

TEST_CASE("bad stiffness is a clear error before any work", "[optimizers][stiffness]") {
  BentTube tube(10, 8, 1.0, 0.5, Eigen::Vector3d(0.0, 0.2, 0.0));
  TestSetup classic(Config("classic", "spokes_and_rims"));
  DeformationProblem problem = tube.problem;
  problem.stiffness.assign(3, 1.0);
  CHECK_THROWS_WITH(classic.MakeOptimizer()->Optimize(problem, classic.factory, Context()),
                    Catch::Contains("3 stiffness factors for a mesh of"));
  for (const double bad : {0.0, -2.0, std::nan(""), HUGE_VAL}) {
    problem.stiffness.assign(tube.mesh.num_elements(), 1.0);
    problem.stiffness[5] = bad;
    CHECK_THROWS_WITH(classic.MakeOptimizer()->Optimize(problem, classic.factory, Context()),
                      Catch::Contains("stiffness factor of element 5"));
  }
  TwistedTetBar bar(2, 2, 4, 2.0, 0.5);
  DeformationProblem stiff_bar = bar.problem;
  stiff_bar.stiffness.assign(bar.mesh.num_elements(), 2.0);
  TestSetup admm("[optimizer]\ntype = \"admm_pd\"\n[energy]\ntype = \"elements\"\n");
  CHECK_THROWS_WITH(admm.MakeOptimizer()->Optimize(stiff_bar, admm.factory, Context()),
                    Catch::Contains("take no stiffness"));
}

TEST_CASE("per-vertex and per-element stiffness convert by means", "[framework][stiffness]") {
  Mesh mesh;
  mesh.vertices.resize(4, 3);
  mesh.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0;
  mesh.elements.resize(2, 3);
  mesh.elements << 0, 1, 2, 1, 3, 2;
  const std::vector<double> at_vertex = VertexStiffness(mesh, {2.0, 4.0});
  CHECK(at_vertex == std::vector<double>{2.0, 3.0, 3.0, 4.0});
  CHECK(ElementStiffness(mesh, at_vertex) == std::vector<double>{8.0 / 3.0, 10.0 / 3.0});
  CHECK(VertexStiffness(mesh, {}).empty());
  CHECK_NOTHROW(ValidateStiffness({}, mesh, "x"));
  CHECK_THROWS_AS(ValidateStiffness({1.0}, mesh, "x"), InputError);
}
