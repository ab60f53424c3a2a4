// SPDX-License-Identifier: MIT
#include "solvers/optimizers/hierarchical_optimizer.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <string>

#include "solvers/optimizers/coarse_constraints.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

// A long tube (≈ 4000 vertices, height 4, radius 0.25) with its bottom ring fixed and its top
// ring turned and shifted.
struct LongBentTube : BentTube {
  LongBentTube() : BentTube(100, 40, 4.0, M_PI / 2, Eigen::Vector3d(0.0, 1.0, -1.5)) {}
};

}  // namespace

TEST_CASE("hierarchical with a one-level hierarchy reproduces classic exactly", "[optimizers]") {
  LongBentTube tube;
  TestSetup classic("[optimizer]\ntype = \"classic\"\ntolerance = 1e-7\n");
  TestSetup hierarchical(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-7\n[hierarchy]\nmax_levels = 1\n");
  const OptimizeResult a =
      classic.MakeOptimizer()->Optimize(tube.problem, classic.factory, Context());
  const OptimizeResult b =
      hierarchical.MakeOptimizer()->Optimize(tube.problem, hierarchical.factory, Context());
  REQUIRE(b.levels.size() == 1);
  CHECK(a.iterations == b.iterations);
  CHECK(a.energy == b.energy);
  CHECK((a.positions - b.positions).cwiseAbs().maxCoeff() == 0.0);
}

TEST_CASE("hierarchical: setting finer levels up in the background changes no result",
          "[optimizers]") {
  LongBentTube tube;
  const auto run = [&](bool overlap, int threads) {
    TestSetup setup(std::string("[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-7\n"
                                "overlap_setup = ") +
                    (overlap ? "true" : "false") + "\n[hierarchy]\nmin_vertices = 200\n");
    return setup.MakeOptimizer()->Optimize(tube.problem, setup.factory,
                                           Context::WithThreads(threads));
  };
  const OptimizeResult reference = run(false, 2);
  REQUIRE(reference.levels.size() >= 3);
  for (const int threads : {1, 2, 4}) {
    DYNAMIC_SECTION(threads << " threads") {
      const OptimizeResult overlapped = run(true, threads);
      REQUIRE(overlapped.levels.size() == reference.levels.size());
      for (size_t l = 0; l < reference.levels.size(); ++l) {
        CHECK(overlapped.levels[l].iterations == reference.levels[l].iterations);
        CHECK(overlapped.levels[l].energy == reference.levels[l].energy);
      }
      CHECK(overlapped.energy == reference.energy);
      CHECK((overlapped.positions - reference.positions).cwiseAbs().maxCoeff() == 0.0);
      CHECK(overlapped.timings.constrain > 0.0);
    }
  }
}

TEST_CASE("hierarchical: coarse_tolerance_factor scales the finest tolerance on the coarse levels",
          "[optimizers]") {
  LongBentTube tube;
  const auto run = [&](const std::string& options) {
    TestSetup setup("[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-5\n" + options +
                    "\n[hierarchy]\nmin_vertices = 200\n");
    return setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, Context());
  };
  const OptimizeResult plain = run("");
  // 0.5 × 1e-5 is 5e-6 to the last bit (a power of two), so the two runs must agree exactly.
  const OptimizeResult factor = run("coarse_tolerance_factor = 0.5");
  const OptimizeResult absolute = run("coarse_tolerance = 5e-6");
  REQUIRE(plain.levels.size() >= 3);
  REQUIRE(factor.levels.size() == plain.levels.size());
  REQUIRE(absolute.levels.size() == plain.levels.size());
  for (size_t l = 0; l < plain.levels.size(); ++l) {
    // The same solve as the absolute coarse tolerance it stands for, level by level.
    CHECK(factor.levels[l].iterations == absolute.levels[l].iterations);
    CHECK(factor.levels[l].energy == absolute.levels[l].energy);
  }
  // The coarsest level starts alike in both runs and stops later with the tighter tolerance.
  CHECK(factor.levels.back().iterations > plain.levels.back().iterations);
  // A coarse_tolerance set wins over the factor.
  const OptimizeResult both = run("coarse_tolerance = 1e-5\ncoarse_tolerance_factor = 0.5");
  CHECK(both.energy == plain.energy);
  CHECK(both.iterations == plain.iterations);
}

TEST_CASE("hierarchical: a stop requested on a coarse level still finishes the finest level",
          "[optimizers]") {
  LongBentTube tube;
  TestSetup setup(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-7\n[hierarchy]\nmin_vertices = 200\n");
  Context context = Context::WithThreads(2);
  context.iteration_callback = [](const IterationSummary& summary) {
    return summary.level > 0 && summary.iteration == 2 ? CallbackAction::kStop
                                                       : CallbackAction::kContinue;
  };
  const OptimizeResult result =
      setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, context);
  CHECK(result.stopped_by_callback);
  CHECK(result.positions.rows() == tube.mesh.num_vertices());
  CHECK(std::isfinite(result.energy));
  CHECK(result.constraints.constrained_vertices == 80);
}

TEST_CASE(
    "hierarchical ARAP: energy decreases within each level, constraints exact, levels "
    "reported",
    "[optimizers]") {
  LongBentTube tube;
  for (const char* upsampler : {"rotations", "positions", "smoothed_rotations"}) {
    DYNAMIC_SECTION("upsampler " << upsampler) {
      // Fixed coarse targets (targets_follow_rotations = false) make each level a plain
      // local/global run, which must be monotone.
      TestSetup setup(
          fmt::format("[optimizer]\ntype = \"hierarchical\"\ntolerance = "
                      "1e-7\ntargets_follow_rotations = false\n"
                      "[hierarchy]\nmin_vertices = 100\n[upsampler]\ntype = \"{}\"\n",
                      upsampler));
      EnergyTrace energies;
      const OptimizeResult result = OptimizeWithTrace(setup, tube.problem, energies);
      REQUIRE(result.levels.size() >= 3);
      CHECK(energies.size() == result.levels.size());
      CheckEnergiesNeverIncrease(energies);
      for (size_t l = 1; l < result.levels.size(); ++l) {
        CHECK(result.levels[l].vertices < result.levels[l - 1].vertices);
        CHECK(result.levels[l].level == static_cast<int>(l));
      }
      CHECK(result.levels[0].vertices == tube.mesh.num_vertices());
      CHECK(result.energy == result.levels[0].energy);
      for (size_t k = 0; k < tube.problem.constraints.indices.size(); ++k) {
        CHECK(result.positions.row(tube.problem.constraints.indices[k]) ==
              tube.problem.constraints.targets.row(k));
      }
      CHECK(result.converged);
      CHECK(result.timings.hierarchy > 0.0);
    }
  }
}

TEST_CASE("hierarchical ARAP reaches a lower energy than classic on a large bend", "[optimizers]") {
  LongBentTube tube;
  TestSetup classic("[optimizer]\ntype = \"classic\"\ntolerance = 1e-6\n");
  TestSetup hierarchical(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-6\n"
      "[hierarchy]\nmin_vertices = 100\n");
  const OptimizeResult a =
      classic.MakeOptimizer()->Optimize(tube.problem, classic.factory, Context());
  const OptimizeResult b =
      hierarchical.MakeOptimizer()->Optimize(tube.problem, hierarchical.factory, Context());
  CHECK(b.energy < a.energy);
}

TEST_CASE("coarse targets of a rigidly moved handle are the rigid motion of the coarse positions",
          "[optimizers]") {
  LongBentTube tube;
  const Registries registries = MakeBuiltinRegistries();
  ConfigNode options = ConfigNode::Parse("min_vertices = 100\n", "test");
  const MeshHierarchy hierarchy =
      registries.hierarchies.Create("octree", options)->Build(tube.mesh, Context());
  REQUIRE(hierarchy.num_levels() >= 3);
  // Every vertex of the top half moves rigidly.
  const Eigen::Matrix3d r = RandomRotation(9);
  const Eigen::RowVector3d t(0.5, -1.0, 2.0);
  Constraints constraints;
  for (Index v = 0; v < tube.mesh.num_vertices(); ++v) {
    if (tube.mesh.vertices(v, 2) > 2.0) constraints.indices.push_back(v);
  }
  constraints.targets.resize(constraints.indices.size(), 3);
  for (size_t k = 0; k < constraints.indices.size(); ++k) {
    constraints.targets.row(k) = tube.mesh.vertices.row(constraints.indices[k]) * r.transpose() + t;
  }
  for (int level = 1; level < hierarchy.num_levels(); ++level) {
    const Mesh& coarse = hierarchy.levels[level].mesh;
    const LevelConstraints mapped = MapConstraints(hierarchy, level, constraints);
    REQUIRE(!mapped.vertices.empty());
    Rotations rotations(coarse.num_vertices(), r);
    Positions positions = coarse.vertices;
    PlaceConstrainedVertices(mapped, RotationSite::kVertex, &rotations, positions);
    for (Index c : mapped.vertices) {
      const Eigen::RowVector3d expected = coarse.vertices.row(c) * r.transpose() + t;
      CHECK((positions.row(c) - expected).norm() < 1e-12);
    }
  }
}

TEST_CASE("hierarchical options are validated", "[optimizers]") {
  CHECK_THROWS_WITH(
      TestSetup("[optimizer]\ntype = \"hierarchical\"\nlevel_step = 0\n").MakeOptimizer(),
      Catch::Contains("level_step"));
  CHECK_THROWS_WITH(TestSetup("[optimizer]\ntype = \"hierarchical\"\ncoarse_tolerance_factor = 0\n")
                        .MakeOptimizer(),
                    Catch::Contains("coarse_tolerance_factor"));
  CHECK_THROWS_WITH(TestSetup("[optimizer]\ntype = \"hierarchical\"\nlevels = 2\n").MakeOptimizer(),
                    Catch::Contains("level_step") && Catch::Contains("levels"));
  // The option's former name says what it is called now, and where it was written.
  CHECK_THROWS_WITH(TestSetup("[optimizer]\ntype = \"hierarchical\"\nupdate_constraints = false\n")
                        .MakeOptimizer(),
                    Catch::Contains("test config:3:") &&
                        Catch::Contains("'optimizer.update_constraints'") &&
                        Catch::Contains("'targets_follow_rotations'"));
  const TestSetup fixed_targets("[optimizer]\ntargets_follow_rotations = false\n");
  CHECK_FALSE(HierarchicalOptimizer::Options::FromConfig(
                  OptionReader(fixed_targets.config.Child("optimizer")),
                  fixed_targets.registries.level_solvers)
                  .targets_follow_rotations);
}
