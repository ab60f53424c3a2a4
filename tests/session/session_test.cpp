// SPDX-License-Identifier: MIT
#include "api/session.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "tests/session/session_test_support.h"

using namespace harap;
using namespace harap::testing;

TEST_CASE("session: the first solve equals the one-shot optimizer", "[session]") {
  SmallBentTube tube;
  for (const char* config : {kClassic, kHierarchical}) {
    DYNAMIC_SECTION(config) {
      TestSetup setup(config);
      const OptimizeResult reference =
          setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, Context::WithThreads(2));
      auto configured = Session(setup, tube.mesh);
      DeformationSession& session = configured->session();
      const HandleEditResult edit =
          session.SetHandles(tube.problem.constraints.indices, tube.problem.constraints.targets);
      CHECK(edit.levels.size() == reference.levels.size());
      const OptimizeResult result = session.Solve();
      REQUIRE(result.levels.size() == reference.levels.size());
      if (std::string(config) == kHierarchical) CHECK(result.levels.size() >= 3);
      for (size_t l = 0; l < result.levels.size(); ++l) {
        INFO("level " << result.levels[l].level);
        CHECK(result.levels[l].level == reference.levels[l].level);
        CHECK(result.levels[l].iterations == reference.levels[l].iterations);
        CHECK(result.levels[l].unknowns == reference.levels[l].unknowns);
        CHECK(Close(result.levels[l].energy, reference.levels[l].energy, 1e-10));
      }
      CHECK(Close(result.energy, reference.energy, 1e-10));
      CHECK((result.positions - reference.positions).cwiseAbs().maxCoeff() < 1e-8);
      CHECK(result.constraints.constrained_vertices == 32);
    }
  }
}

TEST_CASE("session: coarse_tolerance_factor scales a per-solve tolerance on the coarse levels",
          "[session]") {
  SmallBentTube tube;
  const std::string hierarchy = "max_iterations = 500\n[hierarchy]\nmin_vertices = 60\n";
  // The one-shot reference: the per-solve tolerance and its coarse multiple spelled out.
  TestSetup reference_setup(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-5\ncoarse_tolerance = 5e-6\n" +
      hierarchy);
  const OptimizeResult reference = reference_setup.MakeOptimizer()->Optimize(
      tube.problem, reference_setup.factory, Context::WithThreads(2));
  TestSetup setup(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-3\n"
      "coarse_tolerance_factor = 0.5\n" +
      hierarchy);
  auto configured = Session(setup, tube.mesh);
  DeformationSession& session = configured->session();
  session.SetHandles(tube.problem.constraints.indices, tube.problem.constraints.targets);
  SessionSolveOptions options;
  options.tolerance = 1e-5;
  const OptimizeResult result = session.Solve(options);
  REQUIRE(result.levels.size() == reference.levels.size());
  REQUIRE(result.levels.size() >= 3);
  for (size_t l = 0; l < result.levels.size(); ++l) {
    INFO("level " << result.levels[l].level);
    CHECK(result.levels[l].iterations == reference.levels[l].iterations);
  }
  CHECK(Close(result.energy, reference.energy, 1e-10));
}

TEST_CASE("session: after adding and removing handles a solve equals a fresh session's",
          "[session]") {
  SmallBentTube tube;
  const Constraints& handles = tube.problem.constraints;
  // A ring in the middle of the tube, pulled sideways.
  std::vector<Index> extra;
  for (Index s = 0; s < 16; ++s) extra.push_back(15 * 16 + s);
  Positions extra_targets(extra.size(), 3);
  for (size_t k = 0; k < extra.size(); ++k) {
    extra_targets.row(k) = tube.mesh.vertices.row(extra[k]) + Eigen::RowVector3d(0.3, 0.0, 0.0);
  }
  const Positions start = SmoothlyDeformed(tube.mesh.vertices, 0.05);
  const std::vector<std::string> solvers = RefactorRouteSolvers();
  for (const char* config : {kClassic, kHierarchical}) {
    for (const std::string& solver : solvers) {
      DYNAMIC_SECTION(config << solver) {
        TestSetup setup(config + solver);
        auto edited = Session(setup, tube.mesh);
        DeformationSession& session = edited->session();
        session.SetHandles(handles.indices, handles.targets);
        session.Solve();
        const HandleEditResult added = session.AddHandles(extra, extra_targets);
        CHECK(added.constraints.constrained_vertices == 48);
        for (const auto& level : added.levels) {
          INFO("level " << level.level);
          CHECK(level.factored);
          CHECK(level.changed_rows > 0);
          if (solver.find("partial") != std::string::npos) {
            CHECK(level.route == LinearSolver::RefactorRoute::kPartial);
          }
        }
        const OptimizeResult with_extra = session.Solve();
        CHECK(std::isfinite(with_extra.energy));
        const HandleEditResult removed = session.RemoveHandles(extra);
        CHECK(removed.constraints.constrained_vertices == 32);
        CHECK(session.handles() == handles.indices);
        CHECK(session.targets() == handles.targets);
        session.SetPositions(start);
        const OptimizeResult after_edits = session.Solve();

        auto fresh_session = Session(setup, tube.mesh);
        fresh_session->session().SetHandles(handles.indices, handles.targets);
        fresh_session->session().SetPositions(start);
        const OptimizeResult fresh = fresh_session->session().Solve();
        CheckSameSolve(after_edits, fresh, 1e-10);
      }
    }
  }
}

TEST_CASE("session: bad calls throw InputError, change nothing, and the session keeps working",
          "[session]") {
  SmallBentTube tube;
  TestSetup setup("[optimizer]\ntype = \"hierarchical\"\n[hierarchy]\nmin_vertices = 60\n");
  auto configured = Session(setup, tube.mesh);
  DeformationSession& session = configured->session();
  const Index n = tube.mesh.num_vertices();
  CHECK_THROWS_WITH(session.Solve(), Catch::Contains("no handles"));
  CHECK_THROWS_WITH(session.Preview(), Catch::Contains("no handles"));
  CHECK_THROWS_WITH(session.SetTargets(Positions::Zero(1, 3)), Catch::Contains("no handles"));
  const Constraints& handles = tube.problem.constraints;
  session.SetHandles(handles.indices, handles.targets);
  const OptimizeResult first = session.Solve({1e-8, -1, 0.0});
  REQUIRE(std::isfinite(first.energy));

  Positions nan_targets = handles.targets;
  nan_targets(3, 1) = std::nan("");
  Positions inf_targets = handles.targets;
  inf_targets(5, 2) = INFINITY;
  Positions bad_positions = tube.mesh.vertices;
  bad_positions(7, 0) = -INFINITY;
  std::vector<Index> duplicate = handles.indices;
  duplicate[1] = duplicate[0];
  std::vector<Index> out_of_range = handles.indices;
  out_of_range.back() = n;
  std::vector<Index> negative = handles.indices;
  negative[2] = -1;
  const std::vector<std::pair<std::string, std::function<void()>>> bad_calls = {
      {"targets for", [&] { session.SetTargets(handles.targets.topRows(5)); }},
      {"not finite", [&] { session.SetTargets(nan_targets); }},
      {"not finite", [&] { session.SetTargets(inf_targets); }},
      {"out of range", [&] { session.SetHandles(out_of_range); }},
      {"out of range", [&] { session.SetHandles(negative, handles.targets); }},
      {"given twice", [&] { session.SetHandles(duplicate); }},
      {"no vertex indices", [&] { session.SetHandles({}); }},
      {"targets for", [&] { session.SetHandles(handles.indices, handles.targets.topRows(3)); }},
      {"not finite", [&] { session.SetHandles(handles.indices, nan_targets); }},
      {"a handle already",
       [&] { session.AddHandles({handles.indices[0]}, Positions::Zero(1, 3)); }},
      {"targets for",
       [&] {
         session.AddHandles({200, 201}, Positions::Zero(1, 3));
       }},
      {"out of range", [&] { session.AddHandles({n + 5}, Positions::Zero(1, 3)); }},
      {"not finite", [&] { session.AddHandles({200}, nan_targets.row(3)); }},
      {"not a handle", [&] { session.RemoveHandles({200}); }},
      {"every handle", [&] { session.RemoveHandles(handles.indices); }},
      {"given twice",
       [&] {
         session.RemoveHandles({handles.indices[0], handles.indices[0]});
       }},
      {"positions for", [&] { session.SetPositions(Positions::Zero(3, 3)); }},
      {"not all finite", [&] { session.SetPositions(bad_positions); }},
      {"time budget",
       [&] {
         session.Solve({-1.0, -1, -2.0});
       }},
  };
  for (const auto& [message, call] : bad_calls) {
    INFO("expected an error containing '" << message << "'");
    CHECK_THROWS_AS(call(), InputError);
    CHECK_THROWS_WITH(call(), Catch::Contains(message));
    // Unchanged: the same handles and targets, and a solve from the converged state stays there.
    CHECK(session.handles() == handles.indices);
    CHECK(session.targets() == handles.targets);
    const OptimizeResult again = session.Solve({1e-8, -1, 0.0});
    INFO("energy " << again.energy << " after the bad call, " << first.energy << " before");
    CHECK(again.energy <= first.energy * (1 + 1e-12));
    CHECK(Close(again.energy, first.energy, 1e-4));
  }
}

TEST_CASE("session: a warm-started solve with unchanged targets takes very few iterations",
          "[session]") {
  SmallBentTube tube;
  TestSetup setup(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-6\n"
      "[hierarchy]\nmin_vertices = 60\n");
  for (const auto start :
       {SessionOptions::FrameStart::kUpsampled, SessionOptions::FrameStart::kPrevious,
        SessionOptions::FrameStart::kCorrected}) {
    DYNAMIC_SECTION("frame start " << static_cast<int>(start)) {
      auto configured = Session(setup, tube.mesh, start);
      DeformationSession& session = configured->session();
      session.SetHandles(tube.problem.constraints.indices, tube.problem.constraints.targets);
      const OptimizeResult first = session.Solve();
      const OptimizeResult second = session.Solve();
      INFO("first " << first.iterations << " iterations, second " << second.iterations);
      CHECK(first.iterations > 5);
      // The coarsest level always starts from its own solution; the finest from the up-sampled
      // coarse one in the cascade (as many iterations as a first solve), else from its own.
      CHECK(second.levels.back().iterations <= 2);
      CHECK(second.iterations <= 2);
      CHECK(second.converged);
      CHECK(second.energy <= first.energy * (1.0 + 1e-6));
    }
  }
}

TEST_CASE("session: moving targets, preview, time budget and a stopping callback", "[session]") {
  SmallBentTube tube;
  TestSetup setup(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-6\n"
      "[hierarchy]\nmin_vertices = 60\n");
  auto configured = Session(setup, tube.mesh);
  DeformationSession& session = configured->session();
  const Constraints& handles = tube.problem.constraints;
  session.SetHandles(handles.indices);  // targets: the rest positions
  CHECK(session.targets() == Positions(tube.mesh.vertices(handles.indices, Eigen::all)));
  const OptimizeResult rest = session.Solve();
  CHECK(rest.energy < 1e-20);
  // Move the handles halfway, then all the way: the solution follows.
  session.SetTargets(0.5 * (handles.targets + session.targets()));
  const OptimizeResult halfway = session.Solve();
  session.SetTargets(handles.targets);
  const OptimizeResult preview = session.Preview();
  CHECK(preview.iterations == 1);
  CHECK(std::isnan(preview.energy));
  const double preview_energy = session.CurrentEnergy();
  for (size_t k = 0; k < handles.indices.size(); ++k) {
    CHECK((preview.positions.row(handles.indices[k]) - handles.targets.row(k)).norm() == 0.0);
  }
  const OptimizeResult full = session.Solve();
  CHECK(halfway.energy > 0.0);
  CHECK(full.energy > halfway.energy);
  CHECK(preview_energy >= full.energy * (1.0 - 1e-9));
  CHECK(preview_energy < 10.0 * full.energy);
  CHECK(session.CurrentEnergy() == Approx(full.energy).epsilon(1e-9));
  CHECK(full.converged);

  // The preview gathered straight from the coarsest level equals the one up-sampled through
  // every level (a direct solver: the up-sampled positions are overwritten).
  {
    auto other_configured = Session(setup, tube.mesh);
    DeformationSession& other = other_configured->session();
    other.set_preview_straight(false);
    session.set_preview_straight(true);
    other.SetHandles(handles.indices);
    other.Solve();
    other.SetTargets(0.5 * (handles.targets + tube.mesh.vertices(handles.indices, Eigen::all)));
    other.Solve();
    other.SetTargets(handles.targets);
    const OptimizeResult through = other.Preview();
    CHECK((through.positions - preview.positions).cwiseAbs().maxCoeff() <=
          1e-12 * preview.positions.cwiseAbs().maxCoeff());
    CHECK(other.CurrentEnergy() == Approx(preview_energy).epsilon(1e-12));
  }

  // A budget that runs out at once still returns the handles at their targets.
  session.SetTargets(handles.targets * 1.01);
  const OptimizeResult rushed = session.Solve({-1.0, -1, 1e-9});
  CHECK_FALSE(rushed.converged);
  CHECK(rushed.levels.front().iterations == 1);
  CHECK(std::isfinite(rushed.energy));
  REQUIRE_FALSE(rushed.notes.empty());
  CHECK(rushed.notes.back().find("time budget") != std::string::npos);

  // A callback stops the solve; the next one without it converges.
  int calls = 0;
  session.set_iteration_callback([&](const IterationSummary&) {
    return ++calls == 2 ? CallbackAction::kStop : CallbackAction::kContinue;
  });
  session.SetTargets(handles.targets);
  const OptimizeResult stopped = session.Solve();
  CHECK(stopped.stopped_by_callback);
  CHECK(std::isfinite(stopped.energy));
  session.set_iteration_callback({});
  const OptimizeResult resumed = session.Solve();
  CHECK(resumed.converged);
  INFO("resumed " << resumed.energy << ", full " << full.energy);
  CHECK(resumed.energy <= full.energy * (1.0 + 1e-3));
  CHECK(Close(resumed.energy, full.energy, 1e-2));
}

TEST_CASE("session: a piece without handles is pinned with a note", "[session]") {
  const Mesh mesh = Concatenate(Tube(6, 8), Icosphere(1));
  TestSetup setup(kClassic);
  auto configured = Session(setup, mesh);
  DeformationSession& session = configured->session();
  const HandleEditResult edit = session.SetHandles({0, 1, 2, 40, 41});
  CHECK(edit.constraints.free_components == 1);
  REQUIRE(edit.notes.size() == 1);
  CHECK(edit.notes[0].find("pinned") != std::string::npos);
  Positions targets = session.targets();
  targets.col(0).array() += 0.1;
  session.SetTargets(targets);
  const OptimizeResult result = session.Solve();
  CHECK(std::isfinite(result.energy));
  CHECK(result.notes == edit.notes);
  // Adding a handle on the sphere unpins it.
  const HandleEditResult added =
      session.AddHandles({48 + 3}, mesh.vertices.row(48 + 3) + Eigen::RowVector3d(0, 0.2, 0));
  CHECK(added.constraints.free_components == 0);
  CHECK(added.notes.empty());
  CHECK(std::isfinite(session.Solve().energy));
}

TEST_CASE("session: options a session cannot run are rejected clearly", "[session]") {
  SmallBentTube tube;
  const auto make = [&](const std::string& toml) {
    TestSetup setup(toml);
    return Session(setup, tube.mesh);
  };
  CHECK_THROWS_WITH(make("[optimizer]\ntype = \"hierarchical\"\nnewton = 10\n"),
                    Catch::Contains("newton = 0"));
  CHECK_THROWS_WITH(make("[optimizer]\ntype = \"admm_pd\"\n"), Catch::Contains("classic"));
  CHECK_THROWS_WITH(make("[optimizer]\ntype = \"hierarchical\"\ninner = \"wrapd\"\n[energy]\n"
                         "type = \"elements\"\n"),
                    Catch::Contains("ADMM"));
  // Anderson acceleration works on the masked system.
  TestSetup anderson("[optimizer]\ntype = \"classic\"\nanderson = 5\ntolerance = 1e-7\n");
  auto configured = Session(anderson, tube.mesh);
  configured->session().SetHandles(tube.problem.constraints.indices,
                                   tube.problem.constraints.targets);
  const OptimizeResult accelerated = configured->session().Solve();
  const OptimizeResult reference =
      anderson.MakeOptimizer()->Optimize(tube.problem, anderson.factory, Context());
  CHECK(accelerated.converged);
  CHECK(Close(accelerated.energy, reference.energy, 1e-6));
}

TEST_CASE("session: a drag in frames ends near the one-shot solution with the cascade starts",
          "[session]") {
  SmallBentTube tube;
  TestSetup setup(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-8\n"
      "[hierarchy]\nmin_vertices = 60\n");
  const OptimizeResult reference =
      setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, Context::WithThreads(2));
  const Constraints& handles = tube.problem.constraints;
  const Positions rest = tube.mesh.vertices(handles.indices, Eigen::all);
  for (const auto start :
       {SessionOptions::FrameStart::kUpsampled, SessionOptions::FrameStart::kCorrected}) {
    DYNAMIC_SECTION("frame start " << static_cast<int>(start)) {
      auto configured = Session(setup, tube.mesh, start);
      DeformationSession& session = configured->session();
      session.SetHandles(handles.indices);
      OptimizeResult last;
      for (int frame = 1; frame <= 4; ++frame) {
        session.SetTargets(rest + (handles.targets - rest) * (frame / 4.0));
        last = session.Solve();
        CHECK(last.converged);
      }
      INFO("last frame " << last.energy << ", one-shot " << reference.energy);
      CHECK(Close(last.energy, reference.energy, 1e-2));
    }
  }
}

TEST_CASE("session: a solve after a preview of the same targets equals a solve without it",
          "[session]") {
  // A 20 × 20 grid, its left column fixed and its right column rotated and moved: a preview's
  // finest state is one global step from rotations not fitted to its positions, so a full solve
  // that took it for a converged warm start would stop after one iteration far from the minimum.
  const Mesh grid = Grid(20, 20);
  std::vector<Index> handles;
  Positions targets(0, 3);
  for (Index v = 0; v < grid.num_vertices(); ++v) {
    const double x = grid.vertices(v, 0);
    if (x > 1e-9 && x < 1.0 - 1e-9) continue;
    handles.push_back(v);
    Eigen::RowVector3d target = grid.vertices.row(v);
    if (x > 0.5)
      target = Eigen::RowVector3d(0.8 * target(0) - 0.6 * target(1) + 0.3,
                                  0.6 * target(0) + 0.8 * target(1), 0.0);
    targets.conservativeResize(targets.rows() + 1, 3);
    targets.row(targets.rows() - 1) = target;
  }
  const std::string classic = "[optimizer]\ntype = \"classic\"\ntolerance = 1e-10\n";
  const std::string hierarchical =
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-10\n[hierarchy]\nmin_vertices = 40\n";
  for (const auto& [config, start] :
       {std::pair{classic, SessionOptions::FrameStart::kCorrected},
        std::pair{hierarchical, SessionOptions::FrameStart::kCorrected},
        std::pair{hierarchical, SessionOptions::FrameStart::kUpsampled},
        std::pair{hierarchical, SessionOptions::FrameStart::kPrevious}}) {
    DYNAMIC_SECTION(config << "frame start " << SessionOptions::FrameStartName(start)) {
      TestSetup setup(config);
      const auto solve = [&](bool preview_first) {
        auto configured = Session(setup, grid, start);
        DeformationSession& session = configured->session();
        session.SetHandles(handles);
        session.Solve();  // at rest
        session.SetTargets(targets);
        if (preview_first) session.Preview();
        return session.Solve();
      };
      const OptimizeResult direct = solve(false);
      const OptimizeResult previewed = solve(true);
      INFO("after a preview " << previewed.energy << " (" << previewed.iterations
                              << " iterations), without " << direct.energy << " ("
                              << direct.iterations << ")");
      CHECK(direct.converged);
      CHECK(previewed.converged);
      CHECK(previewed.iterations > 1);
      CHECK(Close(previewed.energy, direct.energy, 1e-6));
    }
  }
}

TEST_CASE("session: mesh checks and edit summaries for the current handles", "[session]") {
  // Three pieces: a tube, a sphere and a grid, the sphere without handles at first.
  const Mesh tube_and_sphere = Concatenate(Tube(6, 8), Icosphere(1));
  const Mesh mesh = Concatenate(tube_and_sphere, Grid(4, 4));
  const Index grid_start = tube_and_sphere.num_vertices();
  TestSetup setup(kClassic);
  auto configured = Session(setup, mesh);
  // Made without handles: every piece is without one.
  CHECK(configured->mesh_checks().components_without_constraints == 3);
  for (const std::vector<Index>& handles :
       {std::vector<Index>{0, 1, 2, grid_start + 5}, std::vector<Index>{0, 48 + 3, 48 + 7},
        std::vector<Index>{grid_start, grid_start + 1}}) {
    const MeshCheckReport counted = configured->MeshChecksFor(handles);
    const MeshCheckReport reference = CheckMesh(mesh, handles);
    CHECK(counted.components_without_constraints == reference.components_without_constraints);
    REQUIRE(counted.components.size() == reference.components.size());
    for (size_t c = 0; c < counted.components.size(); ++c) {
      CHECK(counted.components[c].first_element == reference.components[c].first_element);
      CHECK(counted.components[c].constrained_vertices ==
            reference.components[c].constrained_vertices);
    }
    // The summary's components line (CheckMesh alone leaves the findings' actions empty;
    // PreparedProblem fills them in).
    CHECK(SummarizeMeshChecks(counted).back() == SummarizeMeshChecks(reference).back());
  }

  const HandleEditResult edit = configured->session().SetHandles({0, 1, 2, grid_start + 5});
  const std::string json = HandleEditJson(edit);
  CHECK(json.find("\"route\":\"full\"") != std::string::npos);
  CHECK(json.find("\"free_components\":1") != std::string::npos);
  CHECK(json.find("pinned") != std::string::npos);
  CHECK(RefactorRouteName(LinearSolver::RefactorRoute::kUpdate) == "update");
  CHECK(RefactorRouteName(LinearSolver::RefactorRoute::kNumeric) == "numeric");
  CHECK(RefactorRouteName(LinearSolver::RefactorRoute::kPartial) == "partial");
}

TEST_CASE("one-shot runs and sessions answer in the input mesh's numbering", "[session]") {
  // The same tube with its vertices in another order: the level solvers work in one locality
  // order either way, so the result is the same, permuted back to each input's numbering.
  SmallBentTube tube;
  std::vector<Index> moved_to;
  const Mesh shuffled = Shuffled(tube.mesh, 17, &moved_to);
  DeformationProblem problem = tube.problem;
  problem.mesh = &shuffled;
  for (Index& v : problem.constraints.indices) v = moved_to[v];
  const auto permuted_back = [&](const Positions& positions) {
    Positions back(positions.rows(), 3);
    for (Index v = 0; v < positions.rows(); ++v) back.row(v) = positions.row(moved_to[v]);
    return back;
  };
  for (const char* config : {kClassic, kHierarchical}) {
    DYNAMIC_SECTION(config) {
      TestSetup setup(config);
      const Context context = Context::WithThreads(2);
      const OptimizeResult reference =
          setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, context);
      const OptimizeResult result =
          setup.MakeOptimizer()->Optimize(problem, setup.factory, context);
      const double scale = reference.positions.cwiseAbs().maxCoeff();
      CHECK((permuted_back(result.positions) - reference.positions).cwiseAbs().maxCoeff() <
            1e-9 * scale);
      CHECK(Close(result.energy, reference.energy, 1e-9));

      auto original = Session(setup, tube.mesh);
      auto reordered = Session(setup, shuffled);
      original->session().SetHandles(tube.problem.constraints.indices,
                                     tube.problem.constraints.targets);
      reordered->session().SetHandles(problem.constraints.indices, problem.constraints.targets);
      const Positions solved = reordered->session().Solve().positions;
      CHECK((permuted_back(solved) - original->session().Solve().positions).cwiseAbs().maxCoeff() <
            1e-9 * scale);
      CHECK(reordered->session().positions() == solved);
      // Handles set where the vertices are now: their targets are their rows of positions().
      const std::vector<Index> held = {moved_to[0], moved_to[5]};
      reordered->session().SetHandles(held);
      for (size_t k = 0; k < held.size(); ++k) {
        CHECK(reordered->session().targets().row(static_cast<Index>(k)) == solved.row(held[k]));
      }
      if (std::string(config) == kHierarchical) {
        // Clusters of mesh vertices: the same coarse vertex (by position) in either session.
        const DeformationSession& a = original->session();
        const DeformationSession& b = reordered->session();
        for (int l = 1; l < a.num_levels(); ++l) {
          for (Index v = 0; v < tube.mesh.num_vertices(); ++v) {
            const Index ca = a.CoarseVertex(v, l), cb = b.CoarseVertex(moved_to[v], l);
            REQUIRE((ca == kNoVertex) == (cb == kNoVertex));
            if (ca == kNoVertex) continue;
            CHECK((a.hierarchy().levels[l].mesh.vertices.row(ca) -
                   b.hierarchy().levels[l].mesh.vertices.row(cb))
                      .norm() < 1e-12);
          }
        }
      }
    }
  }
}
