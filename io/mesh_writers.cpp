// SPDX-License-Identifier: MIT
#include "io/mesh_writers.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string_view>

#include "framework/error.h"
#include "io/tetrahedra.h"

namespace harap {

namespace {

enum class OutputFormat { kUnknown, kPly, kObj, kOff, kStl, kMedit, kTetGen };

std::string LowerExtension(const std::filesystem::path& file) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

OutputFormat FormatOf(const std::filesystem::path& file) {
  const std::string extension = LowerExtension(file);
  if (extension == ".ply") return OutputFormat::kPly;
  if (extension == ".obj") return OutputFormat::kObj;
  if (extension == ".off") return OutputFormat::kOff;
  if (extension == ".stl") return OutputFormat::kStl;
  if (extension == ".mesh") return OutputFormat::kMedit;
  if (extension == ".node" || extension == ".ele") return OutputFormat::kTetGen;
  return OutputFormat::kUnknown;
}

bool TetrahedraOnly(OutputFormat format) {
  return format == OutputFormat::kMedit || format == OutputFormat::kTetGen;
}

// Writes `text` to `file` (truncating), or throws naming the file.
void WriteWholeFile(const std::filesystem::path& file, const std::string& text) {
  std::ofstream stream(file, std::ios::binary | std::ios::trunc);
  if (!stream) throw Error(fmt::format("{}: cannot open the file for writing", file.string()));
  stream.write(text.data(), static_cast<std::streamsize>(text.size()));
  stream.close();
  if (!stream) throw Error(fmt::format("{}: write failed (disk full?)", file.string()));
}

// fmt's "{}" prints a double in the shortest form that reads back to the same value.
void AppendVertices(std::string& out, const Positions& vertices, std::string_view prefix,
                    std::string_view suffix) {
  for (Index v = 0; v < vertices.rows(); ++v) {
    fmt::format_to(std::back_inserter(out), "{}{} {} {}{}\n", prefix, vertices(v, 0),
                   vertices(v, 1), vertices(v, 2), suffix);
  }
}

std::string ObjText(const Positions& vertices, const Elements& triangles) {
  std::string out = "# written by harap\n";
  AppendVertices(out, vertices, "v ", "");
  for (Index f = 0; f < triangles.rows(); ++f) {
    fmt::format_to(std::back_inserter(out), "f {} {} {}\n", triangles(f, 0) + 1,
                   triangles(f, 1) + 1, triangles(f, 2) + 1);
  }
  return out;
}

std::string OffText(const Positions& vertices, const Elements& triangles) {
  std::string out = fmt::format("OFF\n{} {} 0\n", vertices.rows(), triangles.rows());
  AppendVertices(out, vertices, "", "");
  for (Index f = 0; f < triangles.rows(); ++f) {
    fmt::format_to(std::back_inserter(out), "3 {} {} {}\n", triangles(f, 0), triangles(f, 1),
                   triangles(f, 2));
  }
  return out;
}

template <class T>
void PutLittleEndian(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
  out.append(bytes, sizeof(T));
}

// Binary little-endian PLY, double coordinates, int indices (see WritePly).
// Binary PLY; `values` become per-vertex double properties after x y z.
std::string PlyBinary(const Positions& vertices, const Elements& triangles,
                      const std::vector<VertexValues>& values) {
  std::string properties;
  for (const VertexValues& column : values) {
    properties += fmt::format("property double {}\n", column.name);
  }
  std::string out = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment written by harap\n"
      "element vertex {}\nproperty double x\nproperty double y\nproperty double z\n{}"
      "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
      vertices.rows(), properties, triangles.rows());
  out.reserve(out.size() + static_cast<size_t>(vertices.rows()) * 8 * (3 + values.size()) +
              static_cast<size_t>(triangles.rows()) * 13);
  for (Index v = 0; v < vertices.rows(); ++v) {
    for (int d = 0; d < 3; ++d) PutLittleEndian(out, static_cast<double>(vertices(v, d)));
    for (const VertexValues& column : values) PutLittleEndian(out, column.values[v]);
  }
  for (Index f = 0; f < triangles.rows(); ++f) {
    PutLittleEndian(out, static_cast<uint8_t>(3));
    for (int a = 0; a < 3; ++a) PutLittleEndian(out, static_cast<int32_t>(triangles(f, a)));
  }
  return out;
}

std::string PlyBinary(const Positions& vertices, const Elements& triangles) {
  return PlyBinary(vertices, triangles, {});
}

std::string StlBinary(const Positions& vertices, const Elements& triangles) {
  std::string out(80, '\0');
  const std::string_view header = "binary STL written by harap";
  std::copy(header.begin(), header.end(), out.begin());
  PutLittleEndian(out, static_cast<uint32_t>(triangles.rows()));
  out.reserve(out.size() + static_cast<size_t>(triangles.rows()) * 50);
  for (Index f = 0; f < triangles.rows(); ++f) {
    const Eigen::Vector3d a = vertices.row(triangles(f, 0)).transpose();
    const Eigen::Vector3d b = vertices.row(triangles(f, 1)).transpose();
    const Eigen::Vector3d c = vertices.row(triangles(f, 2)).transpose();
    Eigen::Vector3d normal = (b - a).cross(c - a);
    const double length = normal.norm();
    normal = length > 0.0 ? Eigen::Vector3d(normal / length) : Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& p : {normal, a, b, c}) {
      for (int d = 0; d < 3; ++d) PutLittleEndian(out, static_cast<float>(p[d]));
    }
    PutLittleEndian(out, static_cast<uint16_t>(0));
  }
  return out;
}

std::string MeditText(const Positions& vertices, const Elements& tetrahedra) {
  std::string out =
      fmt::format("MeshVersionFormatted 2\nDimension 3\nVertices\n{}\n", vertices.rows());
  AppendVertices(out, vertices, "", " 0");
  fmt::format_to(std::back_inserter(out), "Tetrahedra\n{}\n", tetrahedra.rows());
  for (Index t = 0; t < tetrahedra.rows(); ++t) {
    fmt::format_to(std::back_inserter(out), "{} {} {} {} 0\n", tetrahedra(t, 0) + 1,
                   tetrahedra(t, 1) + 1, tetrahedra(t, 2) + 1, tetrahedra(t, 3) + 1);
  }
  out += "End\n";
  return out;
}

std::string TetGenNodeText(const Positions& vertices) {
  std::string out = fmt::format("# written by harap\n{} 3 0 0\n", vertices.rows());
  for (Index v = 0; v < vertices.rows(); ++v) {
    fmt::format_to(std::back_inserter(out), "{} {} {} {}\n", v, vertices(v, 0), vertices(v, 1),
                   vertices(v, 2));
  }
  return out;
}

std::string TetGenEleText(const Elements& tetrahedra) {
  std::string out = fmt::format("# written by harap\n{} 4 0\n", tetrahedra.rows());
  for (Index t = 0; t < tetrahedra.rows(); ++t) {
    fmt::format_to(std::back_inserter(out), "{} {} {} {} {}\n", t, tetrahedra(t, 0),
                   tetrahedra(t, 1), tetrahedra(t, 2), tetrahedra(t, 3));
  }
  return out;
}

// Checks what every writer relies on: triangles or tetrahedra, indices in range. A failure is a
// bug of the caller (InternalError), not bad input.
void CheckElements(const Positions& vertices, const Elements& elements, std::string_view writer) {
  HARAP_CHECK(elements.rows() == 0 || elements.cols() == 3 || elements.cols() == 4,
              "{} writes triangles or tetrahedra, got elements with {} vertices", writer,
              elements.cols());
  for (Index e = 0; e < elements.rows(); ++e) {
    for (Index a = 0; a < elements.cols(); ++a) {
      HARAP_CHECK(elements(e, a) >= 0 && elements(e, a) < vertices.rows(),
                  "element {} references vertex {} of {}", e, elements(e, a), vertices.rows());
    }
  }
}

// The text of a surface format (CheckMeshOutputFormat has ruled out the others).
using SurfaceWriter = std::string (*)(const Positions&, const Elements&);
SurfaceWriter SurfaceText(OutputFormat format) {
  if (format == OutputFormat::kObj) return ObjText;
  if (format == OutputFormat::kOff) return OffText;
  if (format == OutputFormat::kStl) return StlBinary;
  HARAP_CHECK(format == OutputFormat::kPly, "no surface writer for this format");
  return PlyBinary;
}

// The triangles a surface format writes: tetrahedra give their boundary.
Elements SurfaceTriangles(const Elements& elements) {
  return elements.cols() == 4 ? BoundaryTriangles(elements) : elements;
}

}  // namespace

void WritePly(const std::filesystem::path& file, const Positions& vertices,
              const Elements& elements, const std::vector<VertexValues>& values) {
  CheckElements(vertices, elements, "WritePly");
  for (const VertexValues& column : values) {
    const bool name_ok = !column.name.empty() && column.name != "x" && column.name != "y" &&
                         column.name != "z" &&
                         column.name.find_first_of(" \t\r\n") == std::string::npos;
    if (!name_ok || static_cast<Index>(column.values.size()) != vertices.rows()) {
      throw InternalError(fmt::format("WritePly: vertex values '{}' ({} of them) for {} vertices",
                                      column.name, column.values.size(), vertices.rows()));
    }
  }
  WriteWholeFile(file, PlyBinary(vertices, SurfaceTriangles(elements), values));
}

std::string MeshOutputFormats(ElementKind kind) {
  return kind == ElementKind::kTriangle
             ? ".ply (binary, double), .obj, .off, .stl"
             : ".ply (binary, double), .obj, .off, .stl (these four get the boundary triangles), "
               ".mesh (MEDIT), .node or .ele (TetGen .node/.ele pair)";
}

void CheckMeshOutputFormat(const std::filesystem::path& file, ElementKind kind) {
  const OutputFormat format = FormatOf(file);
  if (format == OutputFormat::kUnknown) {
    const std::string extension = file.extension().string();
    // The caller may not know the mesh yet: name both lists then (kind is a tetrahedral mesh's).
    throw InputError(fmt::format(
        "{}: {} is not a mesh format harap writes; the extension picks the format: {}{}",
        file.string(), extension.empty() ? std::string("no extension") : "'" + extension + "'",
        MeshOutputFormats(ElementKind::kTriangle),
        kind == ElementKind::kTetrahedron
            ? "; tetrahedral meshes also .mesh (MEDIT) and .node or .ele (TetGen pair), and the "
              "boundary triangles in the other formats"
            : ""));
  }
  if (TetrahedraOnly(format) && kind == ElementKind::kTriangle) {
    throw InputError(fmt::format("{}: '{}' holds tetrahedra, but this is a triangle mesh; use {}",
                                 file.string(), file.extension().string(),
                                 MeshOutputFormats(kind)));
  }
}

std::vector<std::filesystem::path> MeshOutputFiles(const std::filesystem::path& file) {
  if (FormatOf(file) != OutputFormat::kTetGen) return {file};
  std::filesystem::path node = file, ele = file;
  node.replace_extension(".node");
  ele.replace_extension(".ele");
  return {node, ele};
}

void WriteMesh(const std::filesystem::path& file, const Positions& vertices,
               const Elements& elements) {
  CheckElements(vertices, elements, "WriteMesh");
  CheckMeshOutputFormat(file,
                        elements.cols() == 4 ? ElementKind::kTetrahedron : ElementKind::kTriangle);
  const OutputFormat format = FormatOf(file);
  if (format == OutputFormat::kMedit) {
    WriteWholeFile(file, MeditText(vertices, elements));
  } else if (format == OutputFormat::kTetGen) {
    const auto files = MeshOutputFiles(file);
    WriteWholeFile(files[0], TetGenNodeText(vertices));
    WriteWholeFile(files[1], TetGenEleText(elements));
  } else {
    WriteWholeFile(file, SurfaceText(format)(vertices, SurfaceTriangles(elements)));
  }
}

}  // namespace harap
