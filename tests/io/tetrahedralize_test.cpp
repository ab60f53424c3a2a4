// SPDX-License-Identifier: MIT
// Tetrahedralization with TetGen: the surface survives exactly, the tetrahedra fill it with
// positive volumes, and broken surfaces (open, self-intersecting, ...) are InputErrors.
#include "io/tetrahedralize.h"

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <map>

#include "framework/config.h"
#include "framework/error.h"
#include "io/builtin_meshes.h"
#include "io/tetrahedra.h"
#include "tests/io/io_test_util.h"

namespace harap {
namespace {

using Catch::Matchers::Contains;
using testing::ExpectInputError;

Mesh Cylinder(int vertices, bool caps = true) {
  return MakeBuiltinMesh(ConfigNode::Parse(
      fmt::format("builtin = \"cylinder\"\nvertices = {}\ncaps = {}", vertices, caps), "test"));
}

// The unit cube's closed surface, outward normals.
Mesh Cube() {
  Mesh mesh;
  mesh.vertices.resize(8, 3);
  mesh.vertices << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1;
  mesh.elements.resize(12, 3);
  mesh.elements << 0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7,
      2, 7, 6, 3, 0, 4, 3, 4, 7;
  return mesh;
}

double TetrahedronVolume(const Mesh& mesh, Index t) {
  auto x = [&](int a) -> Eigen::Vector3d { return mesh.vertices.row(mesh.elements(t, a)); };
  return TetrahedronDeterminant(x(0), x(1), x(2), x(3)) / 6.0;
}

// Checks everything Tetrahedralize promises about `volume` made from `surface`.
void CheckKeepsSurface(const Mesh& surface, const Mesh& volume) {
  const Index n = surface.num_vertices();
  REQUIRE(volume.kind() == ElementKind::kTetrahedron);
  REQUIRE(volume.num_vertices() >= n);
  // Surface vertices first, bit-identical.
  CHECK(volume.vertices.topRows(n) == surface.vertices);
  // Positive volumes that add up to the enclosed volume.
  double total = 0.0;
  double smallest = std::numeric_limits<double>::infinity();
  for (Index t = 0; t < volume.num_elements(); ++t) {
    const double v = TetrahedronVolume(volume, t);
    smallest = std::min(smallest, v);
    total += v;
  }
  CHECK(smallest > 0.0);
  CHECK(total == Approx(testing::SignedVolume(surface)).epsilon(1e-10));
  // Boundary faces (faces of one tetrahedron) are exactly the surface's triangles, and they face
  // the way the surface's triangles do (outward) when taken from the positively oriented tet.
  std::map<std::array<Index, 3>, int> faces;
  for (Index t = 0; t < volume.num_elements(); ++t) {
    for (int skip = 0; skip < 4; ++skip) {
      std::array<Index, 3> face;
      int k = 0;
      for (int a = 0; a < 4; ++a) {
        if (a != skip) face[k++] = volume.elements(t, a);
      }
      std::sort(face.begin(), face.end());
      ++faces[face];
    }
  }
  int boundary = 0;
  for (const auto& [face, count] : faces) {
    REQUIRE(count <= 2);
    boundary += count == 1;
  }
  CHECK(boundary == surface.num_elements());
  for (Index f = 0; f < surface.num_elements(); ++f) {
    std::array<Index, 3> face = {surface.elements(f, 0), surface.elements(f, 1),
                                 surface.elements(f, 2)};
    std::sort(face.begin(), face.end());
    REQUIRE(faces[face] == 1);
  }
  // Steiner points are inside the surface's bounding box.
  for (Index v = n; v < volume.num_vertices(); ++v) {
    for (int d = 0; d < 3; ++d) {
      CHECK(volume.vertices(v, d) >= surface.vertices.col(d).minCoeff());
      CHECK(volume.vertices(v, d) <= surface.vertices.col(d).maxCoeff());
    }
  }
}

TEST_CASE("Tetrahedralize keeps the surface of the built-in cylinder", "[io][tetrahedralize]") {
  const Mesh surface = Cylinder(400);
  SECTION("quality refinement only") {
    const Mesh volume = Tetrahedralize(surface, {}, "cylinder");
    CheckKeepsSurface(surface, volume);
  }
  SECTION("with a volume bound: more tetrahedra, interior Steiner points") {
    const Mesh coarse =
        Tetrahedralize(surface, {.max_volume = 0.0, .max_radius_edge_ratio = 0.0}, "cylinder");
    CheckKeepsSurface(surface, coarse);
    CHECK(coarse.num_vertices() == surface.num_vertices());  // no refinement: no Steiner points
    TetrahedralizeOptions options;
    options.max_volume = 2e-3;
    options.min_dihedral_angle = 10.0;
    const Mesh fine = Tetrahedralize(surface, options, "cylinder");
    CheckKeepsSurface(surface, fine);
    CHECK(fine.num_vertices() > surface.num_vertices());
    const double enclosed = testing::SignedVolume(surface);
    for (Index t = 0; t < fine.num_elements(); ++t) {
      REQUIRE(TetrahedronVolume(fine, t) <= options.max_volume * enclosed * (1 + 1e-9));
    }
  }
}

TEST_CASE("Tetrahedralize keeps unreferenced vertices where they are", "[io][tetrahedralize]") {
  Mesh surface = Cube();
  // A stray vertex inside (index 3 after the shift) and one outside (last): both stay unused.
  Mesh with_strays;
  with_strays.vertices.resize(10, 3);
  with_strays.vertices.topRows(3) = surface.vertices.topRows(3);
  with_strays.vertices.row(3) << 0.5, 0.5, 0.5;
  with_strays.vertices.middleRows(4, 5) = surface.vertices.bottomRows(5);
  with_strays.vertices.row(9) << 5, 5, 5;
  with_strays.elements = surface.elements.unaryExpr([](Index v) { return v >= 3 ? v + 1 : v; });
  const Mesh volume = Tetrahedralize(with_strays, {}, "cube");
  CheckKeepsSurface(with_strays, volume);
  const std::vector<bool> used = ReferencedVertices(volume);
  CHECK(!used[3]);
  CHECK(!used[9]);
}

TEST_CASE("Tetrahedralize rejects surfaces TetGen cannot fill", "[io][tetrahedralize]") {
  ExpectInputError([] { Tetrahedralize(Cylinder(300, false), {}, "tube"); },
                   {"tube", "not closed", "boundary edges in total"});
  Mesh flipped = Cube();
  std::swap(flipped.elements(0, 1), flipped.elements(0, 2));
  ExpectInputError([&] { Tetrahedralize(flipped, {}, "flipped"); },
                   {"flipped", "not consistently oriented", "triangles 0 and"});
  Mesh doubled = Cube();
  doubled.elements.conservativeResize(13, 3);
  doubled.elements.row(12) = doubled.elements.row(0);
  ExpectInputError([&] { Tetrahedralize(doubled, {}, "doubled"); }, {"not a manifold"});
  Mesh collapsed = Cube();
  collapsed.vertices.row(6) = collapsed.vertices.row(2);
  ExpectInputError([&] { Tetrahedralize(collapsed, {}, "collapsed"); }, {"collapsed"});
  Mesh flat = MakeBuiltinMesh(ConfigNode::Parse("builtin = \"disk\"\nvertices = 50", "test"));
  ExpectInputError([&] { Tetrahedralize(flat, {}, "disk"); }, {"disk", "not closed"});
  // Vertex 6 pushed through the opposite corner: the surface intersects itself. TetGen 1.5
  // segfaults on this one; the child process turns that into an error.
  Mesh crossed = Cube();
  crossed.vertices.row(6) << -0.5, -0.5, -0.5;
  ExpectInputError([&] { Tetrahedralize(crossed, {}, "crossed"); },
                   {"crossed", "TetGen", "self-intersect"});
  // Two closed cubes touching at a corner, (1, 1, 1), which each has as its own vertex.
  Mesh twice = Cube();
  twice.vertices.conservativeResize(16, 3);
  twice.vertices.bottomRows(8) = Cube().vertices.rowwise() + Eigen::RowVector3d(1, 1, 1);
  twice.elements.conservativeResize(24, 3);
  twice.elements.bottomRows(12) = Cube().elements.array() + 8;
  ExpectInputError([&] { Tetrahedralize(twice, {}, "twice"); },
                   {"twice", "vertices 6 and 8 coincide"});
  Mesh tets;
  tets.vertices = Cube().vertices.topRows(4);
  tets.vertices.row(3) << 0, 0, 1;
  tets.elements.resize(1, 4);
  tets.elements << 0, 1, 2, 3;
  ExpectInputError([&] { Tetrahedralize(tets, {}, "tets"); }, {"has tetrahedra already"});
}

TEST_CASE("Tetrahedralize options are checked", "[io][tetrahedralize]") {
  CHECK(CheckTetrahedralizeOptions({}).empty());
  CHECK_THAT(CheckTetrahedralizeOptions({.max_volume = -1.0}), Contains("max_volume"));
  CHECK_THAT(CheckTetrahedralizeOptions({.max_volume = 1.0}), Contains("max_volume"));
  CHECK_THAT(CheckTetrahedralizeOptions({.max_radius_edge_ratio = 1.0}),
             Contains("max_radius_edge_ratio"));
  CHECK_THAT(CheckTetrahedralizeOptions({.min_dihedral_angle = 40.0}),
             Contains("min_dihedral_angle"));
  CHECK_THAT(CheckTetrahedralizeOptions({.max_radius_edge_ratio = 0.0, .min_dihedral_angle = 5}),
             Contains("needs quality refinement"));
  CHECK_THROWS_AS(Tetrahedralize(Cube(), {.max_volume = 2.0}, "cube"), ConfigError);
}

}  // namespace
}  // namespace harap
