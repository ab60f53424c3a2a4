// SPDX-License-Identifier: MIT
#include "io/subdivision.h"

#include <catch2/catch.hpp>
#include <chrono>
#include <iostream>
#include <sstream>

#include "framework/error.h"
#include "io/builtin_meshes.h"
#include "io/mesh_io.h"
#include "tests/io/io_test_util.h"
#include "tests/support/shared_data.h"

namespace harap {
namespace {

using Catch::Matchers::Contains;

Mesh Tetrahedron() {
  Mesh mesh;
  mesh.vertices.resize(4, 3);
  mesh.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  mesh.elements.resize(4, 3);
  mesh.elements << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  return mesh;
}

// Does some vertex of `mesh` sit at `point`?
bool HasVertexAt(const Mesh& mesh, const Eigen::RowVector3d& point) {
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if ((mesh.vertices.row(v) - point).norm() < 1e-12) return true;
  }
  return false;
}

TEST_CASE("LoopSubdivide: counts and Loop's stencils on a tetrahedron", "[io][subdivision]") {
  const Mesh tetrahedron = Tetrahedron();
  const Mesh once = LoopSubdivide(tetrahedron, 1);
  REQUIRE(once.num_vertices() == 4 + 6);  // V + E
  REQUIRE(once.num_elements() == 16);
  const Mesh twice = LoopSubdivide(tetrahedron, 2);
  CHECK(twice.num_vertices() == 10 + 24);
  CHECK(twice.num_elements() == 64);
  const auto counts = testing::CountEdges(once);
  for (const auto& [edge, count] : counts.directed) REQUIRE(count == 1);    // still oriented
  for (const auto& [edge, count] : counts.undirected) REQUIRE(count == 2);  // still closed

  // Old vertices come first, moved by the valence-3 rule (1 - 3b) p + b * sum(neighbours) with
  // b = 3/16; each edge gets 3/8 (a + b) + 1/8 (c + d) of its endpoints and opposite corners.
  const Positions& p = tetrahedron.vertices;
  for (Index v = 0; v < 4; ++v) {
    const Eigen::RowVector3d expected =
        (1.0 - 3.0 * 3.0 / 16.0) * p.row(v) + 3.0 / 16.0 * (p.colwise().sum() - p.row(v));
    CHECK((once.vertices.row(v) - expected).norm() < 1e-14);
  }
  for (Index a = 0; a < 4; ++a) {
    for (Index b = a + 1; b < 4; ++b) {
      const Eigen::RowVector3d others = p.colwise().sum() - p.row(a) - p.row(b);
      const Eigen::RowVector3d expected = 3.0 / 8.0 * (p.row(a) + p.row(b)) + 1.0 / 8.0 * others;
      INFO("edge " << a << "-" << b);
      CHECK(HasVertexAt(once, expected));
    }
  }
  CHECK(testing::SignedVolume(once) > 0.0);  // orientation kept
}

TEST_CASE("LoopSubdivide: boundaries, unreferenced vertices, zero steps", "[io][subdivision]") {
  Mesh triangle;
  triangle.vertices.resize(4, 3);
  triangle.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5;  // vertex 3 is unreferenced
  triangle.elements.resize(1, 3);
  triangle.elements << 0, 1, 2;
  const Mesh refined = LoopSubdivide(triangle, 1);
  CHECK(refined.num_vertices() == 6);  // unreferenced vertex dropped
  CHECK(refined.num_elements() == 4);
  // Boundary edges get plain midpoints.
  CHECK(HasVertexAt(refined, Eigen::RowVector3d(0.5, 0.0, 0.0)));
  CHECK(HasVertexAt(refined, Eigen::RowVector3d(0.5, 0.5, 0.0)));

  const Mesh same = LoopSubdivide(triangle, 0);
  CHECK(same.vertices == triangle.vertices);
  CHECK(same.elements == triangle.elements);
  CHECK_THROWS_AS(LoopSubdivide(triangle, -1), InternalError);
}

TEST_CASE("LoopSubdivide refines non-manifold input with a note, without printing",
          "[io][subdivision]") {
  // Three triangles on one edge (a "book"): a halfedge mesh cannot hold the third.
  Mesh book;
  book.vertices.resize(5, 3);
  book.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1;
  book.elements.resize(3, 3);
  book.elements << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  std::ostringstream captured_err, captured_out;
  auto* old_err = std::cerr.rdbuf(captured_err.rdbuf());
  auto* old_out = std::cout.rdbuf(captured_out.rdbuf());
  auto* old_log = std::clog.rdbuf(captured_err.rdbuf());
  std::string note;
  const Mesh refined = LoopSubdivide(book, 1, &note);
  std::cerr.rdbuf(old_err);
  std::cout.rdbuf(old_out);
  std::clog.rdbuf(old_log);
  CHECK(refined.num_elements() == 12);
  CHECK(refined.num_vertices() == 5 + 7);  // 7 edges
  CHECK_THAT(note, Contains("not a manifold"));
  CHECK_THAT(note, Contains("triangle 2"));
  CHECK_THAT(note, Contains("complex edge"));  // OpenMesh's own diagnosis, captured
  CHECK_THAT(note, Contains("1 non-manifold edge "));
  CHECK(captured_err.str().empty());  // OpenMesh's complaint went into the note
  CHECK(captured_out.str().empty());
  // A manifold mesh gets no note.
  note.clear();
  LoopSubdivide(Tetrahedron(), 1, &note);
  CHECK(note.empty());
}

TEST_CASE("LoopSubdivideCreased: non-manifold edges are creases, non-manifold vertices stay",
          "[io][subdivision]") {
  // A book of three triangles on the edge (0, 1), plus two triangles touching it only at
  // vertex 2 (a non-manifold vertex: two fans), plus an unreferenced vertex 8.
  Mesh mesh;
  mesh.vertices.resize(9, 3);
  mesh.vertices << 0, 0, 0,  // 0
      2, 0, 0,               // 1
      1, 1, 0,               // 2: tip of the first page, and where the bowtie meets
      1, -1, 0,              // 3
      1, 0, 1,               // 4
      2, 2, 0,               // 5
      0, 2, 0,               // 6
      1, 3, 0,               // 7
      9, 9, 9;               // 8: unreferenced
  mesh.elements.resize(5, 3);
  mesh.elements << 0, 1, 2, 1, 0, 3, 0, 1, 4, 2, 5, 7, 2, 7, 6;
  Index edges = -1, vertices = -1;
  const Mesh refined = LoopSubdivideCreased(mesh, 1, &edges, &vertices);
  CHECK(edges == 1);     // (0, 1) has three triangles
  CHECK(vertices == 0);  // vertex 2 lies on boundary edges, so it is a corner, not counted
  const auto counts = testing::CountEdges(mesh);
  CHECK(refined.num_vertices() == 8 + static_cast<Index>(counts.undirected.size()));
  CHECK(refined.num_elements() == 20);
  // The old vertices first, in order, without the unreferenced one.
  // Vertex 0 lies on the crease (0, 1) and on boundary edges (0, 2), (0, 3), (0, 4): more than
  // two crease edges, so it is a corner and stays; so does vertex 2 (four boundary edges).
  CHECK(refined.vertices.row(0) == mesh.vertices.row(0));
  CHECK(refined.vertices.row(2) == mesh.vertices.row(2));
  // The non-manifold edge gets its midpoint (crease rule), not Loop's 3/8-1/8 stencil.
  CHECK(HasVertexAt(refined, Eigen::RowVector3d(1, 0, 0)));
  // Orientation of each triangle is kept: the first child of triangle 0 has normal +z.
  const Eigen::RowVector3d a = refined.vertices.row(refined.elements(0, 0));
  const Eigen::RowVector3d b = refined.vertices.row(refined.elements(0, 1));
  const Eigen::RowVector3d c = refined.vertices.row(refined.elements(0, 2));
  CHECK((b - a).cross(c - a)(2) > 0.0);

  // Two closed tetrahedra sharing one vertex: every edge has two triangles, but the shared
  // vertex has two fans, so it stays; the others follow Loop's rule.
  Mesh touching;
  touching.vertices.resize(7, 3);
  touching.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1;
  touching.elements.resize(8, 3);
  touching.elements << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3,  //
      0, 5, 4, 0, 4, 6, 0, 6, 5, 4, 5, 6;
  const Mesh split = LoopSubdivideCreased(touching, 1, &edges, &vertices);
  CHECK(edges == 0);
  CHECK(vertices == 1);
  CHECK(split.vertices.row(0) == touching.vertices.row(0));
  // Through the public entry point (OpenMesh refuses the second fan): refined with a note.
  std::string note;
  const Mesh through_public = LoopSubdivide(touching, 1, &note);
  CHECK_THAT(note, Contains("1 vertex where separate fans meet"));
  CHECK(through_public.vertices == split.vertices);
}

TEST_CASE("LoopSubdivideCreased equals OpenMesh's Loop on manifold meshes", "[io][subdivision]") {
  // Same vertex positions (as sets: the edge vertices may be numbered differently), for a closed
  // mesh (Loop's interior rule) and an open one (the boundary rules).
  Mesh open = Tetrahedron();
  open.elements.conservativeResize(3, 3);
  for (const Mesh& mesh : {Tetrahedron(), open}) {
    for (const int steps : {1, 2}) {
      const Mesh ours = LoopSubdivideCreased(mesh, steps);
      const Mesh theirs = LoopSubdivide(mesh, steps);
      REQUIRE(ours.num_vertices() == theirs.num_vertices());
      REQUIRE(ours.num_elements() == theirs.num_elements());
      // The original vertices keep their numbers in both.
      for (Index v = 0; v < mesh.num_vertices(); ++v) {
        CHECK((ours.vertices.row(v) - theirs.vertices.row(v)).norm() < 1e-12);
      }
      for (Index v = 0; v < ours.num_vertices(); ++v) {
        CHECK(HasVertexAt(theirs, ours.vertices.row(v)));
      }
    }
  }
}

TEST_CASE("LoopSubdivide of the built-in cylinder stays a closed manifold", "[io][subdivision]") {
  const Mesh cylinder =
      MakeBuiltinMesh(ConfigNode::Parse("builtin = \"cylinder\"\nvertices = 2000", "test"));
  const Mesh refined = LoopSubdivide(cylinder, 1);
  const auto counts = testing::CountEdges(cylinder);
  CHECK(refined.num_vertices() ==
        cylinder.num_vertices() + static_cast<Index>(counts.undirected.size()));
  CHECK(refined.num_elements() == 4 * cylinder.num_elements());
  for (const auto& [edge, count] : testing::CountEdges(refined).undirected) REQUIRE(count == 2);
}

TEST_CASE("LoopSubdivide of armadillo-43k gives the paper's ~173K vertices",
          "[io][subdivision]"
          "[shared]") {
  HARAP_REQUIRE_SHARED(file, "meshes/armadillo-43k.obj.xz");
  const Mesh mesh = ReadMesh(file);
  const auto start = std::chrono::steady_clock::now();
  const Mesh refined = LoopSubdivide(mesh, 1);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  WARN("armadillo-43k: Loop subdivision in " << seconds << " s");
  // Closed surface: V + E = V + 3F/2.
  CHECK(refined.num_vertices() == 43243 + 86482 * 3 / 2);
  CHECK(refined.num_vertices() == 172966);
  CHECK(refined.num_elements() == 4 * 86482);
  CHECK(BoundingBoxDiagonal(refined) == Approx(BoundingBoxDiagonal(mesh)).epsilon(0.02));
}

TEST_CASE("LoopSubdivide refines the non-manifold dragon-res2 with a note",
          "[io][subdivision]"
          "[shared]") {
  HARAP_REQUIRE_SHARED(file, "meshes/dragon-res2.obj.xz");
  const Mesh mesh = ReadMesh(file);
  std::string note;
  const Mesh refined = LoopSubdivide(mesh, 1, &note);
  CHECK_THAT(note, Contains("not a manifold"));
  CHECK(refined.num_elements() == 4 * mesh.num_elements());
}

}  // namespace
}  // namespace harap
