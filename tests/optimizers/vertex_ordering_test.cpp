// SPDX-License-Identifier: MIT
// MeshOrdering::IsToNew, and LocalGlobalSolver::AuxiliaryMeasures, which uses it to measure the
// final state from the level's kept internal copy instead of making another one.
#include "solvers/optimizers/vertex_ordering.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "solvers/optimizers/local_global_solver.h"
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
    r = Eigen::AngleAxisd(angle(random),
                          Eigen::Vector3d(angle(random), 1.0, angle(random)).normalized())
            .toRotationMatrix();
  }
  return rotations;
}

}  // namespace

TEST_CASE("vertex ordering: a Morton order of the vertices, elements by their first vertex",
          "[optimizers]") {
  // Vertices along the z-order curve, ties (equal positions) in input order; elements by their
  // smallest new vertex index, ties in input order (the radix and counting sorts must give
  // what sorting the (key, index) pairs gave).
  Mesh mesh = Jittered(Grid(13, 11), 13, 0.3, 7);
  {  // in a random order, so that locality has something to improve
    std::vector<Index> to(mesh.num_vertices());
    std::iota(to.begin(), to.end(), Index{0});
    std::shuffle(to.begin(), to.end(), std::mt19937(3));
    Positions shuffled(mesh.num_vertices(), 3);
    for (Index v = 0; v < mesh.num_vertices(); ++v) shuffled.row(to[v]) = mesh.vertices.row(v);
    mesh.vertices = shuffled;
    for (Index e = 0; e < mesh.num_elements(); ++e) {
      for (int a = 0; a < 3; ++a) mesh.elements(e, a) = to[mesh.elements(e, a)];
    }
  }
  mesh.vertices.row(5) = mesh.vertices.row(40);  // ties
  mesh.vertices.row(77) = mesh.vertices.row(40);
  const MeshOrdering ordering = LocalityOrdering(mesh);
  const Index n = mesh.num_vertices();
  REQUIRE(static_cast<Index>(ordering.old_vertex.size()) == n);
  std::vector<Index> seen(n, 0);
  for (Index k = 0; k < n; ++k) {
    ++seen[ordering.old_vertex[k]];
    CHECK(ordering.new_vertex[ordering.old_vertex[k]] == k);
    CHECK(ordering.mesh.vertices.row(k) == mesh.vertices.row(ordering.old_vertex[k]));
  }
  CHECK(std::count(seen.begin(), seen.end(), 1) == n);
  // The tied vertices are consecutive, in input order.
  CHECK(ordering.new_vertex[40] == ordering.new_vertex[5] + 1);
  CHECK(ordering.new_vertex[77] == ordering.new_vertex[40] + 1);
  // Neighbours in the mesh are nearer in the new numbering than in the shuffled one.
  double old_span = 0.0, new_span = 0.0;
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 0; a < 3; ++a) {
      const Index v = mesh.elements(e, a), w = mesh.elements(e, (a + 1) % 3);
      old_span += std::abs(v - w);
      new_span += std::abs(ordering.new_vertex[v] - ordering.new_vertex[w]);
    }
  }
  CHECK(new_span < old_span);
  Index previous_first = -1, previous_element = -1;
  for (Index k = 0; k < mesh.num_elements(); ++k) {
    const Index e = ordering.old_element[k];
    CHECK(ordering.new_element[e] == k);
    const Index first = ordering.mesh.elements.row(k).minCoeff();
    CHECK(first >= previous_first);
    if (first == previous_first) CHECK(e > previous_element);
    previous_first = first;
    previous_element = e;
    for (int a = 0; a < 3; ++a) {
      CHECK(ordering.mesh.elements(k, a) == ordering.new_vertex[mesh.elements(e, a)]);
    }
  }
}

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
