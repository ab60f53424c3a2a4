// SPDX-License-Identifier: MIT
// The per-format readers (obj_reader.h, off_reader.h, ply_reader.h, stl_reader.h) called
// directly: each gives what ReadMesh/ParseMesh give for its extension, names its source in
// errors, and PLY reads WritePly's doubles back exactly.
#include <catch2/catch.hpp>
#include <string>

#include "framework/error.h"
#include "io/file_reading.h"
#include "io/mesh_io.h"
#include "io/mesh_writers.h"
#include "io/obj_reader.h"
#include "io/off_reader.h"
#include "io/ply_reader.h"
#include "io/stl_reader.h"
#include "tests/io/io_test_util.h"

namespace {

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

// A unit square as two triangles (a quad, fan-triangulated by the text formats).
const std::string kObj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0.1\nf 1 2 3 4\n";
const std::string kOff = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0.1\n4 0 1 2 3\n";
const std::string kPly =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0.1\n4 0 1 2 3\n";
const std::string kStl =
    "solid square\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\n"
    "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\n"
    "vertex 0 1 0.1\nendloop\nendfacet\nendsolid square\n";

void CheckSame(const harap::Mesh& a, const harap::Mesh& b) {
  CHECK(a.vertices == b.vertices);
  CHECK(a.elements == b.elements);
}

}  // namespace

TEST_CASE("format readers: each reader gives what ParseMesh gives for its extension", "[io]") {
  const harap::Mesh obj = harap::ParseObj(kObj, "square.obj");
  CHECK(obj.num_vertices() == 4);
  CHECK(obj.num_elements() == 2);
  CheckSame(obj, harap::ParseMesh(kObj, "square.obj"));
  const harap::Mesh off = harap::ParseOff(kOff, "square.off");
  CheckSame(off, harap::ParseMesh(kOff, "square.off"));
  CheckSame(off, obj);
  const harap::Mesh ply = harap::ParsePly(kPly, "square.ply");
  CheckSame(ply, harap::ParseMesh(kPly, "square.ply"));
  CHECK(ply.elements == obj.elements);
  const harap::Mesh stl = harap::ParseStl(kStl, "square.stl");
  CheckSame(stl, harap::ParseMesh(kStl, "square.stl"));
  CHECK(stl.num_vertices() == 4);  // corners welded
  CHECK(stl.num_elements() == 2);
}

TEST_CASE("format readers: errors name the source and the line", "[io]") {
  CHECK_THROWS_WITH(harap::ParseObj("v 0 0 0\nf 1 2 3\n", "bad.obj"),
                    StartsWith("bad.obj: line 2: vertex index out of range"));
  CHECK_THROWS_WITH(harap::ParseOff("OFF\n3 1 0\n0 0 0\n1 0 0\n", "bad.off"),
                    StartsWith("bad.off: truncated file"));
  CHECK_THROWS_WITH(harap::ParsePly("ply\nformat ascii 1.0\nend_header\n", "bad.ply"),
                    StartsWith("bad.ply: PLY header declares no 'vertex' element"));
  CHECK_THROWS_WITH(harap::ParseStl("not an stl", "bad.stl"),
                    StartsWith("bad.stl: neither ASCII STL"));
}

TEST_CASE("format readers: WritePly's double coordinates read back exactly", "[io]") {
  const harap::testing::ScratchDir dir;
  harap::Positions vertices(3, 3);
  vertices << 0.1, 1.0 / 3.0, -2e-300, 1.0, 0.0, 0.0, 0.0, 1.0, 0.354446;
  harap::Elements triangles(1, 3);
  triangles << 0, 1, 2;
  const auto file = dir.path() / "exact.ply";
  harap::WritePly(file, vertices, triangles);
  const harap::Mesh mesh = harap::ParsePly(harap::ReadFileMaybeXz(file), file.string());
  CHECK(mesh.vertices == vertices);
  CHECK(mesh.elements == triangles);
}
