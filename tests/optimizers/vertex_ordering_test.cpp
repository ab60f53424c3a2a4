// SPDX-License-Identifier: MIT
// MeshOrdering::IsToNew, and LocalGlobalSolver::AuxiliaryMeasures, which uses it to measure the
// final state from the level's kept internal copy instead of making another one.
#include <catch2/catch.hpp>

#include <random>
#include <vector>

#include "solvers/optimizers/local_global_solver.h"
#include "solvers/optimizers/vertex_ordering.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

Rotations RandomRotations(size_t count, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> angle(-3.0, 3.0);
  Rotations rotations(count);
  for (Rotation& r : rotations) {
    r = Eigen::AngleAxisd(angle(random), Eigen::Vector3d(angle(random), 1.0, angle(random))
                                             .normalized())
            .toRotationMatrix();
  }
  return rotations;
}

}  // namespace

TEST_CASE("vertex ordering: IsToNew recognizes exactly the renumbered copy", "[optimizers]") {
  const Mesh mesh = Jittered(Grid(9, 7), 9, 0.2, 3);
  const MeshOrdering ordering = LocalityOrdering(mesh);
  const Positions input = Positions::Random(mesh.num_vertices(), 3);
  const Positions renumbered = ordering.ToNew(input);
  CHECK(ordering.IsToNew(input, renumbered));
  CHECK_FALSE(ordering.IsToNew(renumbered, input));  // the ordering is not the identity
  CHECK_FALSE(ordering.IsToNew(input, input.topRows(input.rows() - 1)));
  CHECK_FALSE(ordering.IsToNew(input, Positions()));
  Positions changed = renumbered;
  changed(4, 2) = std::nextafter(changed(4, 2), 10.0);
  CHECK_FALSE(ordering.IsToNew(input, changed));
  // Bit for bit: −0 is not 0.
  Positions zero = input;
  zero(7, 1) = 0.0;
  Positions negative_zero = ordering.ToNew(zero);
  negative_zero(ordering.new_vertex[7], 1) = -0.0;
  CHECK(ordering.IsToNew(zero, ordering.ToNew(zero)));
  CHECK_FALSE(ordering.IsToNew(zero, negative_zero));

  for (const bool per_element : {false, true}) {
    const size_t sites = per_element ? static_cast<size_t>(mesh.num_elements())
                                     : static_cast<size_t>(mesh.num_vertices());
    const Rotations rotations = RandomRotations(sites, 5);
    const Rotations renumbered_rotations = ordering.ToNew(rotations, per_element);
    CHECK(ordering.IsToNew(rotations, per_element, renumbered_rotations));
    Rotations off = renumbered_rotations;
    off[3](1, 2) += 1e-15;
    CHECK_FALSE(ordering.IsToNew(rotations, per_element, off));
    CHECK_FALSE(ordering.IsToNew(rotations, per_element, Rotations()));
  }
  // ToNew passes rotations of another count (e.g. none yet) through unchanged.
  CHECK(ordering.IsToNew(Rotations(), false, Rotations()));
  const Rotations three = RandomRotations(3, 6);
  CHECK(ordering.IsToNew(three, false, three));
  CHECK_FALSE(ordering.IsToNew(three, false, RandomRotations(3, 7)));
}

TEST_CASE("local/global: auxiliary measures from the kept internal state equal those of copies",
          "[optimizers]") {
  const Mesh mesh = TetBox(3, 3, 4);
  const TestSetup setup("[energy]\ntype = \"elements\"\n");
  const Context context;
  const double top = mesh.vertices.col(2).maxCoeff();
  std::vector<Index> constrained;
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    const double z = mesh.vertices(v, 2);
    if (z == 0.0 || z == top) constrained.push_back(v);
  }
  // Two levels alike: one runs (and keeps its internal state), the other never ran.
  LocalGlobalSolver ran(mesh, constrained, setup.factory, 0, context);
  const LocalGlobalSolver fresh(mesh, constrained, setup.factory, 0, context);
  LevelState state;
  state.positions = mesh.vertices;
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.vertices(v, 2) == top) state.positions(v, 0) += 0.4;  // shear the top
  }
  LocalGlobalOptions options;
  options.max_iterations = 4;
  ran.Run(state, false, options, 1.0, context);
  REQUIRE(state.rotations.size() == static_cast<size_t>(mesh.num_elements()));
  const auto kept = ran.AuxiliaryMeasures(state, context);
  REQUIRE_FALSE(kept.empty());
  CHECK(kept == fresh.AuxiliaryMeasures(state, context));
  // A state changed since the run: measured from copies, like the other level does.
  LevelState moved = state;
  moved.positions(5, 1) += 0.25;
  const auto after_move = ran.AuxiliaryMeasures(moved, context);
  CHECK(after_move == fresh.AuxiliaryMeasures(moved, context));
  CHECK(after_move != kept);
}
