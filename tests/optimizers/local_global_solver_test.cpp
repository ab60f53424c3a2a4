// SPDX-License-Identifier: MIT
#include "solvers/optimizers/local_global_solver.h"

#include <catch2/catch.hpp>

#include "tests/support/level_energies.h"
#include "tests/support/test_factory.h"

using namespace harap;
using namespace harap::testing;

TEST_CASE("local/global: constraint targets that keep raising the energy are frozen",
          "[optimizers]") {
  constexpr int kSegments = 24;
  const BentTube tube(40, kSegments, 2.0, M_PI / 2, Eigen::Vector3d(0.0, 0.8, -0.8));
  const TestSetup setup;
  const Context context;
  LocalGlobalSolver solver(tube.mesh, tube.problem.constraints.indices, setup.factory, 1, context);
  LevelState state;
  state.positions = InitialPositions(tube.problem);
  LocalGlobalOptions options;
  options.tolerance = 1e-8;
  REQUIRE(solver.Run(state, false, options, 1.0, context).converged);
  // From the converged state, a target update that jerks the top ring up and down: every upward
  // move raises the energy, so the targets cycle until the third increase freezes them.
  int calls = 0;
  const auto jerk = [&](const Rotations&, Positions& positions) {
    ++calls;
    for (int k = kSegments; k < 2 * kSegments; ++k) {
      const Index v = tube.problem.constraints.indices[k];
      positions(v, 2) += calls % 2 == 1 ? 0.3 : -0.3;
    }
  };
  LevelEnergies energies;
  Context recording;
  energies.Record(recording);
  const auto run = solver.Run(state, false, options, 1.0, recording, jerk);
  REQUIRE(run.targets_frozen_at > 1);
  CHECK(calls == run.targets_frozen_at);
  CHECK(calls % 2 == 1);  // frozen right after an upward move
  CHECK(run.converged);
  // From the freeze on, plain local/global iterations: monotone.
  const std::vector<double>& trace = energies.by_level[1];
  REQUIRE(static_cast<int>(trace.size()) > run.targets_frozen_at);
  LevelEnergies after_freeze;
  after_freeze.by_level[1].assign(trace.begin() + run.targets_frozen_at - 1, trace.end());
  CHECK(after_freeze.MonotonePerLevel());
  // The frozen targets are where the last update put them.
  for (int k = kSegments; k < 2 * kSegments; ++k) {
    CHECK(state.positions(tube.problem.constraints.indices[k], 2) ==
          Approx(tube.problem.constraints.targets(k, 2) + 0.3));
  }
}

TEST_CASE("local/global: the gathered global step equals the global step on gathered rotations",
          "[optimizers][session]") {
  // A preview's finest global step (sessions): rotations gathered from a few coarse ones, the
  // right-hand side from the probed linear map instead of the energy's assembly.
  const BentTube tube(20, 12, 2.0, M_PI / 3, Eigen::Vector3d(0.0, 0.5, -0.4));
  const Context context;
  const Constraints& handles = tube.problem.constraints;
  for (const std::string energy : {"spokes_and_rims", "spokes", "smooth_arap"}) {
    DYNAMIC_SECTION(energy) {
      const TestSetup setup("[energy]\ntype = \"" + energy + "\"\n");
      // As a session's finest level: handle edits (masked system), exact targets.
      LocalGlobalSolver solver;
      solver.Precompute(LevelSetup{&tube.mesh, nullptr, 0, /*handle_edits=*/true}, setup.factory,
                        context);
      solver.Constrain(LevelConstraints::Exact(handles, false), setup.factory, context);
      REQUIRE(solver.accepts_gathered_rotations());
      REQUIRE(solver.energy().rotation_site() == RotationSite::kVertex);
      const Index n = tube.mesh.num_vertices();
      // Seven coarse clusters in bands along the tube, a few vertices without one (identity).
      const auto cluster = [&](Index v) { return v % 13 == 5 ? kNoVertex : (v / 36) % 7; };
      std::vector<Index> source(n);
      for (Index s = 0; s < n; ++s) source[s] = cluster(s);
      for (int round = 0; round < 3; ++round) {
        Rotations coarse(7);
        for (int c = 0; c < 7; ++c) {
          coarse[c] =
              Eigen::AngleAxisd(0.3 * c + 0.2 * round, Eigen::Vector3d(1.0, c, round).normalized())
                  .toRotationMatrix();
        }
        const Positions targets = handles.targets * (1.0 + 0.1 * round);
        LevelState reference;
        reference.positions = tube.mesh.vertices;
        for (size_t k = 0; k < handles.indices.size(); ++k) {
          reference.positions.row(handles.indices[k]) = targets.row(static_cast<Index>(k));
        }
        reference.rotations.resize(n);
        for (Index v = 0; v < n; ++v) {
          reference.rotations[v] =
              cluster(v) == kNoVertex ? Rotation(Rotation::Identity()) : coarse[cluster(v)];
        }
        solver.GlobalStep(reference, context);
        Positions gathered = tube.mesh.vertices;
        solver.GatheredGlobalStep(source, coarse, handles.indices, targets, gathered, context);
        CHECK(solver.gathered_rhs_is_linear());
        INFO("round " << round);
        CHECK((gathered - reference.positions).cwiseAbs().maxCoeff() <=
              1e-12 * reference.positions.cwiseAbs().maxCoeff());
        // The same through the LevelSolver interface (the session's preview): the map
        // in the mesh's numbering, the targets the level's own (moved by MoveTargets).
        std::vector<Index> mesh_source(n);
        for (Index v = 0; v < n; ++v) mesh_source[v] = cluster(v);
        solver.MoveTargets(targets);
        LevelState state;
        state.positions = tube.mesh.vertices;
        const LevelSolveResult result =
            solver.GlobalStepFromGathered(state, mesh_source, coarse, context);
        CHECK(result.iterations == 1);
        CHECK(state.rotations.empty());  // never written out
        CHECK((state.positions - reference.positions).cwiseAbs().maxCoeff() <=
              1e-12 * reference.positions.cwiseAbs().maxCoeff());
        solver.MoveTargets(handles.targets);
      }
    }
  }
}
