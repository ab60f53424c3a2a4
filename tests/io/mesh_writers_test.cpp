// SPDX-License-Identifier: MIT
// WriteMesh: the extension picks the format, each format reads back (exactly where the format
// can hold doubles), tetrahedra-only formats refuse triangle meshes, unknown extensions name the
// valid ones.
#include "io/mesh_writers.h"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "framework/error.h"
#include "io/mesh_io.h"
#include "io/tetrahedra.h"
#include "tests/support/test_meshes.h"

namespace harap {
namespace {

namespace fs = std::filesystem;
using Catch::Matchers::Contains;

fs::path TempDir() {
  const fs::path dir = fs::temp_directory_path() / fmt::format("harap-writers-{}", getpid());
  fs::create_directories(dir);
  return dir;
}

std::string Head(const fs::path& file, size_t bytes) {
  std::ifstream stream(file, std::ios::binary);
  std::string text(bytes, '\0');
  stream.read(text.data(), static_cast<std::streamsize>(bytes));
  return text;
}

TEST_CASE("WriteMesh writes the format of the extension and reads back", "[io][writers]") {
  const fs::path dir = TempDir();
  Mesh mesh = testing::Grid(4, 3);
  mesh.vertices(5, 0) = 0.1 + 1e-13;  // needs all 17 digits to survive text formats
  for (const char* extension : {".ply", ".obj", ".OFF"}) {
    INFO(extension);
    const fs::path file = dir / (std::string("grid") + extension);
    WriteMesh(file, mesh.vertices, mesh.elements);
    const Mesh back = ReadMesh(file);
    CHECK(back.vertices == mesh.vertices);  // exact, in the same vertex order
    CHECK(back.elements == mesh.elements);
  }
  CHECK(Head(dir / "grid.ply", 3) == "ply");
  CHECK(Head(dir / "grid.obj", 18) == "# written by harap");
  CHECK(Head(dir / "grid.OFF", 3) == "OFF");

  SECTION("stl: float32 per-triangle corners, welded again by the reader") {
    WriteMesh(dir / "grid.stl", mesh.vertices, mesh.elements);
    CHECK(fs::file_size(dir / "grid.stl") == 84 + 50 * static_cast<uintmax_t>(mesh.num_elements()));
    const Mesh back = ReadMesh(dir / "grid.stl");
    CHECK(back.num_vertices() == mesh.num_vertices());
    CHECK(back.num_elements() == mesh.num_elements());
  }

  SECTION("tetrahedra: .mesh and .node/.ele keep them, surface formats get the boundary") {
    const Mesh box = testing::TetBox(2, 2, 2);
    WriteMesh(dir / "box.mesh", box.vertices, box.elements);
    const Mesh medit = ReadMesh(dir / "box.mesh");
    CHECK(medit.vertices == box.vertices);
    CHECK(medit.elements == box.elements);
    WriteMesh(dir / "box.ele", box.vertices, box.elements);  // names the .node/.ele pair
    REQUIRE(fs::exists(dir / "box.node"));
    const Mesh tetgen = ReadMesh(dir / "box.node");
    CHECK(tetgen.vertices == box.vertices);
    CHECK(tetgen.elements == box.elements);
    CHECK(MeshOutputFiles(dir / "box.node") ==
          std::vector<fs::path>{dir / "box.node", dir / "box.ele"});
    WriteMesh(dir / "box.obj", box.vertices, box.elements);
    const Mesh surface = ReadMesh(dir / "box.obj");
    CHECK(surface.num_vertices() == box.num_vertices());
    CHECK(surface.elements == BoundaryTriangles(box.elements));
  }
  fs::remove_all(dir);
}

TEST_CASE("WriteMesh refuses names it cannot honour, listing the valid extensions",
          "[io][writers]") {
  const Mesh mesh = testing::Grid(2, 2);
  std::string message;
  try {
    CheckMeshOutputFormat("result.vtk", ElementKind::kTriangle);
  } catch (const InputError& error) {
    message = error.what();
  }
  CHECK_THAT(message, Contains("result.vtk") && Contains("'.vtk'") && Contains(".ply") &&
                          Contains(".obj") && Contains(".off") && Contains(".stl"));
  CHECK_THROWS_WITH(CheckMeshOutputFormat("result", ElementKind::kTriangle),
                    Contains("no extension"));
  CHECK_THROWS_WITH(CheckMeshOutputFormat("result.mesh", ElementKind::kTriangle),
                    Contains("holds tetrahedra") && Contains("triangle mesh"));
  CHECK_NOTHROW(CheckMeshOutputFormat("result.node", ElementKind::kTetrahedron));
  CHECK_THROWS_AS(WriteMesh("never-written.vtk", mesh.vertices, mesh.elements), InputError);
  CHECK_FALSE(fs::exists("never-written.vtk"));
}

}  // namespace
}  // namespace harap
