// SPDX-License-Identifier: MIT
#include "io/mesh_io.h"

#include <Eigen/Geometry>
#include <bit>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <sstream>

#include "framework/error.h"
#include "io/file_reading.h"
#include "io/mesh_writers.h"
#include "tests/io/io_test_util.h"
#include "tests/support/shared_data.h"
#include "tests/support/test_meshes.h"

namespace harap {
namespace {

using Catch::Matchers::Contains;
using testing::ScratchDir;

// A closed tetrahedron, xz-compressed by `xz -9e` (100 bytes), so the xz path is tested without
// the shared data folder.
const unsigned char kTetrahedronObjXz[] = {
    0xfd, 0x37, 0x7a, 0x58, 0x5a, 0x00, 0x00, 0x04, 0xe6, 0xd6, 0xb4, 0x46, 0x02, 0x00, 0x21,
    0x01, 0x1c, 0x00, 0x00, 0x00, 0x10, 0xcf, 0x58, 0xcc, 0xe0, 0x00, 0x3f, 0x00, 0x26, 0x5d,
    0x00, 0x3b, 0x08, 0x02, 0x11, 0x02, 0x0a, 0x80, 0x5b, 0x9c, 0x91, 0xd6, 0x00, 0x58, 0x23,
    0xd4, 0x68, 0x80, 0x15, 0x1f, 0xdd, 0x1f, 0x72, 0xa9, 0x5e, 0xd6, 0xdf, 0xbd, 0xd5, 0xcd,
    0x3e, 0x3c, 0x0d, 0x31, 0xbc, 0x33, 0xaa, 0xde, 0x00, 0x00, 0x00, 0x00, 0x2f, 0xb2, 0x7f,
    0x5f, 0x0d, 0x6d, 0x24, 0xdb, 0x00, 0x01, 0x42, 0x40, 0x3c, 0xd9, 0x15, 0x94, 0x1f, 0xb6,
    0xf3, 0x7d, 0x01, 0x00, 0x00, 0x00, 0x00, 0x04, 0x59, 0x5a};
const char kTetrahedronObj[] =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

std::string TetrahedronXzBytes() {
  return std::string(reinterpret_cast<const char*>(kTetrahedronObjXz), sizeof(kTetrahedronObjXz));
}

// Expects ReadMesh(file) to throw InputError whose message names the file and contains `phrase`.
void ExpectReadError(const std::filesystem::path& file, const std::string& phrase) {
  INFO("file: " << file.string());
  try {
    ReadMesh(file);
    FAIL("no exception; expected InputError containing '" << phrase << "'");
  } catch (const InputError& error) {
    const std::string message = error.what();
    INFO("message: " << message);
    CHECK_THAT(message, Contains(file.filename().string()));
    CHECK_THAT(message, Contains(phrase));
  }
}

// -----------------------------------------------------------------------------------------------
// Valid input.

TEST_CASE("ReadMesh reads OBJ keeping vertex order and unreferenced vertices", "[io]") {
  ScratchDir dir;
  const auto file = dir.Write("quad.obj",
                              "# comment\nv 0.1 0.2 0.3\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                              "v 9 9 9  # unused\nvt 0 0\nvn 0 0 1\ng group\n"
                              "f 1/1/1 2//1 3/1 4\nf -5 -4 -2\n");
  const Mesh mesh = ReadMesh(file);
  REQUIRE(mesh.num_vertices() == 5);
  REQUIRE(mesh.num_elements() == 3);  // the quad is fan-triangulated into two
  CHECK(mesh.vertices(0, 0) == 0.1);  // exact double, not float-rounded
  CHECK(mesh.vertices(0, 1) == 0.2);
  CHECK(mesh.vertices(0, 2) == 0.3);
  CHECK(mesh.vertices(4, 0) == 9.0);
  CHECK(mesh.elements.row(0) == Eigen::RowVector3i(0, 1, 2));
  CHECK(mesh.elements.row(1) == Eigen::RowVector3i(0, 2, 3));
  CHECK(mesh.elements.row(2) == Eigen::RowVector3i(0, 1, 3));  // relative indices
}

TEST_CASE("ReadMesh reads ASCII OFF with polygons and optional colours", "[io]") {
  ScratchDir dir;
  const auto file = dir.Write("square.off",
                              "COFF\n# comment\n5 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n"
                              "1 1 0 0 0 255 255\n0 1 0 1 1 1 255\n0.5 0.5 1e-3 0 0 0 0\n"
                              "4 0 1 2 3 1 0 0\n3 0 1 4\n");
  const Mesh mesh = ReadMesh(file);
  REQUIRE(mesh.num_vertices() == 5);
  REQUIRE(mesh.num_elements() == 3);
  CHECK(mesh.vertices(4, 2) == 1e-3);
  CHECK(mesh.elements.row(1) == Eigen::RowVector3i(0, 2, 3));
  CHECK(mesh.elements.row(2) == Eigen::RowVector3i(0, 1, 4));
}

TEST_CASE("ReadMesh reads ASCII PLY and big-endian binary PLY", "[io]") {
  ScratchDir dir;
  const auto ascii = dir.Write("a.ply",
                               "ply\nformat ascii 1.0\ncomment hi\nelement vertex 4\n"
                               "property float x\nproperty float y\nproperty float z\n"
                               "property uchar red\nelement face 1\n"
                               "property list uchar int vertex_indices\nproperty int flags\n"
                               "end_header\n0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0.25 4\n4 0 1 2 3 7\n");
  const Mesh a = ReadMesh(ascii);
  REQUIRE(a.num_vertices() == 4);
  REQUIRE(a.num_elements() == 2);
  CHECK(a.vertices(3, 2) == 0.25);

  // Big-endian: float coordinates, a list with a ushort count and uint indices.
  std::string big =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list ushort uint vertex_indices\nend_header\n";
  auto put_big = [&big](auto value) {
    unsigned char bytes[sizeof(value)];
    std::memcpy(bytes, &value, sizeof(value));
    if constexpr (std::endian::native == std::endian::little) {
      std::reverse(bytes, bytes + sizeof(value));
    }
    big.append(reinterpret_cast<const char*>(bytes), sizeof(value));
  };
  for (float value : {0.f, 0.f, 0.f, 1.5f, 0.f, 0.f, 0.f, 2.5f, -0.125f}) put_big(value);
  put_big(static_cast<uint16_t>(3));
  for (uint32_t index : {0u, 1u, 2u}) put_big(index);
  const Mesh b = ReadMesh(dir.Write("b.ply", big));
  REQUIRE(b.num_vertices() == 3);
  REQUIRE(b.num_elements() == 1);
  CHECK(b.vertices(1, 0) == 1.5);
  CHECK(b.vertices(2, 2) == -0.125);
}

TEST_CASE("ReadMesh reads ASCII and binary STL through OpenMesh, welding corners", "[io]") {
  ScratchDir dir;
  // Tetrahedron as 4 facets of 3 corners each: 12 corners, 4 distinct positions.
  const double p[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::string ascii = "solid tet\n";
  std::string binary(80, ' ');
  const uint32_t count = 4;
  binary.append(reinterpret_cast<const char*>(&count), 4);
  for (const auto& face : faces) {
    ascii += "  facet normal 0 0 0\n    outer loop\n";
    const float normal[3] = {0, 0, 0};
    binary.append(reinterpret_cast<const char*>(normal), 12);
    for (int corner : face) {
      ascii += fmt::format("      vertex {} {} {}\n", p[corner][0], p[corner][1], p[corner][2]);
      const float xyz[3] = {static_cast<float>(p[corner][0]), static_cast<float>(p[corner][1]),
                            static_cast<float>(p[corner][2])};
      binary.append(reinterpret_cast<const char*>(xyz), 12);
    }
    ascii += "    endloop\n  endfacet\n";
    binary.append(2, '\0');
  }
  ascii += "endsolid tet\n";
  for (const auto& [name, bytes] :
       {std::pair{std::string("a.stl"), ascii}, std::pair{std::string("b.stl"), binary}}) {
    INFO(name);
    const Mesh mesh = ReadMesh(dir.Write(name, bytes));
    REQUIRE(mesh.num_vertices() == 4);
    REQUIRE(mesh.num_elements() == 4);
    CHECK(testing::SignedVolume(mesh) == Approx(1.0 / 6.0));
  }
}

TEST_CASE("ReadMesh decompresses .xz in memory", "[io]") {
  ScratchDir dir;
  const Mesh compressed = ReadMesh(dir.Write("tet.obj.xz", TetrahedronXzBytes()));
  const Mesh plain = ReadMesh(dir.Write("tet.obj", kTetrahedronObj));
  REQUIRE(compressed.num_vertices() == 4);
  REQUIRE(compressed.num_elements() == 4);
  CHECK(compressed.vertices == plain.vertices);
  CHECK(compressed.elements == plain.elements);
  CHECK(ReadFileMaybeXz(dir.path() / "tet.obj.xz") == kTetrahedronObj);
  CHECK(ReadFileMaybeXz(dir.path() / "tet.obj") == kTetrahedronObj);
}

TEST_CASE("WritePly writes a tetrahedral mesh as its outward boundary triangles", "[io]") {
  ScratchDir dir;
  const int n = 4;
  const Mesh box = testing::TetBox(n, n, n);
  const auto file = dir.path() / "box.ply";
  WritePly(file, box.vertices, box.elements);
  const Mesh surface = ReadMesh(file);
  // Every vertex (interior ones too, unreferenced), and two triangles per boundary grid square.
  REQUIRE(surface.num_vertices() == box.num_vertices());
  REQUIRE(surface.num_elements() == 6 * 2 * (n - 1) * (n - 1));
  // Outward orientation: the enclosed volume by the divergence theorem is the unit cube's, +1.
  double volume = 0.0;
  for (Index f = 0; f < surface.num_elements(); ++f) {
    const Eigen::Vector3d a = surface.vertices.row(surface.elements(f, 0));
    const Eigen::Vector3d b = surface.vertices.row(surface.elements(f, 1));
    const Eigen::Vector3d c = surface.vertices.row(surface.elements(f, 2));
    volume += a.dot(b.cross(c)) / 6.0;
  }
  CHECK(volume == Approx(1.0));
}

TEST_CASE("WritePly then ReadMesh round-trips doubles bit-exactly", "[io]") {
  ScratchDir dir;
  uint64_t state = 42;
  Positions vertices(200, 3);
  for (Index v = 0; v < vertices.rows(); ++v) {
    for (int d = 0; d < 3; ++d) {
      // Full 53-bit mantissas over many magnitudes, and some awkward values.
      const double unit = static_cast<double>(testing::NextRandom(state) >> 11) * 0x1.0p-53;
      vertices(v, d) = (unit - 0.5) * std::pow(10.0, static_cast<int>(v % 40) - 20);
    }
  }
  vertices.row(0) << 0.1, -0.0, std::numeric_limits<double>::denorm_min();
  vertices.row(1) << std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest(),
      1.0 / 3.0;
  Elements elements(150, 3);
  for (Index f = 0; f < elements.rows(); ++f) elements.row(f) << f, f + 1, f + 2;
  // Vertices 152..199 are unreferenced and must survive too.
  const auto file = dir.path() / "round_trip.ply";
  WritePly(file, vertices, elements);
  const Mesh mesh = ReadMesh(file);
  REQUIRE(mesh.num_vertices() == vertices.rows());
  REQUIRE(mesh.elements == elements);
  for (Index v = 0; v < vertices.rows(); ++v) {
    for (int d = 0; d < 3; ++d) {
      INFO("vertex " << v << " coordinate " << d);
      REQUIRE(std::bit_cast<uint64_t>(mesh.vertices(v, d)) ==
              std::bit_cast<uint64_t>(vertices(v, d)));
    }
  }
  // The header is the documented one.
  const std::string bytes = testing::ReadBytes(file);
  CHECK_THAT(bytes, Contains("format binary_little_endian 1.0"));
  CHECK_THAT(bytes, Contains("property double x"));
  CHECK_THAT(bytes, Contains("property list uchar int vertex_indices"));
}

// -----------------------------------------------------------------------------------------------
// Bad input: every case is an InputError naming the file and the problem, never a crash or hang.

TEST_CASE("ReadMesh reports missing files and unknown extensions", "[io]") {
  ScratchDir dir;
  ExpectReadError(dir.path() / "nope.obj", "file not found");
  ExpectReadError(dir.path() / "nope.obj.xz", "file not found");
  const auto unknown = dir.Write("mesh.abc", "v 0 0 0\n");
  ExpectReadError(unknown, "unknown mesh file extension '.abc'");
  ExpectReadError(unknown, ".obj, .ply, .off, .stl");
  ExpectReadError(dir.Write("noext", "v 0 0 0\n"), "unknown mesh file extension");
  ExpectReadError(dir.Write("bunny.mesh", "MeshVersionFormatted 1\n"), "no Vertices section");
  ExpectReadError(dir.Write("bunny.node.xz", ""), "the .ele file with its tetrahedra is missing");
}

TEST_CASE("ReadMesh rejects empty files", "[io]") {
  ScratchDir dir;
  ExpectReadError(dir.Write("empty.obj", ""), "no vertices");
  ExpectReadError(dir.Write("empty.off", ""), "empty file");
  ExpectReadError(dir.Write("empty.ply", ""), "not a PLY file");
  ExpectReadError(dir.Write("empty.stl", ""), "neither ASCII STL");
  ExpectReadError(dir.Write("empty.obj.xz", ""), "not xz-compressed");
}

TEST_CASE("ReadMesh survives random bytes in every format", "[io]") {
  ScratchDir dir;
  uint64_t state = 7;
  for (const char* extension : {"obj", "off", "ply", "stl", "obj.xz", "ply.xz"}) {
    for (int trial = 0; trial < 20; ++trial) {
      std::string bytes(1 + testing::NextRandom(state) % 5000, '\0');
      for (char& c : bytes) c = static_cast<char>(testing::NextRandom(state));
      // Half of the trials start with a valid magic line, so the body parsers get garbage too.
      if (trial % 2 == 1) {
        const std::string_view ext(extension);
        if (ext == "off") bytes = "OFF\n3 1 0\n" + bytes;
        if (ext == "ply")
          bytes =
              "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
              "property float x\nproperty float y\nproperty float z\n"
              "element face 1\nproperty list uchar int vertex_indices\n"
              "end_header\n" +
              bytes;
        if (ext == "stl") bytes = "solid x\n facet normal 0 0 0\n  outer loop\n" + bytes;
        if (ext == "obj") bytes = "v 0 0 0\nf 1 2 3\n" + bytes;
      }
      const auto file = dir.Write(fmt::format("random.{}", extension), bytes);
      INFO(extension << " trial " << trial);
      CHECK_THROWS_AS(ReadMesh(file), InputError);
    }
  }
}

TEST_CASE("ReadMesh survives mutations of valid files in every format", "[io]") {
  ScratchDir dir;
  Positions vertices(5, 3);
  vertices << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 1;
  Elements elements(4, 3);
  elements << 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4;
  WritePly(dir.path() / "pyramid.ply", vertices, elements);
  std::string binary_stl(80, ' ');
  const uint32_t count = 2;
  binary_stl.append(reinterpret_cast<const char*>(&count), 4);
  for (const float corner : {0.f, 1.f}) {
    const float facet[12] = {0, 0, 1, corner, 0, 0, 1, 1, 0, 0, 1, 0};
    binary_stl.append(reinterpret_cast<const char*>(facet), sizeof(facet));
    binary_stl.append(2, '\0');
  }
  const std::vector<std::pair<std::string, std::string>> seeds = {
      {"obj", kTetrahedronObj},
      {"off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n4 0 1 2 3\n"},
      {"ply", testing::ReadBytes(dir.path() / "pyramid.ply")},
      {"ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
       "property double z\nelement face 1\nproperty list uchar int vertex_indices\n"
       "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {"stl",
       "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
       "vertex 0 1 0\nendloop\nendfacet\nendsolid s\n"},
      {"stl", binary_stl},
      {"obj.xz", TetrahedronXzBytes()}};
  uint64_t state = 99;
  int accepted = 0;
  int rejected = 0;
  for (const auto& [extension, original] : seeds) {
    for (int trial = 0; trial < 300; ++trial) {
      std::string bytes = original;
      testing::Mutate(bytes, state);
      const auto file = dir.Write("mutant." + extension, bytes);
      INFO(extension << " trial " << trial);
      try {
        const Mesh mesh = ReadMesh(file);
        // Whatever is accepted is a valid mesh.
        CHECK_NOTHROW(ValidateMesh(mesh, "mutant"));
        ++accepted;
      } catch (const InputError&) {
        ++rejected;  // anything but InputError escapes and fails the test
      }
    }
  }
  CHECK(accepted > 0);
  CHECK(rejected > 0);
}

TEST_CASE("ReadMesh rejects every truncation of a binary PLY", "[io]") {
  ScratchDir dir;
  Positions vertices(5, 3);
  vertices << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 1;
  Elements elements(4, 3);
  elements << 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4;
  const auto full = dir.path() / "full.ply";
  WritePly(full, vertices, elements);
  const std::string bytes = testing::ReadBytes(full);
  const size_t body = bytes.find("end_header\n") + std::strlen("end_header\n");
  for (size_t length = 0; length < bytes.size(); ++length) {
    INFO("length " << length << " of " << bytes.size());
    const auto file = dir.Write("cut.ply", bytes.substr(0, length));
    if (length > body) {
      ExpectReadError(file, "truncated");
    } else {
      CHECK_THROWS_AS(ReadMesh(file), InputError);
    }
  }
  CHECK(ReadMesh(full).num_elements() == 4);
}

TEST_CASE("ReadMesh rejects out-of-range, zero and negative OBJ indices", "[io]") {
  ScratchDir dir;
  const std::string vertices = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  ExpectReadError(dir.Write("high.obj", vertices + "f 1 2 4\n"), "out of range");
  ExpectReadError(dir.Write("zero.obj", vertices + "f 0 1 2\n"), "out of range: 0");
  ExpectReadError(dir.Write("negative.obj", vertices + "f -1 -2 -4\n"), "out of range");
  ExpectReadError(dir.Write("high.obj", vertices + "f 1 2 4\n"), "line 4");
  ExpectReadError(dir.Write("repeat.obj", vertices + "f 1 1 2\n"), "degenerate face");
  ExpectReadError(dir.Write("short.obj", vertices + "f 1 2\n"), "face has 2 vertices");
  ExpectReadError(dir.Write("word.obj", vertices + "f 1 2 x\n"), "not an index");
}

TEST_CASE("ReadMesh rejects out-of-range indices in PLY, OFF", "[io]") {
  ScratchDir dir;
  Positions vertices(3, 3);
  vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  Elements elements(1, 3);
  elements << 0, 1, 2;
  WritePly(dir.path() / "ok.ply", vertices, elements);
  std::string bytes = testing::ReadBytes(dir.path() / "ok.ply");
  const int32_t bad = 3;
  std::memcpy(bytes.data() + bytes.size() - 4, &bad, 4);
  ExpectReadError(dir.Write("bad.ply", bytes), "out of range");
  const int32_t negative = -1;
  std::memcpy(bytes.data() + bytes.size() - 4, &negative, 4);
  ExpectReadError(dir.Write("negative.ply", bytes), "out of range");
  ExpectReadError(dir.Write("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
                  "out of range");
  ExpectReadError(dir.Write("cut.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n"), "truncated");
  ExpectReadError(dir.Write("huge.off", "OFF\n3 2000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                  "truncated");
  ExpectReadError(dir.Write("bin.off", "OFF BINARY\n"), "ends inside the vertex/face/edge counts");
}

TEST_CASE("ReadMesh rejects non-finite coordinates in every format", "[io]") {
  ScratchDir dir;
  ExpectReadError(dir.Write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"), "non-finite");
  ExpectReadError(dir.Write("inf.obj", "v 0 0 0\nv 1 -inf 0\nv 0 1 0\nf 1 2 3\n"), "non-finite");
  ExpectReadError(dir.Write("big.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n"), "non-finite");
  ExpectReadError(dir.Write("nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n"),
                  "non-finite");
  ExpectReadError(dir.Write("nan.stl",
                            "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                            "vertex nan 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n"),
                  "non-finite");
  Positions vertices(3, 3);
  vertices << 0, 0, 0, std::numeric_limits<double>::quiet_NaN(), 0, 0, 0, 1, 0;
  Elements elements(1, 3);
  elements << 0, 1, 2;
  WritePly(dir.path() / "nan.ply", vertices, elements);
  ExpectReadError(dir.path() / "nan.ply", "non-finite");
}

TEST_CASE("ReadMesh rejects files without faces", "[io]") {
  ScratchDir dir;
  ExpectReadError(dir.Write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "no faces");
  ExpectReadError(dir.Write("points.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"), "no faces");
  Positions vertices(3, 3);
  vertices.setZero();
  WritePly(dir.path() / "points.ply", vertices, Elements(0, 3));
  ExpectReadError(dir.path() / "points.ply", "no faces");
  ExpectReadError(dir.Write("points.stl", "solid s\nendsolid s\n"), "no faces");
}

TEST_CASE("ReadFileMaybeXz reports corrupt and truncated xz data", "[io]") {
  ScratchDir dir;
  std::string corrupt = TetrahedronXzBytes();
  corrupt[40] = static_cast<char>(corrupt[40] ^ 0x55);
  const auto corrupt_file = dir.Write("corrupt.obj.xz", corrupt);
  CHECK_THROWS_WITH(ReadFileMaybeXz(corrupt_file),
                    Contains("corrupt.obj.xz") && Contains("corrupt xz data"));
  ExpectReadError(corrupt_file, "corrupt xz data");
  const auto truncated = dir.Write("cut.obj.xz", TetrahedronXzBytes().substr(0, 60));
  CHECK_THROWS_WITH(ReadFileMaybeXz(truncated), Contains("truncated xz data"));
  const auto plain = dir.Write("plain.obj.xz", kTetrahedronObj);
  CHECK_THROWS_WITH(ReadFileMaybeXz(plain), Contains("not xz-compressed"));
  CHECK_THROWS_AS(ReadFileMaybeXz(dir.path() / "missing.xz"), InputError);
}

// -----------------------------------------------------------------------------------------------
// The shared meshes.

struct ManifestRow {
  std::string file;
  Index vertices = 0;
  Index faces = 0;
  double bbox_diagonal = 0.0;
  std::string type;
};

std::vector<ManifestRow> ReadManifest(const std::filesystem::path& file) {
  std::ifstream stream(file);
  std::string line;
  std::getline(stream, line);
  std::vector<std::string> columns;
  {
    std::istringstream header(line);
    for (std::string column; std::getline(header, column, '\t');) columns.push_back(column);
  }
  auto column = [&](const std::string& name) {
    const auto it = std::find(columns.begin(), columns.end(), name);
    REQUIRE(it != columns.end());
    return static_cast<size_t>(it - columns.begin());
  };
  const size_t c_file = column("file"), c_v = column("vertices"), c_f = column("faces"),
               c_d = column("bbox_diagonal"), c_type = column("type");
  std::vector<ManifestRow> rows;
  while (std::getline(stream, line)) {
    std::vector<std::string> cells;
    std::istringstream row(line);
    for (std::string cell; std::getline(row, cell, '\t');) cells.push_back(cell);
    if (cells.size() < columns.size()) continue;
    rows.push_back({cells[c_file], std::stoi(cells[c_v]), std::stoi(cells[c_f]),
                    std::stod(cells[c_d]), cells[c_type]});
  }
  return rows;
}

void CheckSharedMesh(const std::filesystem::path& dir, const ManifestRow& row) {
  INFO(row.file);
  const auto start = std::chrono::steady_clock::now();
  const Mesh mesh = ReadMesh(dir / row.file);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  CHECK(mesh.num_vertices() == row.vertices);
  CHECK(mesh.num_elements() == row.faces);
  // The manifest's diagonal is of the referenced vertices, printed with 6 digits.
  CHECK(BoundingBoxDiagonal(mesh) == Approx(row.bbox_diagonal).epsilon(1e-5));
  WARN(row.file << ": read in " << seconds << " s");
}

TEST_CASE("ReadMesh reads every shared surface mesh with the manifest's counts", "[io][shared]") {
  HARAP_REQUIRE_SHARED(manifest, "meshes/MANIFEST.tsv");
  const auto rows = ReadManifest(manifest);
  REQUIRE(rows.size() >= 14);
  int checked = 0;
  for (const ManifestRow& row : rows) {
    if (row.type != "tri" || row.file == "dragon.obj.xz") continue;  // dragon: [slow] below
    CheckSharedMesh(manifest.parent_path(), row);
    ++checked;
  }
  CHECK(checked == 13);
}

TEST_CASE("ReadMesh reads the shared tetrahedral meshes with the manifest's counts",
          "[io][shared][tet]") {
  HARAP_REQUIRE_SHARED(manifest, "meshes/MANIFEST.tsv");
  int checked = 0;
  for (const ManifestRow& row : ReadManifest(manifest)) {
    if (row.type != "tet") continue;
    CheckSharedMesh(manifest.parent_path(), row);
    ++checked;
  }
  CHECK(checked == 2);
}

TEST_CASE("ReadMesh reads the full Stanford dragon", "[io][shared][.slow]") {
  HARAP_REQUIRE_SHARED(manifest, "meshes/MANIFEST.tsv");
  for (const ManifestRow& row : ReadManifest(manifest)) {
    if (row.file == "dragon.obj.xz") CheckSharedMesh(manifest.parent_path(), row);
  }
}

TEST_CASE("ReadMesh gives identical meshes for a shared file and its decompressed copy",
          "[io][shared]") {
  HARAP_REQUIRE_SHARED(cow, "meshes/cow.ply.xz");
  HARAP_REQUIRE_SHARED(cactus, "meshes/cactus.obj.xz");
  ScratchDir dir;
  for (const auto& compressed : {cow, cactus}) {
    INFO(compressed.string());
    const auto plain = dir.Write(compressed.stem().string(), ReadFileMaybeXz(compressed));
    const Mesh a = ReadMesh(compressed);
    const Mesh b = ReadMesh(plain);
    CHECK(a.vertices == b.vertices);
    CHECK(a.elements == b.elements);
  }
}

TEST_CASE("ReadMesh keeps the bunny's unreferenced vertices and the non-manifold dragon-res2",
          "[io][shared]") {
  HARAP_REQUIRE_SHARED(bunny, "meshes/stanford-bunny.obj.xz");
  const Mesh mesh = ReadMesh(bunny);
  const auto referenced = ReferencedVertices(mesh);
  CHECK(std::count(referenced.begin(), referenced.end(), false) == 1113);
  HARAP_REQUIRE_SHARED(dragon, "meshes/dragon-res2.obj.xz");
  const Mesh res2 = ReadMesh(dragon);
  // Edges with more than two triangles are kept, not dropped as a halfedge mesh would.
  const auto counts = testing::CountEdges(res2);
  int nonmanifold = 0;
  for (const auto& [edge, count] : counts.undirected) nonmanifold += count > 2;
  CHECK(nonmanifold == 2534);
}

}  // namespace
}  // namespace harap
