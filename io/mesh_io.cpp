// SPDX-License-Identifier: MIT
//
// ReadMesh: the format by the file name's extension (looking through a trailing ".xz"), then the
// reader of that format. Why each format has its own parser rather than OpenMesh's is written at
// the top of each reader (obj_reader.cpp, ...); every reader keeps the file's vertex order and
// unreferenced vertices and fan-triangulates polygons; nothing is dropped silently.
#include "io/mesh_io.h"

#include <fmt/format.h>

#include "io/file_reading.h"
#include "io/medit_reader.h"
#include "io/obj_reader.h"
#include "io/off_reader.h"
#include "io/ply_reader.h"
#include "io/stl_reader.h"
#include "io/tetgen_reader.h"
#include "io/text_scanning.h"

namespace harap {

namespace {

using namespace io_internal;

constexpr std::string_view kSupportedFormats =
    ".obj, .ply, .off, .stl (surfaces), .node/.ele (TetGen), .mesh (MEDIT) (each optionally "
    "compressed as .xz, e.g. .obj.xz)";

bool IsTetrahedralFormat(const FileFormat& format) {
  return format.extension == "node" || format.extension == "ele" || format.extension == "mesh";
}

// The parser of a surface format, or nullptr.
using SurfaceParser = Mesh (*)(std::string_view, const std::string&);
SurfaceParser SurfaceParserFor(const FileFormat& format) {
  const std::string& extension = format.extension;
  if (extension == "obj") return ParseObj;
  if (extension == "ply") return ParsePly;
  if (extension == "off") return ParseOff;
  if (extension == "stl") return ParseStl;
  return nullptr;
}

// The surface parser for `format`, or an error listing the supported formats.
SurfaceParser CheckedSurfaceParser(const FileFormat& format, const std::string& what) {
  const SurfaceParser parser = SurfaceParserFor(format);
  if (!parser) {
    Fail(what,
         fmt::format("unknown mesh file extension '{}{}'; supported: {}",
                     format.extension.empty() ? "" : ".", format.extension, kSupportedFormats));
  }
  return parser;
}

}  // namespace

Mesh ReadMesh(const std::filesystem::path& file, std::vector<std::string>* notes) {
  const std::string what = file.string();
  const FileFormat format = DetectFormat(file);
  if (format.extension == "node" || format.extension == "ele") return ReadTetGenMesh(file, notes);
  if (format.extension == "mesh") return ReadMeditMesh(file, notes);
  const SurfaceParser parse = CheckedSurfaceParser(format, what);  // a wrong name costs no read
  return parse(ReadFileMaybeXz(file), what);
}

Mesh ParseMesh(std::string_view data, const std::filesystem::path& name) {
  const std::string what = name.string();
  const FileFormat format = DetectFormat(name);
  if (IsTetrahedralFormat(format)) {
    Fail(what, "tetrahedral formats (.node/.ele, .mesh) are read from files only (ReadMesh)");
  }
  const SurfaceParser parse = CheckedSurfaceParser(format, what);
  if (format.xz) return parse(DecompressXz(data, what), what);
  return parse(data, what);
}

Positions ReadMeshVertices(const std::filesystem::path& file) {
  const std::string& extension = DetectFormat(file).extension;
  if (extension == "node") return ReadTetGenNodes(file);
  if (extension == "mesh") return ReadMeditVertices(file);
  return ReadMesh(file).vertices;
}

}  // namespace harap
