// SPDX-License-Identifier: MIT
// The locality ordering of a mesh and the level cascade's one renumbering of its levels.
#include "solvers/optimizers/vertex_ordering.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "solvers/optimizers/level_cascade.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

TEST_CASE("vertex ordering: a Morton order of the vertices, elements by their first vertex",
          "[optimizers]") {
  // Vertices along the z-order curve, ties (equal positions) in input order; elements by their
  // smallest new vertex index, ties in input order (the radix and counting sorts must give
  // what sorting the (key, index) pairs gave).
  // In a random order, so that locality has something to improve.
  Mesh mesh = Shuffled(Jittered(Grid(13, 11), 13, 0.3, 7), 3);
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

TEST_CASE("level cascade: every stored level is in locality order and the maps follow",
          "[optimizers]") {
  // The hierarchy is built on the input's numbering; the cascade renumbers every level once
  // (LocalityOrdering) and the vertex maps with them.
  const Mesh mesh = Shuffled(Jittered(Grid(17, 15), 17, 0.3, 5), 11);
  const TestSetup setup("[hierarchy]\nmin_vertices = 20\n");
  const MeshHierarchy built = setup.factory.MakeHierarchy()->Build(mesh, Context());
  REQUIRE(built.num_levels() >= 3);
  LevelCascade cascade(mesh, Context());
  cascade.SetHierarchy(built, setup.factory.MakeUpsampler());
  REQUIRE(cascade.num_levels() == built.num_levels());
  const std::vector<Index>& to_level = cascade.finest_ordering().new_vertex;
  for (int l = 0; l < cascade.num_levels(); ++l) {
    INFO("level " << l);
    const Mesh& stored = cascade.LevelMesh(l);
    CHECK(&stored == &cascade.LevelMesh(l));
    CHECK(cascade.hierarchy().levels[l].mesh.vertices == stored.vertices);
    CHECK(cascade.hierarchy().levels[l].mesh.elements == stored.elements);
    // In locality order already: renumbering it again changes nothing.
    const MeshOrdering again = LocalityOrdering(stored);
    std::vector<Index> identity(stored.num_vertices());
    std::iota(identity.begin(), identity.end(), Index{0});
    CHECK(again.old_vertex == identity);
    CHECK(again.mesh.elements == stored.elements);
    // The same level as built: its vertices permuted, its elements with them.
    REQUIRE(stored.num_vertices() == built.levels[l].mesh.num_vertices());
    REQUIRE(stored.num_elements() == built.levels[l].mesh.num_elements());
    CHECK(LocalityOrdering(built.levels[l].mesh).mesh.vertices == stored.vertices);
    // Every input vertex reaches the same coarse vertex (by position) through either map.
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      const Index as_built = built.MapFinestVertex(v, l);
      const Index as_stored = cascade.hierarchy().MapFinestVertex(to_level[v], l);
      REQUIRE((as_built == kNoVertex) == (as_stored == kNoVertex));
      if (as_built == kNoVertex) continue;
      CHECK(built.levels[l].mesh.vertices.row(as_built) == stored.vertices.row(as_stored));
    }
  }
  // The boundary: constraints in, positions out.
  Constraints constraints;
  constraints.indices = {3, 50, 7};
  constraints.targets = Positions::Random(3, 3);
  const Constraints in_level = cascade.ToLevel(constraints);
  for (size_t k = 0; k < constraints.indices.size(); ++k) {
    CHECK(cascade.LevelMesh(0).vertices.row(in_level.indices[k]) ==
          mesh.vertices.row(constraints.indices[k]));
  }
  CHECK(in_level.targets == constraints.targets);
  Positions out;
  cascade.ToInput(cascade.LevelMesh(0).vertices, out, Context());
  CHECK(out == mesh.vertices);
}
