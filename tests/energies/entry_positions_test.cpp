// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include "energies/kernels/mesh_adjacency.h"
#include "energies/kernels/triangle_stencil.h"
#include "framework/error.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

TEST_CASE("TriangleEntryPositions and TransposePositions agree with EntryPosition", "[energies]") {
  for (const Mesh& mesh : {Tube(6, 7), Icosphere(2)}) {
    const SparseMatrix pattern = AdjacencyPattern(mesh.num_vertices(), mesh.elements);
    const auto entry = TriangleEntryPositions(pattern, mesh.elements);
    REQUIRE(static_cast<Index>(entry.size()) == mesh.num_elements());
    for (Index f = 0; f < mesh.num_elements(); ++f) {
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
          CHECK(entry[f][3 * a + b] ==
                EntryPosition(pattern, mesh.elements(f, a), mesh.elements(f, b)));
        }
      }
    }
    const std::vector<Index> mirror = TransposePositions(pattern);
    for (Index col = 0; col < pattern.outerSize(); ++col) {
      for (Index p = pattern.outerIndexPtr()[col]; p < pattern.outerIndexPtr()[col + 1]; ++p) {
        CHECK(mirror[p] == EntryPosition(pattern, col, pattern.innerIndexPtr()[p]));
      }
    }
  }
}

TEST_CASE("TransposePositions rejects a pattern without the mirror entries", "[energies]") {
  SparseMatrix lower(3, 3);
  lower.insert(0, 0) = 1.0;
  lower.insert(1, 0) = 1.0;  // (0, 1) missing
  lower.insert(1, 1) = 1.0;
  lower.insert(2, 2) = 1.0;
  lower.makeCompressed();
  CHECK_THROWS_AS(TransposePositions(lower), InternalError);
  // A face whose pair is not in the pattern.
  Elements face(1, 3);
  face << 0, 1, 2;
  CHECK_THROWS_AS(TriangleEntryPositions(lower, face), InternalError);
}
