// SPDX-License-Identifier: MIT
// The per-format readers (obj_reader.h, off_reader.h, ply_reader.h, stl_reader.h) called
// directly: each gives what ReadMesh/ParseMesh give for its extension, names its source in
// errors, PLY reads WritePly's doubles back exactly, and binary OFF reads in both layouts.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstring>
#include <sstream>
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
#include "tests/support/shared_data.h"

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

namespace {

// Appends `value` as 4 bytes in the given byte order.
template <typename T>
void AppendWord(std::string& bytes, T value, bool big_endian) {
  static_assert(sizeof(T) == 4);
  unsigned char word[4];
  std::memcpy(word, &value, 4);
  if (big_endian) std::reverse(word, word + 4);
  bytes.append(reinterpret_cast<const char*>(word), 4);
}

// The square of kOff as binary OFF: little-endian without colour counts (pmp-library's layout)
// or big-endian with a colour count per face (Geomview's), the quad split into two faces.
std::string BinarySquareOff(bool big_endian, bool colour_counts) {
  std::string bytes = "OFF BINARY\n";
  for (int32_t count : {4, 2, 0}) AppendWord(bytes, count, big_endian);
  for (float coordinate : {0.F, 0.F, 0.F, 1.F, 0.F, 0.F, 1.F, 1.F, 0.F, 0.F, 1.F, 0.1F}) {
    AppendWord(bytes, coordinate, big_endian);
  }
  const std::array<std::array<int32_t, 3>, 2> faces = {{{0, 1, 2}, {0, 2, 3}}};
  for (const std::array<int32_t, 3>& face : faces) {
    AppendWord(bytes, int32_t{3}, big_endian);
    for (int32_t corner : face) AppendWord(bytes, corner, big_endian);
    if (colour_counts) {
      AppendWord(bytes, int32_t{3}, big_endian);  // an RGB colour, ignored
      for (float channel : {0.5F, 0.25F, 1.F}) AppendWord(bytes, channel, big_endian);
    }
  }
  return bytes;
}

}  // namespace

TEST_CASE("format readers: binary OFF in both layouts reads like the ASCII square", "[io]") {
  const harap::Mesh ascii = harap::ParseOff(kOff, "square.off");
  for (const bool big_endian : {false, true}) {
    CAPTURE(big_endian);
    const harap::Mesh binary =
        harap::ParseMesh(BinarySquareOff(big_endian, /*colour_counts=*/big_endian), "square.off");
    CHECK(binary.elements == ascii.elements);
    // float32 coordinates: 0.1 is stored as the nearest float.
    CHECK(binary.vertices(3, 2) == static_cast<double>(0.1F));
    CHECK(binary.vertices.topRows(3) == ascii.vertices.topRows(3));
  }
}

TEST_CASE("format readers: broken binary OFF files are errors naming the problem", "[io]") {
  const std::string good = BinarySquareOff(false, false);
  // Cut inside the faces, cut inside the counts, and garbage after the last face.
  CHECK_THROWS_WITH(harap::ParseOff(good.substr(0, good.size() - 6), "cut.off"),
                    StartsWith("cut.off: binary OFF that reads in none of the known layouts") &&
                        Contains("little-endian without per-face colour counts: truncated file"));
  CHECK_THROWS_WITH(harap::ParseOff(good.substr(0, 17), "short.off"),
                    Contains("ends inside the vertex/face/edge counts"));
  CHECK_THROWS_WITH(harap::ParseOff(good + "xyz", "long.off"),
                    Contains("3 bytes follow the last face"));
  // A face index out of range in an otherwise well-formed file names the face and its byte.
  std::string bad_index = good;
  const int32_t out_of_range = 9;
  std::memcpy(bad_index.data() + bad_index.size() - 4, &out_of_range, 4);
  CHECK_THROWS_WITH(harap::ParseOff(bad_index, "index.off"),
                    Contains("byte 87: face 1: vertex index out of range: 9"));
}

TEST_CASE("format readers: every mesh of the shared dataset reads with its listed counts",
          "[io][shared]") {
  HARAP_REQUIRE_SHARED(manifest, "meshes/datasets/MANIFEST.tsv");
  const std::string table = harap::testing::ReadBytes(manifest);
  std::istringstream lines(table);
  std::string line;
  std::getline(lines, line);  // header: file vertices faces ...
  int files = 0;
  while (std::getline(lines, line)) {
    std::istringstream fields(line);
    std::string file;
    harap::Index vertices = 0;
    harap::Index faces = 0;
    fields >> file >> vertices >> faces;
    CAPTURE(file);
    const harap::Mesh mesh = harap::ReadMesh(manifest.parent_path() / file);
    CHECK(mesh.num_vertices() == vertices);
    CHECK(mesh.num_elements() == faces);
    ++files;
  }
  CHECK(files >= 8);
}
