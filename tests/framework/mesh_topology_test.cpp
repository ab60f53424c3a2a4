// SPDX-License-Identifier: MIT
#include "framework/mesh_topology.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <set>

using namespace harap;

namespace {

// Two triangles sharing edge 1–2, a tetrahedron-free mesh with an unreferenced vertex 4.
Elements TwoTriangles() {
  Elements e(2, 3);
  e << 0, 1, 2,  //
      2, 1, 3;
  return e;
}

}  // namespace

TEST_CASE("VertexIncidence: the corners around each vertex, in element order", "[framework]") {
  const VertexIncidence incidence = VertexIncidence::Build(5, TwoTriangles());
  REQUIRE(incidence.num_vertices() == 5);
  CHECK(incidence.offsets == std::vector<Index>{0, 1, 3, 5, 6, 6});
  // Vertex 1: corner 1 of triangle 0, corner 1 of triangle 1; vertex 2: corner 2 of 0, 0 of 1.
  CHECK(incidence.element(1) == 0);
  CHECK(incidence.corner(1) == 1);
  CHECK(incidence.element(2) == 1);
  CHECK(incidence.corner(2) == 1);
  CHECK(incidence.element(3) == 0);
  CHECK(incidence.corner(3) == 2);
  CHECK(incidence.element(4) == 1);
  CHECK(incidence.corner(4) == 0);
  CHECK(incidence.offsets[4] == incidence.offsets[5]);  // unreferenced
}

TEST_CASE("VertexAdjacency: sorted distinct neighbours, optionally with the vertex itself",
          "[framework]") {
  const VertexAdjacency ring = VertexAdjacency::Build(5, TwoTriangles(), false);
  const std::vector<std::vector<Index>> expected = {{1, 2}, {0, 2, 3}, {0, 1, 3}, {1, 2}, {}};
  for (Index v = 0; v < 5; ++v) {
    const std::vector<Index> got(ring.neighbors.begin() + ring.offsets[v],
                                 ring.neighbors.begin() + ring.offsets[v + 1]);
    CHECK(got == expected[v]);
  }
  const VertexAdjacency with_self = VertexAdjacency::Build(5, TwoTriangles(), true);
  CHECK(with_self.offsets.back() == ring.offsets.back() + 5);
  CHECK(with_self.neighbors[with_self.offsets[4]] == 4);  // unreferenced: itself only
}
