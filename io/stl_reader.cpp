// SPDX-License-Identifier: MIT
//
// STL goes through OpenMesh's reader: its coordinates are float32 in the format anyway, and
// OpenMesh welds the per-triangle corners into shared vertices. The data is pre-validated here:
// OpenMesh's binary reader trusts the triangle count in the header (a truncated file makes it
// read zeros for up to 2^32 triangles) and its ASCII reader turns an unparsable coordinate into
// 0 silently.
#include "io/stl_reader.h"

#include <fmt/format.h>

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/Options.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/IO/reader/STLReader.hh>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <vector>

#include "io/openmesh_log.h"
#include "io/raw_mesh.h"
#include "io/text_scanning.h"

namespace harap {

namespace {

using namespace io_internal;

// STL through OpenMesh, collecting raw positions and triangles.

// The colours and status of one kind of item (vertex, edge, face), which RawImporter ignores:
// BaseImporter declares them pure virtual, once per item kind.
#define HARAP_IGNORE_COLORS_AND_STATUS(Handle)                \
  void set_color(Handle, const OpenMesh::Vec3uc&) override {} \
  void set_color(Handle, const OpenMesh::Vec4uc&) override {} \
  void set_color(Handle, const OpenMesh::Vec3f&) override {}  \
  void set_color(Handle, const OpenMesh::Vec4f&) override {}  \
  void set_status(Handle, const OpenMesh::Attributes::StatusInfo&) override {}

// Collects what an OpenMesh reader produces without building a halfedge mesh (a halfedge mesh
// would refuse non-manifold faces, and real meshes have them).
class RawImporter final : public OpenMesh::IO::BaseImporter {
 public:
  explicit RawImporter(RawMesh& raw) : raw_(raw) {}

  OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3f& point) override {
    return add_vertex(OpenMesh::Vec3d(point[0], point[1], point[2]));
  }
  OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3d& point) override {
    raw_.xyz.insert(raw_.xyz.end(), {point[0], point[1], point[2]});
    return OpenMesh::VertexHandle(static_cast<int>(raw_.xyz.size() / 3 - 1));
  }
  OpenMesh::VertexHandle add_vertex() override { return add_vertex(OpenMesh::Vec3d(0, 0, 0)); }
  void set_point(OpenMesh::VertexHandle vertex, const OpenMesh::Vec3f& point) override {
    const size_t v = static_cast<size_t>(vertex.idx());
    if (vertex.idx() < 0 || 3 * v + 2 >= raw_.xyz.size()) return;
    raw_.xyz[3 * v] = point[0];
    raw_.xyz[3 * v + 1] = point[1];
    raw_.xyz[3 * v + 2] = point[2];
  }
  OpenMesh::FaceHandle add_face(const VHandles& vertices) override {
    polygon_.clear();
    for (const auto& vertex : vertices) polygon_.push_back(vertex.idx());
    raw_.AddPolygon(polygon_, faces_);
    return OpenMesh::FaceHandle(static_cast<int>(faces_++));
  }
  size_t n_vertices() const override { return raw_.xyz.size() / 3; }
  size_t n_faces() const override { return static_cast<size_t>(faces_); }
  size_t n_edges() const override { return 0; }

  // Attributes and connectivity hints we do not keep.
  OpenMesh::HalfedgeHandle add_edge(OpenMesh::VertexHandle, OpenMesh::VertexHandle) override {
    return OpenMesh::HalfedgeHandle();
  }
  OpenMesh::FaceHandle add_face(OpenMesh::HalfedgeHandle) override {
    return OpenMesh::FaceHandle();
  }
  void add_face_texcoords(OpenMesh::FaceHandle, OpenMesh::VertexHandle,
                          const std::vector<OpenMesh::Vec2f>&) override {}
  void add_face_texcoords(OpenMesh::FaceHandle, OpenMesh::VertexHandle,
                          const std::vector<OpenMesh::Vec3f>&) override {}
  void set_face_texindex(OpenMesh::FaceHandle, int) override {}
  void set_halfedge(OpenMesh::VertexHandle, OpenMesh::HalfedgeHandle) override {}
  void set_normal(OpenMesh::VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(OpenMesh::VertexHandle, const OpenMesh::Vec3d&) override {}
  void set_texcoord(OpenMesh::VertexHandle, const OpenMesh::Vec2f&) override {}
  HARAP_IGNORE_COLORS_AND_STATUS(OpenMesh::VertexHandle)
  void set_next(OpenMesh::HalfedgeHandle, OpenMesh::HalfedgeHandle) override {}
  void set_face(OpenMesh::HalfedgeHandle, OpenMesh::FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(OpenMesh::HalfedgeHandle, const OpenMesh::Vec2f&) override {}
  void set_texcoord(OpenMesh::VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_texcoord(OpenMesh::HalfedgeHandle, const OpenMesh::Vec3f&) override {}
  void set_status(OpenMesh::HalfedgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  HARAP_IGNORE_COLORS_AND_STATUS(OpenMesh::EdgeHandle)
  void set_normal(OpenMesh::FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(OpenMesh::FaceHandle, const OpenMesh::Vec3d&) override {}
  HARAP_IGNORE_COLORS_AND_STATUS(OpenMesh::FaceHandle)
  void add_texture_information(int, std::string) override {}

 private:
  RawMesh& raw_;
  std::vector<int64_t> polygon_;
  int64_t faces_ = 0;
};

#undef HARAP_IGNORE_COLORS_AND_STATUS

// Checks what OpenMesh's STL readers take on trust (see the top of this file). Returns whether
// the data is binary STL.
bool PrevalidateStl(std::string_view data, const std::string& what) {
  if (data.size() >= 84) {
    uint32_t triangles = 0;
    std::memcpy(&triangles, data.data() + 80, 4);
    if constexpr (std::endian::native == std::endian::big) triangles = __builtin_bswap32(triangles);
    if (84 + 50 * static_cast<uint64_t>(triangles) == data.size()) {
      for (uint64_t t = 0; t < triangles; ++t) {
        for (int corner = 0; corner < 3; ++corner) {
          for (int d = 0; d < 3; ++d) {
            float value = 0.0f;
            std::memcpy(&value, data.data() + 84 + 50 * t + 12 + 12 * corner + 4 * d, 4);
            if constexpr (std::endian::native == std::endian::big) {
              value = std::bit_cast<float>(__builtin_bswap32(std::bit_cast<uint32_t>(value)));
            }
            if (!std::isfinite(value)) {
              Fail(what, fmt::format("byte {}: non-finite coordinate {} in triangle {} (0-based) "
                                     "of the binary STL data",
                                     84 + 50 * t + 12 + 12 * corner + 4 * d, value, t));
            }
          }
        }
      }
      return true;
    }
  }
  std::string_view probe = data;
  while (!probe.empty() && (IsSpace(probe.front()) || probe.front() == '\n')) {
    probe.remove_prefix(1);
  }
  if (probe.substr(0, 5) != "solid") {
    uint32_t triangles = 0;
    if (data.size() >= 84) std::memcpy(&triangles, data.data() + 80, 4);
    Fail(what,
         fmt::format("neither ASCII STL (it does not start with \"solid\") nor binary STL "
                     "(a binary STL of {} bytes would declare {} triangles; its header "
                     "declares {}: truncated or not STL)",
                     data.size(), data.size() >= 84 ? (data.size() - 84) / 50 : 0, triangles));
  }
  // ASCII: OpenMesh reads the three lines after each line containing "outer" as vertices.
  LineReader lines(data);
  std::string_view line;
  while (lines.Next(line)) {
    if (line.find("outer") == std::string_view::npos &&
        line.find("OUTER") == std::string_view::npos) {
      continue;
    }
    for (int corner = 0; corner < 3; ++corner) {
      if (!lines.Next(line)) {
        Fail(what, fmt::format("truncated STL: the file ends inside the facet loop started at "
                               "line {}",
                               lines.line_number() - corner));
      }
      std::string_view rest = line;
      const std::string_view keyword = NextToken(rest);
      if (keyword != "vertex") {
        Fail(what, fmt::format("line {}: expected 'vertex x y z' inside a facet loop, found {}",
                               lines.line_number(), Quote(keyword)));
      }
      for (int d = 0; d < 3; ++d) {
        const std::string_view token = NextToken(rest);
        double value = 0.0;
        if (!ParseDouble(token, value)) {
          Fail(what, fmt::format("line {}: vertex coordinate {} is not a number",
                                 lines.line_number(), Quote(token)));
        }
        if (!std::isfinite(value) ||
            std::abs(value) > static_cast<double>(std::numeric_limits<float>::max())) {
          Fail(what, fmt::format("line {}: non-finite coordinate {} (as float)",
                                 lines.line_number(), Quote(token)));
        }
      }
    }
  }
  return false;
}

}  // namespace

Mesh ParseStl(std::string_view data, const std::string& what) {
  const bool binary = PrevalidateStl(data, what);
  RawMesh raw;
  raw.origin_kind = "triangle";
  RawImporter importer(raw);
  OpenMesh::IO::Options options;
  if (binary) options += OpenMesh::IO::Options::Binary;
  io_internal::OpenMeshLogCapture capture;
  std::istringstream stream{std::string(data)};
  if (!OpenMesh::IO::IOManager().read(stream, "stl", importer, options)) {
    const std::string errors = capture.Errors();
    Fail(what, fmt::format("OpenMesh's STL reader failed{}",
                           errors.empty() ? "" : fmt::format(": {}", errors)));
  }
  return BuildMesh(raw, what);
}

}  // namespace harap
