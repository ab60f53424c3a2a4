// SPDX-License-Identifier: MIT
#include "framework/io/subdivision.h"

#include <catch2/catch.hpp>

#include <chrono>
#include <iostream>
#include <sstream>

#include "framework/error.h"
#include "framework/io/builtin_meshes.h"
#include "framework/io/mesh_io.h"
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
  for (const auto& [edge, count] : counts.directed) REQUIRE(count == 1);  // still oriented
  for (const auto& [edge, count] : counts.undirected) REQUIRE(count == 2);  // still closed

  // Old vertices come first, moved by the valence-3 rule (1 - 3b) p + b * sum(neighbours) with
  // b = 3/16; each edge gets 3/8 (a + b) + 1/8 (c + d) of its endpoints and opposite corners.
  const Positions& p = tetrahedron.vertices;
  for (Index v = 0; v < 4; ++v) {
    const Eigen::RowVector3d expected = (1.0 - 3.0 * 3.0 / 16.0) * p.row(v) +
                                        3.0 / 16.0 * (p.colwise().sum() - p.row(v));
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

TEST_CASE("LoopSubdivide rejects non-manifold input without printing", "[io][subdivision]") {
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
  std::string message;
  try {
    LoopSubdivide(book, 1);
  } catch (const InputError& error) {
    message = error.what();
  }
  std::cerr.rdbuf(old_err);
  std::cout.rdbuf(old_out);
  std::clog.rdbuf(old_log);
  CHECK_THAT(message, Contains("not manifold"));
  CHECK_THAT(message, Contains("triangle 2"));
  CHECK_THAT(message, Contains("complex edge"));  // OpenMesh's own diagnosis, captured
  CHECK(captured_err.str().empty());  // OpenMesh's complaint went into the message
  CHECK(captured_out.str().empty());
}

TEST_CASE("LoopSubdivide of the built-in cylinder stays a closed manifold", "[io][subdivision]") {
  const Mesh cylinder = MakeBuiltinMesh(
      ConfigNode::Parse("builtin = \"cylinder\"\nvertices = 2000", "test"));
  const Mesh refined = LoopSubdivide(cylinder, 1);
  const auto counts = testing::CountEdges(cylinder);
  CHECK(refined.num_vertices() ==
        cylinder.num_vertices() + static_cast<Index>(counts.undirected.size()));
  CHECK(refined.num_elements() == 4 * cylinder.num_elements());
  for (const auto& [edge, count] : testing::CountEdges(refined).undirected) REQUIRE(count == 2);
}

TEST_CASE("LoopSubdivide of armadillo-43k gives the paper's ~173K vertices", "[io][subdivision]"
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

TEST_CASE("LoopSubdivide names the problem for the non-manifold dragon-res2", "[io][subdivision]"
          "[shared]") {
  HARAP_REQUIRE_SHARED(file, "meshes/dragon-res2.obj.xz");
  CHECK_THROWS_WITH(LoopSubdivide(ReadMesh(file), 1), Contains("not manifold"));
}

}  // namespace
}  // namespace harap
