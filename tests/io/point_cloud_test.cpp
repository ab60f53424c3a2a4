// SPDX-License-Identifier: MIT
// Point clouds (io/point_cloud.h) and PLY files with per-vertex values (WritePly).
#include "io/point_cloud.h"

#include <catch2/catch.hpp>

#include "framework/error.h"
#include "io/file_reading.h"
#include "io/mesh_io.h"
#include "io/mesh_writers.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

TEST_CASE("point clouds are read from text and PLY files", "[io][point_cloud]") {
  ScratchDir dir;
  SECTION("x y z per line, comments and blank lines skipped") {
    const PointCloud cloud =
        ReadPointCloud(dir.Write("a.xyz", "# scan\n0 0 0\n\n1 2 3\n  -1e-3 4.5 6 \n"));
    REQUIRE(cloud.points.rows() == 3);
    CHECK(cloud.points.row(1) == Eigen::RowVector3d(1, 2, 3));
    CHECK(cloud.points(2, 0) == -1e-3);
    CHECK(cloud.normals.rows() == 0);
  }
  SECTION("x y z nx ny nz per line") {
    const PointCloud cloud = ReadPointCloud(dir.Write("a.pts", "0 0 0 0 0 1\n1 0 0 0 1 0\n"));
    REQUIRE(cloud.normals.rows() == 2);
    CHECK(cloud.normals.row(1) == Eigen::RowVector3d(0, 1, 0));
  }
  SECTION("a PLY file's vertices, normals included, faces ignored") {
    const std::string ply =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n";
    const PointCloud cloud = ReadPointCloud(dir.Write("a.ply", ply));
    CHECK(cloud.points.rows() == 3);
    CHECK(cloud.normals.rows() == 3);
    CHECK(cloud.points.row(2) == Eigen::RowVector3d(0, 1, 0));
  }
  SECTION("a PLY file of vertices alone") {
    const std::string ply =
        "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
        "property double z\nend_header\n0.5 0 0\n1 1 1\n";
    const PointCloud cloud = ReadPointCloud(dir.Write("b.ply", ply));
    CHECK(cloud.points.rows() == 2);
    CHECK(cloud.normals.rows() == 0);
    CHECK_THROWS_WITH(ReadMesh(dir.path() / "b.ply"), Catch::Contains("no faces"));
    CHECK(HoldsPointCloud(dir.path() / "b.ply"));
  }
  SECTION("a PLY mesh, even with broken faces, is a mesh, not points") {
    const std::string ply =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n";
    const std::filesystem::path file = dir.Write("broken.ply", ply);
    CHECK_FALSE(HoldsPointCloud(file));
    CHECK_THROWS_WITH(ReadMesh(file), Catch::Contains("7"));
  }
  CHECK(IsPointCloudFile("scan.xyz"));
  CHECK(IsPointCloudFile("scan.TXT.xz"));
  CHECK_FALSE(IsPointCloudFile("scan.ply"));
}

TEST_CASE("bad point clouds are refused naming the file and line", "[io][point_cloud]") {
  ScratchDir dir;
  CHECK_THROWS_WITH(ReadPointCloud(dir.Write("a.xyz", "0 0 0\n1 2\n")),
                    Catch::Contains("a.xyz:2: 2 values"));
  CHECK_THROWS_WITH(ReadPointCloud(dir.Write("b.xyz", "0 0 0\n1 2 3 0 0 1\n")),
                    Catch::Contains("b.xyz:2: 6 values, but the first point has 3"));
  CHECK_THROWS_WITH(ReadPointCloud(dir.Write("c.xyz", "0 0 nan\n")),
                    Catch::Contains("c.xyz:1: value 3 is not finite"));
  CHECK_THROWS_WITH(ReadPointCloud(dir.Write("d.xyz", "0 0 zero\n")),
                    Catch::Contains("d.xyz:1:") && Catch::Contains("not a number"));
  CHECK_THROWS_WITH(ReadPointCloud(dir.Write("e.xyz", "# nothing\n")),
                    Catch::Contains("no points"));
  CHECK_THROWS_WITH(ReadPointCloud(dir.Write("f.obj", "v 0 0 0\n")),
                    Catch::Contains("unknown point cloud extension"));
  CHECK_THROWS_WITH(ReadPointCloud(dir.path() / "missing.xyz"), Catch::Contains("not found"));
  const std::string nan_normal =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n"
      "0 0 0 0 nan 1\n";
  CHECK_THROWS_WITH(ReadPointCloud(dir.Write("g.ply", nan_normal)),
                    Catch::Contains("non-finite normal"));
}

TEST_CASE("WritePly stores per-vertex values after the coordinates", "[io][point_cloud]") {
  ScratchDir dir;
  const Mesh grid = Grid(3, 3);
  std::vector<double> distance(grid.num_vertices());
  for (size_t v = 0; v < distance.size(); ++v) distance[v] = 0.25 * static_cast<double>(v);
  const std::filesystem::path file = dir.path() / "values.ply";
  WritePly(file, grid.vertices, grid.elements, {{"distance", distance}});
  const Mesh read = ReadMesh(file);  // the extra property is skipped
  CHECK(read.vertices == grid.vertices);
  CHECK(read.elements == grid.elements);
  const std::string text = ReadFileMaybeXz(file);
  CHECK(text.find("property double distance\n") != std::string::npos);
  CHECK_THROWS_AS(WritePly(file, grid.vertices, grid.elements, {{"distance", {1.0}}}),
                  InternalError);
}
