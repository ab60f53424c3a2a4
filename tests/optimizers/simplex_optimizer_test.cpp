// SPDX-License-Identifier: MIT
// classic and hierarchical with the per-element energy on tetrahedral and planar meshes
// (Section 6 of the paper), with every registered linear solver.
#include <Eigen/Geometry>
#include <catch2/catch.hpp>

#include "framework/error.h"
#include "solvers/optimizers/local_global_solver.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

/// A mesh with one end held and the other turned and shifted.
struct BentBar {
  Mesh mesh;
  DeformationProblem problem;

  BentBar(Mesh bar, double length) : mesh(std::move(bar)) {
    mesh.vertices.col(0) *= length;
    problem.mesh = &mesh;
    // Planar meshes turn in their plane, volumes about y.
    const Eigen::Vector3d axis = mesh.planar ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(M_PI / 3, axis).toRotationMatrix();
    const Eigen::Vector3d shift =
        mesh.planar ? Eigen::Vector3d(-0.5, 1.0, 0.0) : Eigen::Vector3d(-0.5, 0.0, 1.0);
    std::vector<Eigen::Vector3d> targets;
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      const Eigen::Vector3d p = mesh.vertices.row(v);
      if (p.x() == 0.0) {
        problem.constraints.indices.push_back(v);
        targets.push_back(p);
      } else if (p.x() == length) {
        problem.constraints.indices.push_back(v);
        targets.push_back(turn * p + shift);
      }
    }
    problem.constraints.targets.resize(targets.size(), 3);
    for (size_t k = 0; k < targets.size(); ++k) {
      problem.constraints.targets.row(k) = targets[k].transpose();
    }
  }
};

BentBar TetBar() { return BentBar(TetBox(25, 6, 6, 5), 4.0); }
BentBar PlanarStrip() { return BentBar(PlanarGrid(48, 12), 4.0); }

std::string RunConfig(const std::string& optimizer, const std::string& solver,
                      const std::string& extra = "") {
  return fmt::format(
      "[optimizer]\ntype = \"{}\"\ntolerance = 1e-7\n{}\n[energy]\ntype = \"elements\"\n"
      "[solver]\ntype = \"{}\"\n[hierarchy]\nmin_vertices = 40\n",
      optimizer, extra, solver);
}

}  // namespace

TEST_CASE("classic and hierarchical: tetrahedral and planar meshes with every solver",
          "[optimizers]") {
  const std::vector<std::string> solvers = MakeBuiltinRegistries().linear_solvers.Names();
  REQUIRE(solvers.size() >= 2);
  for (bool planar : {false, true}) {
    const BentBar bar = planar ? PlanarStrip() : TetBar();
    const Positions start = InitialPositions(bar.problem);
    const double start_energy = FittedElementEnergy(bar.mesh, start);
    std::map<std::string, OptimizeResult> reference;  // per optimizer, first solver
    for (const char* optimizer : {"classic", "hierarchical"}) {
      for (const auto& solver : solvers) {
        DYNAMIC_SECTION((planar ? "planar " : "tetrahedra ") << optimizer << " " << solver) {
          // Fixed coarse targets make each level a plain local/global descent.
          const TestSetup setup(RunConfig(
              optimizer, solver,
              std::string(optimizer) == "hierarchical" ? "targets_follow_rotations = false" : ""));
          std::vector<IterationSummary> trace;
          Context context;
          context.iteration_callback = [&](const IterationSummary& s) {
            trace.push_back(s);
            return CallbackAction::kContinue;
          };
          const OptimizeResult result =
              setup.MakeOptimizer()->Optimize(bar.problem, setup.factory, context);
          CHECK(result.converged);
          CHECK(std::isfinite(result.energy));
          CHECK(result.energy < 0.5 * start_energy);
          if (std::string(optimizer) == "hierarchical") CHECK(result.levels.size() >= 3);
          // Monotone within each level (the local and the global step each minimize).
          for (size_t i = 1; i < trace.size(); ++i) {
            if (trace[i].level != trace[i - 1].level) continue;
            CHECK(trace[i].energy <= trace[i - 1].energy * (1.0 + 1e-12));
          }
          CHECK(result.energy ==
                Approx(FittedElementEnergy(bar.mesh, result.positions)).epsilon(1e-10));
          REQUIRE(result.measures.count("energy_wrapd") == 1);
          CHECK(result.measures.at("energy_wrapd") == Approx(0.5 * result.energy).epsilon(1e-9));
          for (size_t k = 0; k < bar.problem.constraints.indices.size(); ++k) {
            CHECK(result.positions.row(bar.problem.constraints.indices[k]) ==
                  bar.problem.constraints.targets.row(k));
          }
          // A planar problem stays exactly in its plane.
          if (planar) CHECK(result.positions.col(2).cwiseAbs().maxCoeff() == 0.0);
        }
      }
    }
  }
}

TEST_CASE("classic and hierarchical reach the same minimum on a tetrahedral bar", "[optimizers]") {
  const BentBar bar = TetBar();
  const TestSetup classic(RunConfig("classic", "cholmod"));
  const TestSetup hierarchical(RunConfig("hierarchical", "cholmod"));
  const OptimizeResult a =
      classic.MakeOptimizer()->Optimize(bar.problem, classic.factory, Context());
  const OptimizeResult b =
      hierarchical.MakeOptimizer()->Optimize(bar.problem, hierarchical.factory, Context());
  CHECK(b.levels.size() >= 3);
  CHECK(b.energy == Approx(a.energy).epsilon(1e-3));
  // The hierarchy's head start: fewer finest-level iterations than classic.
  CHECK(b.iterations < a.iterations);
}

TEST_CASE("hierarchical with a one-level hierarchy reproduces classic on tetrahedra",
          "[optimizers]") {
  const BentBar bar = TetBar();
  const TestSetup classic(RunConfig("classic", "cholmod"));
  const TestSetup hierarchical(RunConfig("hierarchical", "cholmod") + "max_levels = 1\n");
  const OptimizeResult a =
      classic.MakeOptimizer()->Optimize(bar.problem, classic.factory, Context());
  const OptimizeResult b =
      hierarchical.MakeOptimizer()->Optimize(bar.problem, hierarchical.factory, Context());
  REQUIRE(b.levels.size() == 1);
  CHECK(a.iterations == b.iterations);
  CHECK(a.energy == b.energy);
  CHECK((a.positions - b.positions).cwiseAbs().maxCoeff() == 0.0);
}

TEST_CASE("hierarchical stopped on a coarse level reports the energy of its finest positions",
          "[optimizers]") {
  const BentBar bar = TetBar();
  const TestSetup setup(RunConfig("hierarchical", "cholmod"));
  Context context;
  context.iteration_callback = [](const IterationSummary& s) {
    return s.level > 0 && s.iteration == 2 ? CallbackAction::kStop : CallbackAction::kContinue;
  };
  const OptimizeResult result =
      setup.MakeOptimizer()->Optimize(bar.problem, setup.factory, context);
  CHECK(result.stopped_by_callback);
  REQUIRE(result.positions.rows() == bar.mesh.num_vertices());
  CHECK(result.energy == Approx(FittedElementEnergy(bar.mesh, result.positions)).epsilon(1e-10));
  CHECK(result.measures.at("energy_wrapd") == Approx(0.5 * result.energy).epsilon(1e-9));
}

TEST_CASE("planar meshes: targets off the plane are an input error", "[optimizers]") {
  BentBar strip = PlanarStrip();
  strip.problem.constraints.targets(0, 2) = 0.1;
  const TestSetup setup(RunConfig("classic", "cholmod"));
  CHECK_THROWS_WITH(setup.MakeOptimizer()->Optimize(strip.problem, setup.factory, Context()),
                    Catch::Contains("planar") && Catch::Contains("target"));
}

TEST_CASE("degenerate rest tetrahedra: their lone vertices stay, the rest solves", "[optimizers]") {
  BentBar bar = TetBar();
  // A flat tetrahedron on the bar's top face, at a new vertex in that face.
  Mesh& mesh = bar.mesh;
  const Index n = mesh.num_vertices();
  Index top[3];
  int found = 0;
  for (Index v = 0; v < n && found < 3; ++v) {
    if (mesh.vertices(v, 2) == 1.0 && mesh.vertices(v, 0) > 1.0) top[found++] = v;
  }
  REQUIRE(found == 3);
  Positions vertices(n + 1, 3);
  vertices << mesh.vertices, mesh.vertices.row(top[0]) + Eigen::RowVector3d(0.05, 0.05, 0.0);
  mesh.vertices = vertices;
  Elements elements(mesh.num_elements() + 1, 4);
  elements << mesh.elements, top[0], top[1], top[2], n;
  mesh.elements = elements;
  for (const char* optimizer : {"classic", "hierarchical"}) {
    DYNAMIC_SECTION(optimizer) {
      const TestSetup setup(RunConfig(optimizer, "cholmod"));
      const OptimizeResult result =
          setup.MakeOptimizer()->Optimize(bar.problem, setup.factory, Context());
      CHECK(result.converged);
      CHECK(std::isfinite(result.energy));
      CHECK(result.constraints.isolated_vertices == 1);
      CHECK(result.positions.allFinite());
      // classic keeps it at its start (hierarchical: where up-sampling put it).
      if (std::string(optimizer) == "classic") {
        CHECK(result.positions.row(n) == mesh.vertices.row(n));
      }
    }
  }
}
