// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include "solvers/optimizers/local_global_solver.h"
#include "tests/support/level_energies.h"
#include "tests/support/test_factory.h"

using namespace harap;
using namespace harap::testing;

TEST_CASE("local/global: constraint targets that keep raising the energy are frozen", "[optimizers]") {
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
      const Index v = solver.ordering().new_vertex[tube.problem.constraints.indices[k]];
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
