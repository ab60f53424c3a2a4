// SPDX-License-Identifier: MIT
#include "io/builtin_meshes.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "framework/error.h"
#include "tests/io/io_test_util.h"

namespace harap {
namespace {

using Catch::Matchers::Contains;

Mesh Make(const std::string& toml) { return MakeBuiltinMesh(ConfigNode::Parse(toml, "test.toml")); }

// Every edge in exactly two triangles, once in each direction (closed, oriented 2-manifold).
void CheckClosedOrientedManifold(const Mesh& mesh) {
  const auto counts = testing::CountEdges(mesh);
  int bad_edges = 0;
  for (const auto& [edge, count] : counts.undirected) bad_edges += count != 2;
  CHECK(bad_edges == 0);
  int repeated_directed = 0;
  for (const auto& [edge, count] : counts.directed) repeated_directed += count != 1;
  CHECK(repeated_directed == 0);
  // Euler characteristic of a sphere, and no vertex left out.
  const auto referenced = ReferencedVertices(mesh);
  CHECK(std::count(referenced.begin(), referenced.end(), false) == 0);
  CHECK(mesh.num_vertices() - static_cast<Index>(counts.undirected.size()) + mesh.num_elements() ==
        2);
}

// No folded triangle: caps face -z (bottom) / +z (top), the side faces away from the axis.
void CheckNormalsOutward(const Mesh& mesh) {
  const double top = mesh.vertices.col(2).maxCoeff();
  int folded = 0;
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    const Eigen::Vector3d p = mesh.vertices.row(mesh.elements(f, 0)).transpose();
    const Eigen::Vector3d q = mesh.vertices.row(mesh.elements(f, 1)).transpose();
    const Eigen::Vector3d r = mesh.vertices.row(mesh.elements(f, 2)).transpose();
    const Eigen::Vector3d normal = (q - p).cross(r - p);
    if (p.z() == q.z() && q.z() == r.z() && (p.z() == 0.0 || p.z() == top)) {
      folded += normal.z() * (p.z() == 0.0 ? -1.0 : 1.0) <= 0.0;
    } else {
      const Eigen::Vector3d centre = (p + q + r) / 3.0;
      folded += normal.dot(Eigen::Vector3d(centre.x(), centre.y(), 0.0)) <= 0.0;
    }
  }
  CHECK(folded == 0);
}

TEST_CASE("builtin cylinder: closed manifold of well-shaped triangles", "[io][builtin]") {
  const Mesh mesh = Make("builtin = \"cylinder\"");
  INFO("V = " << mesh.num_vertices() << ", F = " << mesh.num_elements());
  CHECK(std::abs(mesh.num_vertices() - 10000) <= 1000);
  CheckClosedOrientedManifold(mesh);
  // Outward normals: positive enclosed volume close to pi r^2 h (the polygon is inscribed).
  const double volume = testing::SignedVolume(mesh);
  CHECK(volume > 0.99 * M_PI * 0.25 * 4.0);
  CHECK(volume < M_PI * 0.25 * 4.0);
  // Near-equilateral side, concentric-ring caps: no slivers, no needle fans.
  const double min_angle = testing::MinAngleDegrees(mesh);
  INFO("smallest angle " << min_angle);
  CHECK(min_angle > 35.0);
  CheckNormalsOutward(mesh);
  CHECK(testing::MinArea(mesh) > 0.0);
  // Height / diameter = aspect (default 4), axis along z from 0.
  const Eigen::RowVector3d lo = mesh.vertices.colwise().minCoeff();
  const Eigen::RowVector3d hi = mesh.vertices.colwise().maxCoeff();
  CHECK(hi.z() - lo.z() == Approx(4.0));
  CHECK(lo.z() == 0.0);
  CHECK(hi.x() - lo.x() == Approx(1.0).epsilon(1e-3));
}

TEST_CASE("builtin cylinder: vertex counts within 10% for sizes and aspects", "[io][builtin]") {
  for (const int vertices : {100, 1000, 12345, 100000}) {
    for (const double aspect : {1.0, 4.0, 10.0}) {
      for (const bool caps : {true, false}) {
        const Mesh mesh =
            Make(fmt::format("builtin = \"cylinder\"\nvertices = {}\naspect = {}\n"
                             "caps = {}",
                             vertices, aspect, caps));
        INFO(vertices << " vertices, aspect " << aspect << ", caps " << caps << ": got "
                      << mesh.num_vertices());
        CHECK(std::abs(mesh.num_vertices() - vertices) <= vertices / 10);
        const double height = mesh.vertices.col(2).maxCoeff() - mesh.vertices.col(2).minCoeff();
        CHECK(height == Approx(aspect));
        CHECK(testing::MinArea(mesh) > 0.0);
        CHECK(testing::MinAngleDegrees(mesh) > 35.0);
        CheckNormalsOutward(mesh);
        if (caps) {
          CheckClosedOrientedManifold(mesh);
        } else {
          // Open tube: the two end rows are the only boundary.
          const auto counts = testing::CountEdges(mesh);
          int boundary = 0, interior = 0, other = 0;
          for (const auto& [edge, count] : counts.undirected) {
            (count == 1 ? boundary : count == 2 ? interior : other)++;
          }
          CHECK(other == 0);
          const int ring =
              static_cast<int>((mesh.vertices.col(2).array() == 0.0).count());  // bottom row
          CHECK(boundary == 2 * ring);
        }
      }
    }
  }
}

TEST_CASE("builtin cylinder of 480K vertices (the paper's size)", "[io][builtin]") {
  const Mesh mesh = Make("builtin = \"cylinder\"\nvertices = 480000");
  CHECK(std::abs(mesh.num_vertices() - 480000) <= 48000);
  CHECK(testing::MinArea(mesh) > 0.0);
}

TEST_CASE("builtin meshes are deterministic", "[io][builtin]") {
  for (const char* toml : {"builtin = \"cylinder\"\nvertices = 3000",
                           "builtin = \"plane\"\nvertices = 3000\nseed = 5"}) {
    const Mesh a = Make(toml);
    const Mesh b = Make(toml);
    CHECK(a.vertices == b.vertices);
    CHECK(a.elements == b.elements);
  }
  const Mesh seed1 = Make("builtin = \"plane\"\nseed = 1");
  const Mesh seed2 = Make("builtin = \"plane\"\nseed = 2");
  CHECK(seed1.vertices != seed2.vertices);
  CHECK(seed1.elements == seed2.elements);
}

TEST_CASE("builtin plane: grid with sharp spikes", "[io][builtin]") {
  const Mesh mesh = Make("builtin = \"plane\"\nvertices = 20000\nspikes = 5\nspike_height = 0.3");
  CHECK(std::abs(mesh.num_vertices() - 20000) <= 2000);
  CHECK(testing::MinArea(mesh) > 0.0);
  // Square of side 1 in xy.
  CHECK(mesh.vertices.col(0).minCoeff() == 0.0);
  CHECK(mesh.vertices.col(0).maxCoeff() == Approx(1.0));
  CHECK(mesh.vertices.col(1).maxCoeff() == Approx(1.0));
  // Spike tips sit on vertices: the maximum height is reached exactly, and is a strict local
  // maximum at (up to) 5 places; most of the plane stays flat.
  CHECK(mesh.vertices.col(2).maxCoeff() == Approx(0.3));
  CHECK(mesh.vertices.col(2).minCoeff() == 0.0);
  const Index tips = static_cast<Index>((mesh.vertices.col(2).array() == 0.3).count());
  CHECK(tips >= 1);
  CHECK(tips <= 5);
  const Index raised = static_cast<Index>((mesh.vertices.col(2).array() > 0.0).count());
  CHECK(raised > 5);                         // cones, not single raised vertices
  CHECK(raised < mesh.num_vertices() / 20);  // narrow
  // The border stays flat, and every triangle faces +z (the grid is oriented).
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    const double x = mesh.vertices(v, 0), y = mesh.vertices(v, 1);
    if (x == 0.0 || y == 0.0 || x > 0.9999 || y > 0.9999) REQUIRE(mesh.vertices(v, 2) == 0.0);
  }
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    const Eigen::Vector3d p = mesh.vertices.row(mesh.elements(f, 0)).transpose();
    const Eigen::Vector3d q = mesh.vertices.row(mesh.elements(f, 1)).transpose();
    const Eigen::Vector3d r = mesh.vertices.row(mesh.elements(f, 2)).transpose();
    REQUIRE((q - p).cross(r - p).z() > 0.0);
  }
  // A disk with boundary: every edge in one or two triangles.
  const auto counts = testing::CountEdges(mesh);
  for (const auto& [edge, count] : counts.undirected) REQUIRE((count == 1 || count == 2));
  const Mesh flat = Make("builtin = \"plane\"\nspikes = 0");
  CHECK(flat.vertices.col(2).cwiseAbs().maxCoeff() == 0.0);
}

// A planar disk-like mesh: z = 0, `planar` set, every triangle counter-clockwise (positive
// area), edges in one or two triangles with one boundary loop, Euler characteristic 1.
void CheckPlanarDisk(const Mesh& mesh) {
  CHECK(mesh.planar);
  CHECK(mesh.vertices.col(2).cwiseAbs().maxCoeff() == 0.0);
  int clockwise = 0;
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    const Eigen::Vector3d p = mesh.vertices.row(mesh.elements(f, 0)).transpose();
    const Eigen::Vector3d q = mesh.vertices.row(mesh.elements(f, 1)).transpose();
    const Eigen::Vector3d r = mesh.vertices.row(mesh.elements(f, 2)).transpose();
    clockwise += (q - p).cross(r - p).z() <= 0.0;
  }
  CHECK(clockwise == 0);
  const auto counts = testing::CountEdges(mesh);
  int boundary = 0;
  for (const auto& [edge, count] : counts.undirected) {
    REQUIRE((count == 1 || count == 2));
    boundary += count == 1;
  }
  for (const auto& [edge, count] : counts.directed) REQUIRE(count == 1);
  CHECK(boundary > 0);
  const auto referenced = ReferencedVertices(mesh);
  CHECK(std::count(referenced.begin(), referenced.end(), false) == 0);
  CHECK(mesh.num_vertices() - static_cast<Index>(counts.undirected.size()) + mesh.num_elements() ==
        1);
  CHECK(testing::MinAngleDegrees(mesh) > 25.0);
}

TEST_CASE("builtin disk and rectangle: planar, counter-clockwise, sized", "[io][builtin]") {
  for (const int vertices : {30, 1000, 20000}) {
    INFO("vertices = " << vertices);
    const Mesh disk = Make(fmt::format("builtin = \"disk\"\nvertices = {}", vertices));
    CheckPlanarDisk(disk);
    CHECK(std::abs(disk.num_vertices() - vertices) <= std::max(5, vertices / 10));
    CHECK(disk.vertices.rowwise().norm().maxCoeff() == Approx(0.5));
    // The area of an inscribed polygon: a little below pi / 4.
    double area = 0.0;
    for (Index f = 0; f < disk.num_elements(); ++f) {
      const Eigen::Vector3d p = disk.vertices.row(disk.elements(f, 0)).transpose();
      area += 0.5 * (disk.vertices.row(disk.elements(f, 1)).transpose() - p)
                        .cross(disk.vertices.row(disk.elements(f, 2)).transpose() - p)
                        .z();
    }
    CHECK(area < M_PI / 4);
    CHECK(area == Approx(M_PI / 4).epsilon(0.05));
    for (const double aspect : {1.0, 4.0, 0.25}) {
      INFO("aspect = " << aspect);
      const Mesh rectangle =
          Make(fmt::format("builtin = \"rectangle\"\nvertices = {}\n"
                           "aspect = {}",
                           vertices, aspect));
      CheckPlanarDisk(rectangle);
      CHECK(std::abs(rectangle.num_vertices() - vertices) <= std::max(10, vertices / 10));
      CHECK(rectangle.vertices.col(0).maxCoeff() == Approx(aspect));
      CHECK(rectangle.vertices.col(1).maxCoeff() == Approx(1.0));
      CHECK(rectangle.vertices.colwise().minCoeff().norm() == 0.0);
    }
  }
  CHECK(Make("builtin = \"disk\"\nvertices = 500").vertices ==
        Make("builtin = \"disk\"\nvertices = 500").vertices);
  CHECK_THROWS_WITH(Make("builtin = \"disk\"\naspect = 2"), Contains("unknown option 'aspect'"));
  CHECK_THROWS_WITH(Make("builtin = \"rectangle\"\nvertices = 3"), Contains("'vertices'"));
  CHECK_THROWS_WITH(Make("builtin = \"rectangle\"\naspect = 0"), Contains("'aspect'"));
}

TEST_CASE("builtin meshes reject unknown names, unknown keys and bad values", "[io][builtin]") {
  CHECK_THROWS_WITH(Make("builtin = \"torus\""),
                    Contains("torus") && Contains("cylinder") && Contains("plane"));
  CHECK_THROWS_AS(Make("builtin = \"torus\""), ConfigError);
  CHECK_THROWS_WITH(Make("vertices = 10"), Contains("builtin") && Contains("cylinder, plane"));
  CHECK_THROWS_WITH(
      Make("builtin = \"cylinder\"\nvertex = 10"),
      Contains("unknown option 'vertex'") && Contains("aspect") && Contains("test.toml:2"));
  CHECK_THROWS_WITH(Make("builtin = \"plane\"\naspect = 2"), Contains("unknown option 'aspect'"));
  CHECK_THROWS_WITH(Make("builtin = \"cylinder\"\nvertices = 0"), Contains("'vertices'"));
  CHECK_THROWS_WITH(Make("builtin = \"cylinder\"\naspect = -1.0"), Contains("'aspect'"));
  CHECK_THROWS_WITH(Make("builtin = \"cylinder\"\naspect = nan"), Contains("finite"));
  CHECK_THROWS_WITH(Make("builtin = \"plane\"\nvertices = 100\nspike_radius = 0.45"),
                    Contains("do not fit"));
  CHECK_THROWS_AS(Make("builtin = \"cylinder\"\nvertices = \"many\""), ConfigError);
  CHECK(BuiltinMeshNames() == std::vector<std::string>{"cylinder", "plane", "disk", "rectangle"});
}

}  // namespace
}  // namespace harap
