// SPDX-License-Identifier: MIT
//
// Mesh reading and writing.
//
// Which parser reads what, and why (measured against OpenMesh 9.0, Debian 12):
//   - OBJ, PLY and OFF are parsed here, not by OpenMesh. OpenMesh's readers hand every coordinate
//     to the importer as a float (Vec3f) even when the file stores doubles, so a double-precision
//     PLY written by WritePly would not read back bit-identically, and text coordinates such as
//     "0.354446" would be rounded to float. They also produce silent garbage on bad input:
//       * OBJ: a vertex line that fails to parse ("v nan 0 0", "v 1e39 0 0") is dropped, which
//         shifts every later vertex index; faces with a repeated index ("f 1 1 3") are dropped;
//         index 0 becomes vertex -1.
//       * OFF: a non-numeric coordinate leaves later reads failing and faces are filled with
//         uninitialized indices; a header that declares 2e9 faces on a short file, or random
//         bytes, keep the reader looping for minutes.
//       * PLY: a truncated binary file is reported as success with the vertices read so far.
//   - STL goes through OpenMesh's reader (its coordinates are float32 in the format anyway, and
//     OpenMesh welds the per-triangle corners into shared vertices). It is pre-validated here:
//     OpenMesh's binary reader trusts the triangle count in the header (a truncated file makes it
//     read zeros for up to 2^32 triangles) and its ASCII reader turns an unparsable coordinate
//     into 0 silently.
// Every reader keeps the file's vertex order and unreferenced vertices and fan-triangulates
// polygons; nothing is dropped silently.
#include "framework/io/mesh_io.h"

#include <lzma.h>

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/Options.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/IO/reader/STLReader.hh>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "framework/error.h"
#include "framework/io/openmesh_log.h"
#include "framework/io/tet_mesh_io.h"
#include "framework/io/text_scanning.h"

namespace harap {

namespace {

using namespace io_internal;

constexpr std::string_view kSupportedFormats =
    ".obj, .ply, .off, .stl (surfaces), .node/.ele (TetGen), .mesh (MEDIT) (each optionally "
    "compressed as .xz, e.g. .obj.xz)";

// The format extension ("obj", "ply", ...) of a file name, looking through a trailing ".xz".
struct FileFormat {
  std::string extension;  // lower case, without dot; "" if none
  bool xz = false;
};

FileFormat DetectFormat(const std::filesystem::path& file) {
  FileFormat format;
  std::filesystem::path name = file.filename();
  if (Lower(name.extension().string()) == ".xz") {
    format.xz = true;
    name = name.stem();
  }
  std::string extension = Lower(name.extension().string());
  if (!extension.empty()) extension.erase(0, 1);
  format.extension = extension;
  return format;
}

// ---------------------------------------------------------------------------------------------
// Whole-file reading and xz decompression.

std::string ReadWholeFile(const std::filesystem::path& file) {
  const std::string what = file.string();
  std::error_code error;
  const auto status = std::filesystem::status(file, error);
  if (!std::filesystem::exists(status)) Fail(what, "file not found");
  if (std::filesystem::is_directory(status)) Fail(what, "is a directory, not a file");
  // Devices such as /dev/zero or /dev/urandom never end; pipes (e.g. <(xz -dc ...)) do.
  if (!std::filesystem::is_regular_file(status) && !std::filesystem::is_fifo(status)) {
    Fail(what, "is not a regular file (a device or socket) and cannot be read as one");
  }
  std::ifstream stream(file, std::ios::binary);
  if (!stream) Fail(what, "cannot open the file for reading");
  std::string data;
  const auto size = std::filesystem::file_size(file, error);
  if (!error) data.reserve(static_cast<size_t>(size));
  data.assign(std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>());
  if (stream.bad()) Fail(what, "read error");
  return data;
}

std::string DecompressXz(std::string_view compressed, const std::string& what) {
  if (compressed.empty()) Fail(what, "not xz-compressed data: the file is empty");
  lzma_stream stream = LZMA_STREAM_INIT;
  // The decoder's memory is set by the dictionary size the file's headers declare (64 MiB for
  // `xz -9`, up to 1.5 GiB for custom settings), so a 100-byte file could make it allocate that
  // much. No mesh file needs more than this limit; a larger request is a corrupt header.
  constexpr uint64_t kDecoderMemoryLimit = uint64_t{512} << 20;
  // LZMA_CONCATENATED: `xz` itself accepts several concatenated streams in one file.
  lzma_ret ret = lzma_stream_decoder(&stream, kDecoderMemoryLimit, LZMA_CONCATENATED);
  if (ret != LZMA_OK) Fail(what, fmt::format("cannot start the xz decoder (liblzma error {})",
                                             static_cast<int>(ret)));
  struct Guard {
    lzma_stream* stream;
    ~Guard() { lzma_end(stream); }
  } guard{&stream};

  std::string out;
  out.resize(std::max<size_t>(size_t{1} << 16, compressed.size() * 6));
  stream.next_in = reinterpret_cast<const uint8_t*>(compressed.data());
  stream.avail_in = compressed.size();
  stream.next_out = reinterpret_cast<uint8_t*>(out.data());
  stream.avail_out = out.size();
  while (true) {
    ret = lzma_code(&stream, LZMA_FINISH);
    if (ret == LZMA_STREAM_END) break;
    if (ret == LZMA_OK) {
      if (stream.avail_out == 0) {
        const size_t used = out.size();
        out.resize(used * 2);
        stream.next_out = reinterpret_cast<uint8_t*>(out.data()) + used;
        stream.avail_out = out.size() - used;
      }
      continue;
    }
    switch (ret) {
      case LZMA_FORMAT_ERROR:
        Fail(what, "not xz-compressed data (the name ends in .xz but the xz magic bytes are "
                   "missing)");
      case LZMA_DATA_ERROR:
        Fail(what, fmt::format("corrupt xz data (decoding failed after {} compressed bytes)",
                               stream.total_in));
      case LZMA_BUF_ERROR:
        Fail(what, fmt::format("truncated xz data (the compressed stream ends after {} bytes "
                               "without its end marker)",
                               stream.total_in));
      case LZMA_MEM_ERROR:
        Fail(what, "out of memory while decompressing xz data");
      case LZMA_MEMLIMIT_ERROR:
        Fail(what, fmt::format("the xz headers ask for {} MiB of decoder memory (dictionary "
                               "size), more than the {} MiB any mesh file needs: corrupt xz data",
                               lzma_memusage(&stream) >> 20, kDecoderMemoryLimit >> 20));
      case LZMA_OPTIONS_ERROR:
        Fail(what, "unsupported xz compression options");
      default:
        Fail(what, fmt::format("xz decompression failed (liblzma error {})",
                               static_cast<int>(ret)));
    }
  }
  out.resize(stream.total_out);
  return out;
}

// ---------------------------------------------------------------------------------------------
// What the parsers produce before validation.

struct RawMesh {
  std::vector<double> xyz;       // 3 per vertex
  std::vector<int64_t> corners;  // 3 per triangle, 0-based, not yet range checked
  // Per triangle: where it came from, for error messages ("line 12", "face 7").
  std::vector<int64_t> origin;
  const char* origin_kind = "line";
  // Optionally, per triangle, where its face starts in the file (PLY: the line, or the byte
  // offset in binary files), when `origin` is a face number.
  std::vector<int64_t> location;
  const char* location_kind = "";

  std::string Origin(size_t triangle) const {
    if (location.size() <= triangle) return fmt::format("{} {}", origin_kind, origin[triangle]);
    return fmt::format("{} {}: {} {}", location_kind, location[triangle], origin_kind,
                       origin[triangle]);
  }

  void AddPolygon(const std::vector<int64_t>& polygon, int64_t where) {
    // Fan triangulation (v0, vi, vi+1): exact for the triangles and convex polygons real files
    // contain; the format gives no geometry to do better with.
    for (size_t i = 1; i + 1 < polygon.size(); ++i) {
      corners.push_back(polygon[0]);
      corners.push_back(polygon[i]);
      corners.push_back(polygon[i + 1]);
      origin.push_back(where);
    }
  }
};

// Turns the raw lists into a Mesh, checking what ValidateMesh checks but with the file position
// of the offending face in the message.
Mesh BuildMesh(const RawMesh& raw, const std::string& what) {
  const int64_t num_vertices = static_cast<int64_t>(raw.xyz.size() / 3);
  const int64_t num_triangles = static_cast<int64_t>(raw.corners.size() / 3);
  if (num_vertices > std::numeric_limits<Index>::max() ||
      num_triangles > std::numeric_limits<Index>::max()) {
    Fail(what, fmt::format("too large: {} vertices and {} triangles (at most {} each)",
                           num_vertices, num_triangles, std::numeric_limits<Index>::max()));
  }
  if (num_vertices == 0) {
    Fail(what, num_triangles == 0 ? "the file contains no vertices and no faces"
                                  : "the file contains no vertices");
  }
  if (num_triangles == 0) {
    Fail(what, fmt::format("no faces: the file contains {} vertices but no faces", num_vertices));
  }
  Mesh mesh;
  mesh.vertices.resize(num_vertices, 3);
  for (int64_t v = 0; v < num_vertices; ++v) {
    for (int d = 0; d < 3; ++d) {
      const double value = raw.xyz[3 * v + d];
      if (!std::isfinite(value)) {
        Fail(what, fmt::format("non-finite coordinate: vertex {} (0-based) is ({}, {}, {})", v,
                               raw.xyz[3 * v], raw.xyz[3 * v + 1], raw.xyz[3 * v + 2]));
      }
      mesh.vertices(v, d) = value;
    }
  }
  mesh.elements.resize(num_triangles, 3);
  for (int64_t t = 0; t < num_triangles; ++t) {
    for (int a = 0; a < 3; ++a) {
      const int64_t v = raw.corners[3 * t + a];
      if (v < 0 || v >= num_vertices) {
        Fail(what, fmt::format("{}: vertex index out of range: {} (0-based), but the file has "
                               "{} vertices",
                               raw.Origin(t), v, num_vertices));
      }
      for (int b = 0; b < a; ++b) {
        if (raw.corners[3 * t + b] == v) {
          Fail(what, fmt::format("{}: degenerate face: it uses vertex {} (0-based) twice",
                                 raw.Origin(t), v));
        }
      }
      mesh.elements(t, a) = static_cast<Index>(v);
    }
  }
  ValidateMesh(mesh, what);
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// OBJ: `v x y z` and `f a b c ...` (a = i, i/t, i//n or i/t/n; 1-based, negative = relative).

RawMesh ParseObj(std::string_view data, const std::string& what) {
  RawMesh raw;
  raw.xyz.reserve(data.size() / 16);
  raw.corners.reserve(data.size() / 8);
  LineReader lines(data);
  std::string_view line;
  std::vector<int64_t> polygon;
  while (lines.Next(line)) {
    line = StripComment(line);
    const std::string_view keyword = NextToken(line);
    if (keyword == "v") {
      for (int d = 0; d < 3; ++d) {
        const std::string_view token = NextToken(line);
        double value = 0.0;
        if (token.empty()) {
          Fail(what, fmt::format("line {}: vertex has fewer than three coordinates",
                                 lines.line_number()));
        }
        if (!ParseDouble(token, value)) {
          Fail(what, fmt::format("line {}: vertex coordinate {} is not a number",
                                 lines.line_number(), Quote(token)));
        }
        if (!std::isfinite(value)) {
          Fail(what, fmt::format("line {}: non-finite coordinate {} (vertex {}, 1-based)",
                                 lines.line_number(), Quote(token), raw.xyz.size() / 3 + 1));
        }
        raw.xyz.push_back(value);
      }
      // Further values (w, or r g b colours) are ignored.
    } else if (keyword == "f") {
      polygon.clear();
      const int64_t vertices_so_far = static_cast<int64_t>(raw.xyz.size() / 3);
      for (std::string_view token = NextToken(line); !token.empty(); token = NextToken(line)) {
        const std::string_view index_text = token.substr(0, token.find('/'));
        int64_t index = 0;
        if (!ParseInteger(index_text, index)) {
          Fail(what, fmt::format("line {}: face vertex {} is not an index", lines.line_number(),
                                 Quote(token)));
        }
        if (index == 0) {
          Fail(what, fmt::format("line {}: vertex index out of range: 0 (OBJ indices start at 1; "
                                 "negative ones count back from the last vertex)",
                                 lines.line_number()));
        }
        if (index < 0) {
          if (-index > vertices_so_far) {
            Fail(what, fmt::format("line {}: vertex index out of range: relative index {} "
                                   "points before the first vertex ({} vertices read so far)",
                                   lines.line_number(), index, vertices_so_far));
          }
          polygon.push_back(vertices_so_far + index);
        } else {
          // Forward references are legal OBJ; the range is checked once all vertices are read.
          polygon.push_back(index - 1);
        }
      }
      if (polygon.size() < 3) {
        Fail(what, fmt::format("line {}: face has {} vertices (at least 3 are needed)",
                               lines.line_number(), polygon.size()));
      }
      raw.AddPolygon(polygon, static_cast<int64_t>(lines.line_number()));
    }
    // Everything else (vt, vn, g, o, s, usemtl, mtllib, l, p, ...) carries nothing we use.
  }
  return raw;
}

// ---------------------------------------------------------------------------------------------
// OFF (ASCII): header `OFF` (or COFF, NOFF, STOFF, ...), counts `nv nf ne`, then one vertex per
// line (x y z, further values ignored) and one face per line (n i1 ... in, 0-based).

RawMesh ParseOff(std::string_view data, const std::string& what) {
  RawMesh raw;
  LineReader lines(data);
  std::string_view line;
  if (!lines.NextContent(line)) Fail(what, "empty file (no OFF header)");
  const std::string header(NextToken(line));
  if (!EndsWith(header, "OFF")) {
    Fail(what, fmt::format("not an OFF file: the first line starts with {} instead of OFF",
                           Quote(header)));
  }
  const std::string prefix = header.substr(0, header.size() - 3);
  // Optional per-vertex data: ST (texture), C (colour), N (normal); all come after x y z on the
  // line, so line-based parsing ignores them. 4OFF (homogeneous) and nOFF (n-dimensional) change
  // the meaning of the coordinates and are refused.
  {
    std::string rest = prefix;
    for (const char* part : {"ST", "C", "N"}) {
      if (rest.rfind(part, 0) == 0) rest.erase(0, std::strlen(part));
    }
    if (!rest.empty()) {
      Fail(what, fmt::format("unsupported OFF variant {} (supported: OFF with optional ST, C, N "
                             "prefixes)",
                             Quote(header)));
    }
  }
  std::string_view counts_line = line;
  {
    std::string_view probe = counts_line;
    const std::string_view first = NextToken(probe);
    if (first == "BINARY") {
      Fail(what, "binary OFF is not supported (convert it to PLY or ASCII OFF)");
    }
    if (first.empty() && !lines.NextContent(counts_line)) {
      Fail(what, "the file ends after the OFF header (no vertex/face counts)");
    }
  }
  int64_t counts[2] = {0, 0};
  for (int64_t& count : counts) {
    const std::string_view token = NextToken(counts_line);
    if (!ParseInteger(token, count) || count < 0) {
      Fail(what, fmt::format("line {}: expected the vertex and face counts, found {}",
                             lines.line_number(), Quote(token)));
    }
  }
  const int64_t num_vertices = counts[0];
  const int64_t num_faces = counts[1];
  // Each vertex line has at least 6 bytes ("0 0 0\n"): a larger count cannot be right, and
  // checking it here keeps a corrupt header from triggering a huge allocation.
  if (num_vertices > static_cast<int64_t>(data.size() / 6) + 1) {
    Fail(what, fmt::format("truncated file: the header declares {} vertices, more than a file of "
                           "{} bytes can hold",
                           num_vertices, data.size()));
  }
  raw.xyz.reserve(static_cast<size_t>(num_vertices) * 3);
  for (int64_t v = 0; v < num_vertices; ++v) {
    if (!lines.NextContent(line)) {
      Fail(what, fmt::format("truncated file: it ends after {} of the {} vertices the header "
                             "declares",
                             v, num_vertices));
    }
    for (int d = 0; d < 3; ++d) {
      const std::string_view token = NextToken(line);
      double value = 0.0;
      if (!ParseDouble(token, value)) {
        Fail(what, fmt::format("line {}: vertex coordinate {} is not a number",
                               lines.line_number(), token.empty() ? "(missing)" : Quote(token)));
      }
      if (!std::isfinite(value)) {
        Fail(what, fmt::format("line {}: non-finite coordinate {} (vertex {}, 0-based)",
                               lines.line_number(), Quote(token), v));
      }
      raw.xyz.push_back(value);
    }
  }
  std::vector<int64_t> polygon;
  for (int64_t f = 0; f < num_faces; ++f) {
    if (!lines.NextContent(line)) {
      Fail(what, fmt::format("truncated file: it ends after {} of the {} faces the header "
                             "declares",
                             f, num_faces));
    }
    const std::string_view count_token = NextToken(line);
    int64_t count = 0;
    if (!ParseInteger(count_token, count) || count < 0) {
      Fail(what, fmt::format("line {}: face vertex count {} is not a non-negative integer",
                             lines.line_number(), Quote(count_token)));
    }
    if (count < 3) {
      Fail(what, fmt::format("line {}: face has {} vertices (at least 3 are needed)",
                             lines.line_number(), count));
    }
    polygon.clear();
    for (int64_t i = 0; i < count; ++i) {
      const std::string_view token = NextToken(line);
      int64_t index = 0;
      if (!ParseInteger(token, index)) {
        Fail(what, fmt::format("line {}: face has {} of its {} vertex indices ({} found)",
                               lines.line_number(), i, count,
                               token.empty() ? "end of line" : Quote(token)));
      }
      polygon.push_back(index);
    }
    raw.AddPolygon(polygon, static_cast<int64_t>(lines.line_number()));
  }
  return raw;
}

// ---------------------------------------------------------------------------------------------
// PLY: ASCII and binary (both byte orders); `vertex` with x y z of any scalar type, `face` with a
// `vertex_indices` (or `vertex_index`) list; other elements and properties are skipped.

enum class PlyType { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };

bool ParsePlyType(std::string_view name, PlyType& type) {
  static const std::pair<std::string_view, PlyType> kTypes[] = {
      {"char", PlyType::kInt8},     {"int8", PlyType::kInt8},      {"uchar", PlyType::kUInt8},
      {"uint8", PlyType::kUInt8},   {"short", PlyType::kInt16},    {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUInt16}, {"uint16", PlyType::kUInt16},  {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},   {"uint", PlyType::kUInt32},    {"uint32", PlyType::kUInt32},
      {"float", PlyType::kFloat32}, {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [text, value] : kTypes) {
    if (text == name) {
      type = value;
      return true;
    }
  }
  return false;
}

size_t PlyTypeSize(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUInt8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUInt16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUInt32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

bool IsIntegerType(PlyType type) { return type != PlyType::kFloat32 && type != PlyType::kFloat64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool is_list = false;
  PlyType count_type = PlyType::kUInt8;
};

struct PlyElement {
  std::string name;
  int64_t count = 0;
  std::vector<PlyProperty> properties;
};

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  size_t data_offset = 0;  // first byte after end_header's line
  size_t data_lines = 0;   // lines up to and including end_header
};

PlyHeader ParsePlyHeader(std::string_view data, const std::string& what) {
  PlyHeader header;
  LineReader lines(data);
  std::string_view line;
  if (!lines.Next(line) || NextToken(line) != "ply") {
    Fail(what, "not a PLY file (it does not start with the line \"ply\")");
  }
  bool have_format = false;
  while (true) {
    if (!lines.Next(line)) Fail(what, "PLY header has no end_header line");
    std::string_view rest = line;
    const std::string_view keyword = NextToken(rest);
    const size_t number = lines.line_number();
    if (keyword == "end_header") break;
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      const std::string_view kind = NextToken(rest);
      if (kind == "ascii") {
        header.format = PlyFormat::kAscii;
      } else if (kind == "binary_little_endian") {
        header.format = PlyFormat::kBinaryLittleEndian;
      } else if (kind == "binary_big_endian") {
        header.format = PlyFormat::kBinaryBigEndian;
      } else {
        Fail(what, fmt::format("PLY header line {}: unknown format {}", number, Quote(kind)));
      }
      have_format = true;
    } else if (keyword == "element") {
      PlyElement element;
      element.name = std::string(NextToken(rest));
      const std::string_view count = NextToken(rest);
      if (element.name.empty() || !ParseInteger(count, element.count) || element.count < 0) {
        Fail(what, fmt::format("PLY header line {}: malformed element line", number));
      }
      header.elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (header.elements.empty()) {
        Fail(what, fmt::format("PLY header line {}: property before any element", number));
      }
      PlyProperty property;
      std::string_view type = NextToken(rest);
      if (type == "list") {
        property.is_list = true;
        const std::string_view count_type = NextToken(rest);
        if (!ParsePlyType(count_type, property.count_type) ||
            !IsIntegerType(property.count_type)) {
          Fail(what, fmt::format("PLY header line {}: bad list count type {}", number,
                                 Quote(count_type)));
        }
        type = NextToken(rest);
      }
      if (!ParsePlyType(type, property.type)) {
        Fail(what, fmt::format("PLY header line {}: unknown property type {}", number,
                               Quote(type)));
      }
      property.name = std::string(NextToken(rest));
      if (property.name.empty()) {
        Fail(what, fmt::format("PLY header line {}: property without a name", number));
      }
      header.elements.back().properties.push_back(std::move(property));
    } else {
      Fail(what, fmt::format("PLY header line {}: unknown keyword {}", number, Quote(keyword)));
    }
  }
  if (!have_format) Fail(what, "PLY header has no format line");
  header.data_offset = lines.position();
  header.data_lines = lines.line_number();
  return header;
}

// Reads the values of a PLY body one by one, ASCII or binary, with bounds checks, and says where
// it is for error messages ("line 12" in ASCII, "byte 345" in binary; both count from the start
// of the file).
class PlyBodyReader {
 public:
  PlyBodyReader(std::string_view data, const PlyHeader& header, const std::string& what)
      : data_(data),
        position_(header.data_offset),
        line_(header.data_lines + 1),
        binary_(header.format != PlyFormat::kAscii),
        swap_(binary_ && (header.format == PlyFormat::kBinaryBigEndian) !=
                             (std::endian::native == std::endian::big)),
        what_(what) {}

  bool binary() const { return binary_; }

  // Where the next value starts.
  std::string Where() {
    if (binary_) return fmt::format("byte {}", position_);
    SkipSpace();
    return fmt::format("line {}", line_);
  }
  int64_t Location() {
    if (binary_) return static_cast<int64_t>(position_);
    SkipSpace();
    return static_cast<int64_t>(line_);
  }
  const char* location_kind() const { return binary_ ? "byte" : "line"; }

  // Each returns false at the end of the data and fails on a malformed ASCII token.
  bool ReadInteger(PlyType type, int64_t& value) {
    if (binary_) return ReadBinary(type, value);
    const std::string_view token = NextToken();
    if (token.empty()) return false;
    if (!ParseInteger(token, value)) {
      Fail(what_, fmt::format("line {}: {} is not an integer", line_, Quote(token)));
    }
    return true;
  }
  bool ReadDouble(PlyType type, double& value) {
    if (binary_) {
      int64_t integer = 0;
      if (type == PlyType::kFloat32 || type == PlyType::kFloat64) return ReadBinaryFloat(type, value);
      if (!ReadBinary(type, integer)) return false;
      value = static_cast<double>(integer);
      return true;
    }
    const std::string_view token = NextToken();
    if (token.empty()) return false;
    if (!ParseDouble(token, value)) {
      Fail(what_, fmt::format("line {}: vertex coordinate {} is not a number", line_,
                              Quote(token)));
    }
    return true;
  }
  bool Skip(PlyType type, uint64_t count = 1) {
    if (!binary_) {
      for (uint64_t i = 0; i < count; ++i) {
        if (NextToken().empty()) return false;
      }
      return true;
    }
    const uint64_t bytes = count * PlyTypeSize(type);  // count < 2^32, size ≤ 8: no overflow
    if (data_.size() - position_ < bytes) return false;
    position_ += static_cast<size_t>(bytes);
    return true;
  }

 private:
  void SkipSpace() {
    while (position_ < data_.size()) {
      const char c = data_[position_];
      if (c == '\n' || (c == '\r' && (position_ + 1 == data_.size() ||
                                      data_[position_ + 1] != '\n'))) {
        ++line_;  // "\n", "\r\n" (counted at its "\n") or a lone "\r"
      } else if (!IsSpace(c)) {
        break;
      }
      ++position_;
    }
  }
  std::string_view NextToken() {
    SkipSpace();
    const size_t start = position_;
    while (position_ < data_.size() && !IsSpace(data_[position_]) && data_[position_] != '\n') {
      ++position_;
    }
    return data_.substr(start, position_ - start);
  }
  bool Load(PlyType type, unsigned char* bytes) {
    const size_t size = PlyTypeSize(type);
    if (data_.size() - position_ < size) return false;
    std::memcpy(bytes, data_.data() + position_, size);
    position_ += size;
    if (swap_) std::reverse(bytes, bytes + size);
    return true;
  }
  template <class T>
  static T As(const unsigned char* bytes) {
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return value;
  }
  bool ReadBinary(PlyType type, int64_t& value) {
    unsigned char bytes[8];
    if (!Load(type, bytes)) return false;
    switch (type) {
      case PlyType::kInt8: value = static_cast<int8_t>(bytes[0]); break;
      case PlyType::kUInt8: value = bytes[0]; break;
      case PlyType::kInt16: value = As<int16_t>(bytes); break;
      case PlyType::kUInt16: value = As<uint16_t>(bytes); break;
      case PlyType::kInt32: value = As<int32_t>(bytes); break;
      case PlyType::kUInt32: value = As<uint32_t>(bytes); break;
      case PlyType::kFloat32:
      case PlyType::kFloat64:
        HARAP_CHECK(false, "integer read of a floating-point PLY property");
    }
    return true;
  }
  bool ReadBinaryFloat(PlyType type, double& value) {
    unsigned char bytes[8];
    if (!Load(type, bytes)) return false;
    value = type == PlyType::kFloat32 ? As<float>(bytes) : As<double>(bytes);
    return true;
  }

  std::string_view data_;
  size_t position_;
  size_t line_;
  bool binary_;
  bool swap_;
  const std::string& what_;
};

RawMesh ParsePly(std::string_view data, const std::string& what) {
  const PlyHeader header = ParsePlyHeader(data, what);
  const std::string_view body = data.substr(header.data_offset);
  const bool binary = header.format != PlyFormat::kAscii;

  // Locate the vertex coordinates and the face index list.
  const PlyElement* vertex_element = nullptr;
  const PlyElement* face_element = nullptr;
  int coordinate_slot[3] = {-1, -1, -1};
  int index_slot = -1;
  for (const PlyElement& element : header.elements) {
    // A second 'vertex' or 'face' element would leave the slots below pointing into the first
    // one's property list (found by fuzzing: a heap overflow); no writer produces one.
    if ((element.name == "vertex" && vertex_element) || (element.name == "face" && face_element)) {
      Fail(what, fmt::format("PLY header declares the element '{}' twice", element.name));
    }
    if (element.name == "vertex") {
      vertex_element = &element;
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        for (int d = 0; d < 3; ++d) {
          if (property.name == std::string(1, static_cast<char>('x' + d)) && !property.is_list) {
            coordinate_slot[d] = static_cast<int>(p);
          }
        }
      }
    } else if (element.name == "face") {
      face_element = &element;
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (property.is_list &&
            (property.name == "vertex_indices" || property.name == "vertex_index")) {
          index_slot = static_cast<int>(p);
        }
      }
    }
  }
  if (!vertex_element) Fail(what, "PLY header declares no 'vertex' element");
  for (int d = 0; d < 3; ++d) {
    if (coordinate_slot[d] < 0) {
      Fail(what, fmt::format("PLY 'vertex' element has no scalar property '{}'",
                             static_cast<char>('x' + d)));
    }
  }
  if (!face_element || face_element->count == 0) {
    Fail(what, fmt::format("no faces: the PLY file declares {} vertices but no faces",
                           vertex_element->count));
  }
  if (index_slot < 0) {
    Fail(what, "PLY 'face' element has no list property 'vertex_indices' (or 'vertex_index')");
  }
  if (!IsIntegerType(face_element->properties[index_slot].type)) {
    Fail(what, "PLY face property 'vertex_indices' has a floating-point type");
  }

  // A lower bound on the bytes each item needs, so that a corrupt count fails before it makes us
  // reserve gigabytes. (ASCII: one character per value and a separator between values.)
  for (const PlyElement& element : header.elements) {
    size_t min_bytes = 0;
    for (const PlyProperty& property : element.properties) {
      min_bytes += binary ? PlyTypeSize(property.is_list ? property.count_type : property.type)
                          : 2;
    }
    const size_t available = binary ? body.size() : body.size() + 1;
    if (min_bytes > 0 && static_cast<uint64_t>(element.count) > available / min_bytes) {
      Fail(what, fmt::format("truncated PLY data: the header declares {} '{}' items, more than "
                             "the {} bytes after the header can hold",
                             element.count, element.name, body.size()));
    }
  }

  RawMesh raw;
  raw.origin_kind = "face";
  raw.xyz.reserve(static_cast<size_t>(vertex_element->count) * 3);
  raw.corners.reserve(static_cast<size_t>(face_element->count) * 3);
  raw.origin.reserve(static_cast<size_t>(face_element->count));
  std::vector<int64_t> polygon;
  PlyBodyReader reader(data, header, what);
  raw.location_kind = reader.location_kind();
  auto truncated = [&](const PlyElement& element, int64_t item) {
    Fail(what, fmt::format("truncated PLY data: the file ends inside element '{}' (item {} of "
                           "{}, at {})",
                           element.name, item, element.count, reader.Where()));
  };
  bool vertices_done = false;
  for (const PlyElement& element : header.elements) {
    const bool is_vertex = &element == vertex_element;
    const bool is_face = &element == face_element;
    if (element.properties.empty()) continue;  // nothing stored per item
    for (int64_t item = 0; item < element.count; ++item) {
      const int64_t item_location = reader.Location();
      double xyz[3] = {0.0, 0.0, 0.0};
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (!property.is_list) {
          int slot = -1;
          for (int d = 0; d < 3; ++d) slot = coordinate_slot[d] == static_cast<int>(p) ? d : slot;
          const bool ok = is_vertex && slot >= 0 ? reader.ReadDouble(property.type, xyz[slot])
                                                 : reader.Skip(property.type);
          if (!ok) truncated(element, item);
          continue;
        }
        const std::string count_where = reader.Where();
        int64_t count = 0;
        if (!reader.ReadInteger(property.count_type, count)) truncated(element, item);
        if (count < 0) {
          Fail(what, fmt::format("{}: PLY element '{}' item {}: negative list length {}",
                                 count_where, element.name, item, count));
        }
        if (!is_face || static_cast<int>(p) != index_slot) {
          if (!reader.Skip(property.type, static_cast<uint64_t>(count))) truncated(element, item);
          continue;
        }
        if (count < 3) {
          Fail(what, fmt::format("{}: face {}: face has {} vertices (at least 3 are needed)",
                                 count_where, item, count));
        }
        polygon.clear();
        for (int64_t i = 0; i < count; ++i) {
          int64_t index = 0;
          if (!reader.ReadInteger(property.type, index)) truncated(element, item);
          polygon.push_back(index);
        }
        raw.AddPolygon(polygon, item);
        raw.location.resize(raw.origin.size(), item_location);
      }
      if (is_vertex) {
        if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2])) {
          Fail(what, fmt::format("{} {}: non-finite coordinate: vertex {} (0-based) is ({}, {}, "
                                 "{})",
                                 raw.location_kind, item_location, item, xyz[0], xyz[1],
                                 xyz[2]));
        }
        raw.xyz.insert(raw.xyz.end(), xyz, xyz + 3);
      }
    }
    vertices_done = vertices_done || is_vertex;
    if (is_face && vertices_done) break;  // later elements hold nothing we use
  }
  return raw;
}

// ---------------------------------------------------------------------------------------------
// STL through OpenMesh, collecting raw positions and triangles.

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
  void set_color(OpenMesh::VertexHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(OpenMesh::VertexHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(OpenMesh::VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_color(OpenMesh::VertexHandle, const OpenMesh::Vec4f&) override {}
  void set_texcoord(OpenMesh::VertexHandle, const OpenMesh::Vec2f&) override {}
  void set_status(OpenMesh::VertexHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_next(OpenMesh::HalfedgeHandle, OpenMesh::HalfedgeHandle) override {}
  void set_face(OpenMesh::HalfedgeHandle, OpenMesh::FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(OpenMesh::HalfedgeHandle, const OpenMesh::Vec2f&) override {}
  void set_texcoord(OpenMesh::VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_texcoord(OpenMesh::HalfedgeHandle, const OpenMesh::Vec3f&) override {}
  void set_status(OpenMesh::HalfedgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec3f&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec4f&) override {}
  void set_status(OpenMesh::EdgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_normal(OpenMesh::FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(OpenMesh::FaceHandle, const OpenMesh::Vec3d&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec4f&) override {}
  void set_status(OpenMesh::FaceHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}

 private:
  RawMesh& raw_;
  std::vector<int64_t> polygon_;
  int64_t faces_ = 0;
};

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
    Fail(what, fmt::format("neither ASCII STL (it does not start with \"solid\") nor binary STL "
                           "(a binary STL of {} bytes would declare {} triangles; its header "
                           "declares {}: truncated or not STL)",
                           data.size(), data.size() >= 84 ? (data.size() - 84) / 50 : 0,
                           triangles));
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

RawMesh ParseStl(const std::string& data, const std::string& what) {
  const bool binary = PrevalidateStl(data, what);
  RawMesh raw;
  raw.origin_kind = "triangle";
  RawImporter importer(raw);
  OpenMesh::IO::Options options;
  if (binary) options += OpenMesh::IO::Options::Binary;
  io_internal::OpenMeshLogCapture capture;
  std::istringstream stream(data);
  if (!OpenMesh::IO::IOManager().read(stream, "stl", importer, options)) {
    const std::string errors = capture.Errors();
    Fail(what, fmt::format("OpenMesh's STL reader failed{}",
                           errors.empty() ? "" : fmt::format(": {}", errors)));
  }
  return raw;
}

}  // namespace

std::string ReadFileMaybeXz(const std::filesystem::path& file) {
  std::string data = ReadWholeFile(file);
  if (DetectFormat(file).xz) return DecompressXz(data, file.string());
  return data;
}

namespace {

bool IsTetrahedralFormat(const FileFormat& format) {
  return format.extension == "node" || format.extension == "ele" || format.extension == "mesh";
}

// Fails unless `format` is a surface format ParseMeshData reads.
void CheckSurfaceFormat(const FileFormat& format, const std::string& what) {
  const std::string& extension = format.extension;
  if (extension != "obj" && extension != "ply" && extension != "off" && extension != "stl") {
    Fail(what, fmt::format("unknown mesh file extension '{}{}'; supported: {}",
                           extension.empty() ? "" : ".", extension, kSupportedFormats));
  }
}

Mesh ParseMeshData(std::string_view data, const FileFormat& format, const std::string& what) {
  const std::string& extension = format.extension;
  RawMesh raw;
  if (extension == "obj") {
    raw = ParseObj(data, what);
  } else if (extension == "ply") {
    raw = ParsePly(data, what);
  } else if (extension == "off") {
    raw = ParseOff(data, what);
  } else {
    raw = ParseStl(std::string(data), what);
  }
  return BuildMesh(raw, what);
}

}  // namespace

Mesh ReadMesh(const std::filesystem::path& file, std::vector<std::string>* notes) {
  const std::string what = file.string();
  const FileFormat format = DetectFormat(file);
  if (format.extension == "node" || format.extension == "ele") return ReadTetGenMesh(file, notes);
  if (format.extension == "mesh") return ReadMeditMesh(file, notes);
  CheckSurfaceFormat(format, what);  // before reading: a wrong name costs no read
  return ParseMeshData(ReadFileMaybeXz(file), format, what);
}

Mesh ParseMesh(std::string_view data, const std::filesystem::path& name) {
  const std::string what = name.string();
  const FileFormat format = DetectFormat(name);
  if (IsTetrahedralFormat(format)) {
    Fail(what, "tetrahedral formats (.node/.ele, .mesh) are read from files only (ReadMesh)");
  }
  CheckSurfaceFormat(format, what);
  if (format.xz) return ParseMeshData(DecompressXz(data, what), format, what);
  return ParseMeshData(data, format, what);
}

Positions ReadMeshVertices(const std::filesystem::path& file) {
  const std::string& extension = DetectFormat(file).extension;
  if (extension == "node") return ReadTetGenNodes(file);
  if (extension == "mesh") return ReadMeditVertices(file);
  return ReadMesh(file).vertices;
}

Elements BoundaryTriangles(const Elements& tetrahedra) {
  // Outward faces of a positive tetrahedron (a, b, c, d): the faces opposite d, c, b and a.
  constexpr int kFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const Index num_faces = 4 * static_cast<Index>(tetrahedra.rows());
  std::vector<std::array<Index, 3>> sorted(static_cast<size_t>(num_faces));
  std::vector<Index> order(static_cast<size_t>(num_faces));
  for (Index t = 0; t < tetrahedra.rows(); ++t) {
    for (int f = 0; f < 4; ++f) {
      std::array<Index, 3> key = {tetrahedra(t, kFaces[f][0]), tetrahedra(t, kFaces[f][1]),
                                  tetrahedra(t, kFaces[f][2])};
      std::sort(key.begin(), key.end());
      sorted[4 * t + f] = key;
      order[4 * t + f] = 4 * t + f;
    }
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](Index x, Index y) { return sorted[x] < sorted[y]; });
  std::vector<Index> boundary;
  for (size_t k = 0; k < order.size();) {
    size_t end = k + 1;
    while (end < order.size() && sorted[order[end]] == sorted[order[k]]) ++end;
    if (end == k + 1) boundary.push_back(order[k]);
    k = end;
  }
  std::sort(boundary.begin(), boundary.end());
  Elements triangles(static_cast<Index>(boundary.size()), 3);
  for (size_t k = 0; k < boundary.size(); ++k) {
    const Index t = boundary[k] / 4;
    const int f = static_cast<int>(boundary[k] % 4);
    for (int a = 0; a < 3; ++a) triangles(static_cast<Index>(k), a) = tetrahedra(t, kFaces[f][a]);
  }
  return triangles;
}

void WritePly(const std::filesystem::path& file, const Positions& vertices,
              const Elements& mesh_elements) {
  HARAP_CHECK(mesh_elements.rows() == 0 || mesh_elements.cols() == 3 || mesh_elements.cols() == 4,
              "WritePly writes triangles or tetrahedra, got elements with {} vertices",
              mesh_elements.cols());
  const Elements elements =
      mesh_elements.cols() == 4 ? BoundaryTriangles(mesh_elements) : mesh_elements;
  for (Index f = 0; f < elements.rows(); ++f) {
    for (int a = 0; a < 3; ++a) {
      HARAP_CHECK(elements(f, a) >= 0 && elements(f, a) < vertices.rows(),
                  "face {} references vertex {} of {}", f, elements(f, a), vertices.rows());
    }
  }
  std::string buffer = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment written by harap\n"
      "element vertex {}\nproperty double x\nproperty double y\nproperty double z\n"
      "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
      vertices.rows(), elements.rows());
  const size_t header_size = buffer.size();
  buffer.resize(header_size + static_cast<size_t>(vertices.rows()) * 24 +
                static_cast<size_t>(elements.rows()) * 13);
  char* out = buffer.data() + header_size;
  auto put = [&out](auto value) {
    if constexpr (std::endian::native == std::endian::big) {
      unsigned char bytes[sizeof(value)];
      std::memcpy(bytes, &value, sizeof(value));
      std::reverse(bytes, bytes + sizeof(value));
      std::memcpy(out, bytes, sizeof(value));
    } else {
      std::memcpy(out, &value, sizeof(value));
    }
    out += sizeof(value);
  };
  for (Index v = 0; v < vertices.rows(); ++v) {
    for (int d = 0; d < 3; ++d) put(static_cast<double>(vertices(v, d)));
  }
  for (Index f = 0; f < elements.rows(); ++f) {
    put(static_cast<uint8_t>(3));
    for (int a = 0; a < 3; ++a) put(static_cast<int32_t>(elements(f, a)));
  }
  std::ofstream stream(file, std::ios::binary | std::ios::trunc);
  if (!stream) throw Error(fmt::format("{}: cannot open the file for writing", file.string()));
  stream.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  stream.close();
  if (!stream) throw Error(fmt::format("{}: write failed (disk full?)", file.string()));
}

}  // namespace harap
