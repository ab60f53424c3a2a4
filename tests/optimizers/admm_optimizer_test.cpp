// SPDX-License-Identifier: MIT
// admm_pd and wrapd (flat and as hierarchical's inner optimizer) on a small twisted and stretched
// tetrahedral box, against classic local/global's converged per-element ARAP energy.
#include <Eigen/Geometry>
#include <catch2/catch.hpp>

#include "framework/error.h"
#include "solvers/optimizers/local_global_solver.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

/// A 2×1×1 box, the x = 0 face held, the x = 2 face turned by 50° about the x axis and pulled
/// out by 0.3: twist and stretch. Jittered so the elements are irregular.
struct TwistedBox {
  Mesh mesh;
  DeformationProblem problem;

  explicit TwistedBox(Mesh box) : mesh(std::move(box)) {
    mesh.vertices.col(0) *= 2.0;
    problem.mesh = &mesh;
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(50.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
    const Eigen::Vector3d centre(0.0, 0.5, 0.5);
    std::vector<Eigen::Vector3d> targets;
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      const Eigen::Vector3d p = mesh.vertices.row(v);
      if (p.x() < 1e-9) {
        problem.constraints.indices.push_back(v);
        targets.push_back(p);
      } else if (p.x() > 2.0 - 1e-9) {
        problem.constraints.indices.push_back(v);
        targets.push_back(turn * (p - centre) + centre + Eigen::Vector3d(0.3, 0.0, 0.0));
      }
    }
    problem.constraints.targets.resize(static_cast<Index>(targets.size()), 3);
    for (size_t k = 0; k < targets.size(); ++k) {
      problem.constraints.targets.row(static_cast<Index>(k)) = targets[k].transpose();
    }
  }
  TwistedBox(const TwistedBox&) = delete;
  TwistedBox& operator=(const TwistedBox&) = delete;
};

Mesh SmallBox() { return TetBox(9, 5, 5, 6); }

std::string Config(const std::string& optimizer, const std::string& options) {
  return fmt::format(
      "[optimizer]\ntype = \"{}\"\n{}\n[energy]\ntype = \"elements\"\n"
      "[hierarchy]\nmin_vertices = 30\n",
      optimizer, options);
}

/// classic local/global run to a displacement of 1e-14 diag²: the reference minimum.
double ClassicMinimum(const DeformationProblem& problem) {
  const TestSetup setup(Config("classic", "tolerance = 1e-14\nmax_iterations = 20000"));
  const OptimizeResult result = setup.MakeOptimizer()->Optimize(problem, setup.factory, Context());
  REQUIRE(result.converged);
  return result.energy;
}

struct TracedRun {
  OptimizeResult result;
  std::vector<IterationSummary> trace;
};

TracedRun Run(const std::string& toml, const DeformationProblem& problem) {
  const TestSetup setup(toml);
  TracedRun run;
  Context context;
  context.iteration_callback = [&](const IterationSummary& summary) {
    run.trace.push_back(summary);
    return CallbackAction::kContinue;
  };
  run.result = setup.MakeOptimizer()->Optimize(problem, setup.factory, context);
  return run;
}

void CheckConstraintsExact(const DeformationProblem& problem, const Positions& u) {
  for (size_t k = 0; k < problem.constraints.indices.size(); ++k) {
    CHECK(u.row(problem.constraints.indices[k]) ==
          problem.constraints.targets.row(static_cast<Index>(k)));
  }
}

}  // namespace

TEST_CASE("admm_pd and wrapd reach the local/global minimum of the per-element energy",
          "[optimizers][admm]") {
  const TwistedBox box(Jittered(SmallBox(), 5, 0.15, 7));
  const double minimum = ClassicMinimum(box.problem);
  const double start = FittedElementEnergy(box.mesh, InitialPositions(box.problem));
  REQUIRE(minimum < 0.5 * start);
  for (const char* optimizer : {"admm_pd", "wrapd"}) {
    SECTION(optimizer) {
      const TracedRun run =
          Run(Config(optimizer, "tolerance = 1e-12\nmax_iterations = 3000"), box.problem);
      const OptimizeResult& r = run.result;
      INFO(optimizer << ": energy " << r.energy << " after " << r.iterations
                     << " iterations, local/global minimum " << minimum);
      // ADMM converges linearly to a stationary point of E; the box has one minimum (mild
      // twist), so the ADMM energy must approach local/global's from above. 1e-6 relative is far
      // above round-off (classic is converged to 1e-14 displacement) and far below the distance
      // of any non-converged iterate (the start is > 2× the minimum).
      CHECK(r.energy >= minimum * (1.0 - 1e-9));
      CHECK(r.energy <= minimum * (1.0 + 1e-6));
      CHECK(r.converged);
      // The reported energy is the `elements` energy of the returned positions.
      CHECK(r.energy == Approx(FittedElementEnergy(box.mesh, r.positions)).epsilon(1e-12));
      REQUIRE(r.measures.count("energy_wrapd") == 1);
      CHECK(r.measures.at("energy_wrapd") == Approx(r.energy / 2).epsilon(1e-9));
      CheckConstraintsExact(box.problem, r.positions);
      REQUIRE(r.levels.size() == 1);
      CHECK(r.levels[0].Measure("inverted_elements") == 0);
      REQUIRE(static_cast<int>(run.trace.size()) == r.iterations);
      for (const IterationSummary& s : run.trace) CHECK(s.inverted_elements >= 0);
      // The last trace energy is the own evaluation of the same energy.
      CHECK(run.trace.back().energy == Approx(r.energy).epsilon(1e-9));
    }
  }
}

TEST_CASE("admm_pd counts inverted elements", "[optimizers][admm]") {
  // Push the x = 2 face through the held x = 0 face: the start has inverted elements, which the
  // trace must report; the run may stop at the cap but never reports a negative count.
  TwistedBox box(SmallBox());
  for (Index k = 0; k < box.problem.constraints.targets.rows(); ++k) {
    if (box.problem.constraints.targets(k, 0) > 1.0) box.problem.constraints.targets(k, 0) = -0.5;
  }
  const TracedRun run = Run(Config("admm_pd", "max_iterations = 3"), box.problem);
  REQUIRE(run.trace.size() == 3u);
  CHECK(run.trace.front().inverted_elements > 0);
  CHECK(run.result.levels[0].Measure("inverted_elements") == run.trace.back().inverted_elements);
  CHECK_FALSE(run.result.converged);
}

TEST_CASE("admm_pd on a planar mesh reaches the local/global minimum", "[optimizers][admm]") {
  Mesh grid = PlanarGrid(13, 7);
  grid.vertices.col(0) *= 2.0;
  DeformationProblem problem;
  problem.mesh = &grid;
  std::vector<Eigen::Vector3d> targets;
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(M_PI / 8, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (Index v = 0; v < grid.num_vertices(); ++v) {
    const Eigen::Vector3d p = grid.vertices.row(v);
    if (p.x() < 1e-9 || p.x() > 2.0 - 1e-9) {
      problem.constraints.indices.push_back(v);
      targets.push_back(p.x() < 1e-9 ? p
                                     : Eigen::Vector3d(turn * p + Eigen::Vector3d(0.2, 0.1, 0)));
    }
  }
  problem.constraints.targets.resize(static_cast<Index>(targets.size()), 3);
  for (size_t k = 0; k < targets.size(); ++k) {
    problem.constraints.targets.row(static_cast<Index>(k)) = targets[k].transpose();
  }
  const double minimum = ClassicMinimum(problem);
  const TracedRun run = Run(Config("admm_pd", "tolerance = 1e-12\nmax_iterations = 5000"), problem);
  INFO("energy " << run.result.energy << " after " << run.result.iterations
                 << " iterations (converged " << run.result.converged << "), minimum " << minimum);
  CHECK(run.result.energy <= minimum * (1.0 + 1e-6));
  CHECK(run.result.energy >= minimum * (1.0 - 1e-9));
  CHECK(run.result.positions.col(2).isZero(0.0));
  CheckConstraintsExact(problem, run.result.positions);
  // wrapd is for tetrahedra.
  CHECK_THROWS_AS(Run(Config("wrapd", ""), problem), InputError);
}

TEST_CASE("hierarchical with inner admm_pd and wrapd", "[optimizers][admm]") {
  const TwistedBox box(TetBox(17, 9, 9, 6));
  const double minimum = ClassicMinimum(box.problem);
  for (const char* inner : {"admm_pd", "wrapd"}) {
    SECTION(inner) {
      const TracedRun flat =
          Run(Config(inner, "tolerance = 1e-9\nmax_iterations = 2000"), box.problem);
      const TracedRun hierarchical =
          Run(Config("hierarchical",
                     fmt::format("inner = \"{}\"\ntolerance = 1e-9\nmax_iterations = 2000", inner)),
              box.problem);
      const OptimizeResult& h = hierarchical.result;
      INFO(inner << ": hierarchical " << h.energy << " (" << h.levels.size() << " levels, "
                 << h.iterations << " finest iterations), flat " << flat.result.energy << " ("
                 << flat.result.iterations << "), minimum " << minimum);
      REQUIRE(h.levels.size() >= 2);
      CHECK(h.converged);
      // Both stop on the same relative-change test; the energies agree with the minimum to well
      // within the 1e-4 the issue asks of WRAPD comparisons.
      CHECK(h.energy <= minimum * (1.0 + 1e-4));
      CHECK(flat.result.energy <= minimum * (1.0 + 1e-4));
      CHECK(h.measures.count("energy_wrapd") == 1);
      CheckConstraintsExact(box.problem, h.positions);
      for (const LevelResult& level : h.levels) CHECK(level.Measure("inverted_elements") >= 0);
      // Every level reported its iterations through the callback, coarsest first.
      REQUIRE_FALSE(hierarchical.trace.empty());
      CHECK(hierarchical.trace.front().level == static_cast<int>(h.levels.size()) - 1);
      CHECK(hierarchical.trace.back().level == 0);
    }
  }
}

TEST_CASE("ADMM options are validated", "[optimizers][admm]") {
  const auto message = [](const std::string& toml) {
    try {
      (void)TestSetup(toml).MakeOptimizer();
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(message(Config("admm_pd", "beta = 0")), Catch::Contains("beta"));
  CHECK_THAT(message(Config("admm_pd", "tolerance = -1")), Catch::Contains("tolerance"));
  CHECK_THAT(message(Config("admm_pd", "patience = 0")), Catch::Contains("patience"));
  CHECK_THAT(message(Config("wrapd", "lbfgs_history = 0")), Catch::Contains("lbfgs_history"));
  CHECK_THAT(message(Config("wrapd", "lbfgs_iterations = 0")), Catch::Contains("lbfgs_iterations"));
  // L-BFGS keys belong to wrapd only; unknown keys are rejected naming the key.
  CHECK_THAT(message(Config("admm_pd", "lbfgs_history = 4")), Catch::Contains("lbfgs_history"));
  CHECK_THAT(message(Config("wrapd", "betta = 2")), Catch::Contains("betta"));
  CHECK_THAT(message(Config("hierarchical", "inner = \"adm\"")), Catch::Contains("inner"));
  CHECK_THAT(message(Config("hierarchical", "inner = \"wrapd\"\nbeta = -2")),
             Catch::Contains("beta"));
  // A surface energy is not the per-element energy ADMM minimizes.
  const TwistedBox box(SmallBox());
  const TestSetup spokes("[optimizer]\ntype = \"admm_pd\"\n[energy]\ntype = \"spokes\"\n");
  CHECK_THROWS(spokes.MakeOptimizer()->Optimize(box.problem, spokes.factory, Context()));
}
