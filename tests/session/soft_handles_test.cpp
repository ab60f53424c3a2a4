// SPDX-License-Identifier: MIT
// Soft handles (Constraints::weights) in an interactive session: the same problem as a one-shot
// run, moved without refactoring, previewed, and edited.
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "api/session.h"
#include "framework/error.h"
#include "tests/session/session_test_support.h"

using namespace harap;
using namespace harap::testing;

namespace {

constexpr Index kSegments = 16;  // SmallBentTube's vertices per ring

// The tube's constraints with the top ring soft (weight `weight`), the bottom ring hard.
Constraints SoftTop(const Constraints& hard, double weight) {
  Constraints soft = hard;
  soft.weights.assign(soft.indices.size(), Constraints::kHardWeight);
  for (size_t k = 0; k < soft.indices.size(); ++k) {
    if (soft.indices[k] >= kSegments) soft.weights[k] = weight;
  }
  return soft;
}

// A session on `mesh` with the handles `handles` (weights included) set.
std::unique_ptr<ConfiguredSession> SessionWith(const TestSetup& setup, const Mesh& mesh,
                                               const Constraints& handles) {
  auto configured = Session(setup, mesh);
  configured->session().SetHandles(handles.indices, handles.targets, handles.weights);
  return configured;
}

// A session built directly, its context counting the factorizations of every level.
struct CountingSession {
  CountingSession(const TestSetup& setup, const Mesh& mesh)
      : options(SessionOptions::FromConfig(OptionReader(setup.config.Child("optimizer")),
                                           setup.registries.level_solvers)),
        context(Counting()),
        session(mesh, setup.factory, options, context) {}
  Context Counting() {
    Context counting = Context::WithThreads(2);
    counting.system_callback = [this](int, const SparseMatrix&) { ++factorizations; };
    return counting;
  }
  std::atomic<int> factorizations{0};
  SessionOptions options;
  Context context;
  DeformationSession session;
};

double MaxDistance(const Positions& positions, const Constraints& constraints) {
  double largest = 0.0;
  for (size_t k = 0; k < constraints.indices.size(); ++k) {
    largest = std::max(largest, (positions.row(constraints.indices[k]) -
                                 constraints.targets.row(static_cast<Index>(k)))
                                    .norm());
  }
  return largest;
}

}  // namespace

TEST_CASE("session: soft handles solve like the one-shot run", "[session][soft]") {
  SmallBentTube tube;
  DeformationProblem problem = tube.problem;
  problem.constraints = SoftTop(tube.problem.constraints, 20.0);
  for (const char* config : {kClassic, kHierarchical}) {
    DYNAMIC_SECTION(config) {
      TestSetup setup(config);
      const OptimizeResult reference =
          setup.MakeOptimizer()->Optimize(problem, setup.factory, Context::WithThreads(2));
      auto configured = Session(setup, tube.mesh);
      DeformationSession& session = configured->session();
      const Constraints& c = problem.constraints;
      const HandleEditResult edit = session.SetHandles(c.indices, c.targets, c.weights);
      CHECK(edit.constraints.constrained_vertices == kSegments);  // the hard ring
      CHECK(session.weights() == c.weights);
      const OptimizeResult result = session.Solve();
      if (std::string(config) == kHierarchical) CHECK(result.levels.size() >= 3);
      CheckSameSolve(result, reference, 1e-9);
      // The soft ring is pulled, not pinned.
      CHECK(MaxDistance(result.positions, c) > 1e-6);
    }
  }
}

TEST_CASE("session: soft handles with a very large weight reproduce hard handles",
          "[session][soft]") {
  SmallBentTube tube;
  const Constraints& hard = tube.problem.constraints;
  const Constraints soft = SoftTop(hard, 1e9);
  for (const char* optimizer : {"classic", "hierarchical"}) {
    DYNAMIC_SECTION(optimizer) {
      TestSetup setup(
          fmt::format("[optimizer]\ntype = \"{}\"\ntolerance = 1e-12\nmax_iterations = 3000\n"
                      "[hierarchy]\nmin_vertices = 60\n",
                      optimizer));
      auto hard_session = Session(setup, tube.mesh);
      hard_session->session().SetHandles(hard.indices, hard.targets);
      const OptimizeResult hard_result = hard_session->session().Solve();
      auto soft_session = Session(setup, tube.mesh);
      soft_session->session().SetHandles(soft.indices, soft.targets, soft.weights);
      const OptimizeResult soft_result = soft_session->session().Solve();
      INFO("hard " << hard_result.energy << ", soft " << soft_result.energy);
      CHECK(Close(soft_result.energy, hard_result.energy, 1e-6));
      CHECK(MaxDistance(soft_result.positions, soft) < 1e-6);
    }
  }
}

TEST_CASE("session: SetTargets moves soft targets without refactoring", "[session][soft]") {
  SmallBentTube tube;
  const Constraints soft = SoftTop(tube.problem.constraints, 5.0);
  // Every handle moves: the hard ring a little, the soft ring further.
  Positions moved = soft.targets;
  for (Index k = 0; k < moved.rows(); ++k) {
    moved.row(k) += soft.indices[k] >= kSegments ? Eigen::RowVector3d(0.2, -0.1, 0.3)
                                                 : Eigen::RowVector3d(0.0, 0.05, 0.0);
  }
  for (const char* config : {kClassic, kHierarchical}) {
    DYNAMIC_SECTION(config) {
      TestSetup setup(config);
      CountingSession counting(setup, tube.mesh);
      DeformationSession& session = counting.session;
      const HandleEditResult edit = session.SetHandles(soft.indices, soft.targets, soft.weights);
      const int after_constrain = counting.factorizations;
      CHECK(after_constrain == static_cast<int>(edit.levels.size()));
      session.Solve();
      session.SetTargets(moved);
      session.Preview();
      session.Solve();
      CHECK(counting.factorizations == after_constrain);
      CHECK(session.targets() == moved);
      CHECK(session.weights() == soft.weights);
      // From the rest positions again: the moved targets on every level are those a fresh
      // session maps from them.
      session.SetPositions(tube.mesh.vertices);
      const OptimizeResult result = session.Solve();
      CHECK(counting.factorizations == after_constrain);

      auto fresh = SessionWith(setup, tube.mesh, Constraints{soft.indices, moved, soft.weights});
      const OptimizeResult expected = fresh->session().Solve();
      CheckSameSolve(result, expected, 1e-10);
    }
  }
}

TEST_CASE("session: a preview with soft handles works and says how", "[session][soft]") {
  SmallBentTube tube;
  const Constraints soft = SoftTop(tube.problem.constraints, 5.0);
  TestSetup setup(kHierarchical);
  auto configured = SessionWith(setup, tube.mesh, soft);
  DeformationSession& session = configured->session();
  const OptimizeResult preview = session.Preview();
  CHECK(preview.positions.allFinite());
  bool noted = false;
  for (const std::string& note : preview.notes) {
    noted = noted || note.find("soft handles") != std::string::npos;
  }
  CHECK(noted);
  // The hard ring at its targets, the soft one pulled towards its own.
  for (Index s = 0; s < kSegments; ++s) {
    CHECK((preview.positions.row(s) - soft.targets.row(s)).norm() < 1e-9);
  }
  CHECK(MaxDistance(preview.positions, soft) < MaxDistance(tube.mesh.vertices, soft));
  // The same preview without soft handles takes the gathered step and has no such note.
  auto hard = Session(setup, tube.mesh);
  hard->session().SetHandles(soft.indices, soft.targets);
  for (const std::string& note : hard->session().Preview().notes) {
    CHECK(note.find("soft handles") == std::string::npos);
  }
}

TEST_CASE("session: handle edits keep the soft weights", "[session][soft]") {
  SmallBentTube tube;
  const Constraints soft = SoftTop(tube.problem.constraints, 5.0);
  std::vector<Index> ring;
  for (Index s = 0; s < kSegments; ++s) ring.push_back(15 * kSegments + s);
  Positions ring_targets(kSegments, 3);
  for (Index s = 0; s < kSegments; ++s) ring_targets.row(s) = tube.mesh.vertices.row(ring[s]);
  TestSetup setup(kHierarchical);
  auto configured = SessionWith(setup, tube.mesh, soft);
  DeformationSession& session = configured->session();
  session.Solve();
  // Added handles are hard; removing them gives the soft set back.
  const HandleEditResult added = session.AddHandles(ring, ring_targets);
  CHECK(added.constraints.constrained_vertices == 2 * kSegments);
  REQUIRE(session.weights().size() == soft.indices.size() + ring.size());
  CHECK(session.weights().back() == Constraints::kHardWeight);
  CHECK(std::isfinite(session.Solve().energy));
  const HandleEditResult removed = session.RemoveHandles(ring);
  CHECK(removed.constraints.constrained_vertices == kSegments);
  CHECK(session.weights() == soft.weights);
  // All hard again: the same as a session that never had soft handles.
  session.SetHandles(soft.indices, soft.targets,
                     std::vector<double>(soft.indices.size(), Constraints::kHardWeight));
  CHECK(session.weights().empty());
}

TEST_CASE("session: other soft weights refactor only the rows they change", "[session][soft]") {
  SmallBentTube tube;
  const Constraints soft = SoftTop(tube.problem.constraints, 5.0);
  // Heavier soft handles, and a second soft ring (the middle one) with its own weight.
  Constraints heavier = soft;
  for (double& w : heavier.weights) {
    if (w != Constraints::kHardWeight) w = 50.0;
  }
  for (Index s = 0; s < kSegments; ++s) {
    heavier.indices.push_back(15 * kSegments + s);
    heavier.weights.push_back(2.0);
  }
  heavier.targets.conservativeResize(static_cast<Index>(heavier.indices.size()), 3);
  for (Index s = 0; s < kSegments; ++s) {
    heavier.targets.row(2 * kSegments + s) =
        tube.mesh.vertices.row(15 * kSegments + s) + Eigen::RowVector3d(0.1, 0.0, 0.0);
  }
  const std::vector<std::string> solvers = RefactorRouteSolvers();
  for (const char* config : {kClassic, kHierarchical}) {
    for (const std::string& solver : solvers) {
      DYNAMIC_SECTION(config << solver) {
        TestSetup setup(config + solver);
        auto configured = SessionWith(setup, tube.mesh, soft);
        DeformationSession& session = configured->session();
        session.Solve();
        const HandleEditResult reweighted =
            session.SetHandles(heavier.indices, heavier.targets, heavier.weights);
        REQUIRE_FALSE(reweighted.levels.empty());
        // The finest level: the diagonal of the 32 soft vertices, nothing else.
        CHECK(reweighted.levels[0].level == 0);
        CHECK(reweighted.levels[0].changed_rows == 2 * kSegments);
        for (const auto& level : reweighted.levels) {
          INFO("level " << level.level);
          CHECK(level.factored);
          CHECK(level.changed_rows > 0);
          if (solver.find("partial") != std::string::npos) {
            CHECK(level.route == LinearSolver::RefactorRoute::kPartial);
          }
          if (solver.find("update") != std::string::npos) {
            CHECK(level.route == LinearSolver::RefactorRoute::kUpdate);
          }
        }
        session.SetPositions(tube.mesh.vertices);
        const OptimizeResult result = session.Solve();
        auto fresh = SessionWith(setup, tube.mesh, heavier);
        const OptimizeResult expected = fresh->session().Solve();
        CheckSameSolve(result, expected, 1e-10);
      }
    }
  }
}

TEST_CASE("session: bad soft weights throw InputError naming the entry and change nothing",
          "[session][soft]") {
  SmallBentTube tube;
  const Constraints soft = SoftTop(tube.problem.constraints, 5.0);
  TestSetup setup(kClassic);
  auto configured = SessionWith(setup, tube.mesh, soft);
  DeformationSession& session = configured->session();
  const OptimizeResult before = session.Solve();
  for (const double bad : {std::nan(""), 0.0, -1.0, -std::numeric_limits<double>::infinity()}) {
    std::vector<double> weights = soft.weights;
    weights[20] = bad;
    INFO("weight " << bad);
    CHECK_THROWS_AS(session.SetHandles(soft.indices, soft.targets, weights), InputError);
    CHECK_THROWS_WITH(session.SetHandles(soft.indices, soft.targets, weights),
                      Catch::Contains("weight 20"));
  }
  CHECK_THROWS_WITH(session.SetHandles(soft.indices, soft.targets, std::vector<double>(3, 1.0)),
                    Catch::Contains("3 weights for 32 handle vertices"));
  CHECK(session.weights() == soft.weights);
  // The same problem, solved further from the last solution (local/global never goes up).
  const OptimizeResult after = session.Solve();
  CHECK(after.energy <= before.energy);
}

TEST_CASE("session: hundreds of small soft handle groups, hierarchical", "[session][soft]") {
  BentTube tube(100, 40, 4.0, M_PI / 2, Eigen::Vector3d(0.0, 1.0, -1.5));
  const Mesh& mesh = tube.mesh;
  // The ends hard; 300 groups of 3 neighbouring vertices on the side, each pulled outwards.
  const Constraints c = WithSoftGroups(tube, 40, 300, 5);

  TestSetup setup(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-8\n[hierarchy]\nmin_vertices = 200\n");
  CountingSession counting(setup, mesh);
  DeformationSession& session = counting.session;
  session.SetHandles(c.indices, c.targets, c.weights);
  const int factored = counting.factorizations;
  const OptimizeResult first = session.Solve();
  REQUIRE(first.levels.size() >= 3);
  CHECK(first.converged);
  // Every group moves a little further out: no refactoring, and the result is a fresh
  // session's with those targets.
  Positions moved = c.targets;
  for (size_t k = 0; k < c.indices.size(); ++k) {
    if (c.weights[k] == Constraints::kHardWeight) continue;
    Eigen::RowVector3d out = mesh.vertices.row(c.indices[k]);
    out.z() = 0.0;
    moved.row(static_cast<Index>(k)) += 0.03 * out;
  }
  session.SetTargets(moved);
  session.Preview();
  const OptimizeResult warm = session.Solve();
  CHECK(warm.converged);
  CHECK(counting.factorizations == factored);
  auto fresh = SessionWith(setup, mesh, Constraints{c.indices, moved, c.weights});
  const OptimizeResult expected = fresh->session().Solve();
  // Both converged to the tolerance from different starts.
  CHECK(Close(warm.energy, expected.energy, 1e-4));
  const Constraints moved_constraints{c.indices, moved, c.weights};
  for (size_t k = 0; k < c.indices.size(); ++k) {
    if (c.weights[k] != Constraints::kHardWeight) continue;
    CHECK(warm.positions.row(c.indices[k]) == moved.row(static_cast<Index>(k)));
  }
  CHECK(std::abs(MaxDistance(warm.positions, moved_constraints) -
                 MaxDistance(expected.positions, moved_constraints)) < 1e-3);
}
