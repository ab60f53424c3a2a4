// SPDX-License-Identifier: MIT
//
// Parsed here, not by OpenMesh: OpenMesh's readers hand every coordinate to the importer as a
// float (Vec3f) even when the file stores doubles, so coordinates such as "0.354446" would be
// rounded to float. A double-precision PLY written by WritePly would then not read back
// bit-identically. OpenMesh's PLY reader also reports a truncated binary file as success with
// the vertices read so far; here a truncation is an error naming the element and byte.
#include "io/ply_reader.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <utility>
#include <vector>

#include "framework/error.h"
#include "io/raw_mesh.h"
#include "io/text_scanning.h"

namespace harap {

namespace {

using namespace io_internal;

// PLY: ASCII and binary (both byte orders); `vertex` with x y z of any scalar type, `face` with a
// `vertex_indices` (or `vertex_index`) list; other elements and properties are skipped.

enum class PlyType { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };

bool ParsePlyType(std::string_view name, PlyType& type) {
  static const std::pair<std::string_view, PlyType> kTypes[] = {
      {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUInt8},
      {"uint8", PlyType::kUInt8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUInt16},  {"uint16", PlyType::kUInt16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},    {"uint", PlyType::kUInt32},     {"uint32", PlyType::kUInt32},
      {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [text, value] : kTypes) {
    if (text == name) {
      type = value;
      return true;
    }
  }
  return false;
}

/// Calls f(T{}) with T the C++ type that stores a value of `type`: the one map from PLY types to
/// C++ types, from which their sizes and the reading of their bytes follow.
template <class F>
auto WithPlyScalar(PlyType type, F&& f) {
  switch (type) {
    case PlyType::kInt8:
      return f(int8_t{});
    case PlyType::kUInt8:
      return f(uint8_t{});
    case PlyType::kInt16:
      return f(int16_t{});
    case PlyType::kUInt16:
      return f(uint16_t{});
    case PlyType::kInt32:
      return f(int32_t{});
    case PlyType::kUInt32:
      return f(uint32_t{});
    case PlyType::kFloat32:
      return f(float{});
    case PlyType::kFloat64:
      return f(double{});
  }
  throw InternalError("unknown PLY type");
}

size_t PlyTypeSize(PlyType type) {
  return WithPlyScalar(type, [](auto scalar) { return sizeof(scalar); });
}

bool IsIntegerType(PlyType type) {
  return WithPlyScalar(type, [](auto scalar) { return std::is_integral_v<decltype(scalar)>; });
}

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
        if (!ParsePlyType(count_type, property.count_type) || !IsIntegerType(property.count_type)) {
          Fail(what, fmt::format("PLY header line {}: bad list count type {}", number,
                                 Quote(count_type)));
        }
        type = NextToken(rest);
      }
      if (!ParsePlyType(type, property.type)) {
        Fail(what,
             fmt::format("PLY header line {}: unknown property type {}", number, Quote(type)));
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
    if (binary_) return ReadBinary(type, value);
    const std::string_view token = NextToken();
    if (token.empty()) return false;
    if (!ParseDouble(token, value)) {
      Fail(what_,
           fmt::format("line {}: vertex coordinate {} is not a number", line_, Quote(token)));
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
      if (c == '\n' ||
          (c == '\r' && (position_ + 1 == data_.size() || data_[position_ + 1] != '\n'))) {
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
  // Reads a binary value of `type` into `value` (an integer into int64_t: integer types only;
  // any type into double: exact for every integer type).
  template <class Value>
  bool ReadBinary(PlyType type, Value& value) {
    unsigned char bytes[8];
    if (!Load(type, bytes)) return false;
    WithPlyScalar(type, [&](auto scalar) {
      using T = decltype(scalar);
      HARAP_CHECK(std::is_floating_point_v<Value> || std::is_integral_v<T>,
                  "integer read of a floating-point PLY property");
      value = static_cast<Value>(As<T>(bytes));
    });
    return true;
  }

  std::string_view data_;
  size_t position_;
  size_t line_;
  bool binary_;
  bool swap_;
  const std::string& what_;
};

// Where ParsePly finds what it keeps: the vertex element and its x, y, z properties, the face
// element and its index list.
struct PlyLayout {
  const PlyElement* vertex_element = nullptr;
  const PlyElement* face_element = nullptr;
  int coordinate_slot[3] = {-1, -1, -1};
  int normal_slot[3] = {-1, -1, -1};  // nx ny nz, where all three are there
  int index_slot = -1;
  bool has_normals() const {
    return normal_slot[0] >= 0 && normal_slot[1] >= 0 && normal_slot[2] >= 0;
  }
};

// `faces`: whether a face element is required (a mesh) or ignored (a point cloud).
PlyLayout LocatePlyData(const PlyHeader& header, const std::string& what, bool faces = true) {
  PlyLayout layout;
  for (const PlyElement& element : header.elements) {
    // A second 'vertex' or 'face' element would leave the slots below pointing into the first
    // one's property list (found by fuzzing: a heap overflow); no writer produces one.
    if ((element.name == "vertex" && layout.vertex_element) ||
        (element.name == "face" && layout.face_element)) {
      Fail(what, fmt::format("PLY header declares the element '{}' twice", element.name));
    }
    if (element.name == "vertex") {
      layout.vertex_element = &element;
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        for (int d = 0; d < 3; ++d) {
          const std::string axis(1, static_cast<char>('x' + d));
          if (property.is_list) continue;
          if (property.name == axis) layout.coordinate_slot[d] = static_cast<int>(p);
          if (property.name == "n" + axis) layout.normal_slot[d] = static_cast<int>(p);
        }
      }
    } else if (element.name == "face") {
      layout.face_element = &element;
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (property.is_list &&
            (property.name == "vertex_indices" || property.name == "vertex_index")) {
          layout.index_slot = static_cast<int>(p);
        }
      }
    }
  }
  if (!layout.vertex_element) Fail(what, "PLY header declares no 'vertex' element");
  for (int d = 0; d < 3; ++d) {
    if (layout.coordinate_slot[d] < 0) {
      Fail(what, fmt::format("PLY 'vertex' element has no scalar property '{}'",
                             static_cast<char>('x' + d)));
    }
  }
  if (!faces) {
    layout.face_element = nullptr;  // skipped like any other element
    return layout;
  }
  if (!layout.face_element || layout.face_element->count == 0) {
    Fail(what, fmt::format("no faces: the PLY file declares {} vertices but no faces",
                           layout.vertex_element->count));
  }
  if (layout.index_slot < 0) {
    Fail(what, "PLY 'face' element has no list property 'vertex_indices' (or 'vertex_index')");
  }
  if (!IsIntegerType(layout.face_element->properties[layout.index_slot].type)) {
    Fail(what, "PLY face property 'vertex_indices' has a floating-point type");
  }
  return layout;
}

// A lower bound on the bytes each item needs, so that a corrupt count fails before it makes us
// reserve gigabytes. (ASCII: one character per value and a separator between values.)
void CheckPlyCounts(const PlyHeader& header, std::string_view body, const std::string& what) {
  const bool binary = header.format != PlyFormat::kAscii;
  for (const PlyElement& element : header.elements) {
    size_t min_bytes = 0;
    for (const PlyProperty& property : element.properties) {
      min_bytes += binary ? PlyTypeSize(property.is_list ? property.count_type : property.type) : 2;
    }
    const size_t available = binary ? body.size() : body.size() + 1;
    if (min_bytes > 0 && static_cast<uint64_t>(element.count) > available / min_bytes) {
      Fail(what, fmt::format("truncated PLY data: the header declares {} '{}' items, more than "
                             "the {} bytes after the header can hold",
                             element.count, element.name, body.size()));
    }
  }
}

// Reads item `item` of `element` into `raw`: a vertex's coordinates, a face's polygon; every
// other property is skipped. `polygon` is a workspace.
// `capture`: one more scalar property to read, appended to `captured` per item of its element.
struct PlyCapture {
  const PlyElement* element = nullptr;
  int slot = -1;
  std::vector<double>* values = nullptr;
};

void ReadPlyItem(PlyBodyReader& reader, const PlyLayout& layout, const PlyElement& element,
                 int64_t item, RawMesh& raw, std::vector<int64_t>& polygon, const std::string& what,
                 std::vector<double>* normals = nullptr, const PlyCapture& capture = {}) {
  const bool is_vertex = &element == layout.vertex_element;
  const bool is_face = &element == layout.face_element;
  const auto truncated = [&] {
    Fail(what, fmt::format("truncated PLY data: the file ends inside element '{}' (item {} of "
                           "{}, at {})",
                           element.name, item, element.count, reader.Where()));
  };
  const int64_t item_location = reader.Location();
  double xyz[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};  // x y z nx ny nz
  const bool read_normals = normals != nullptr && layout.has_normals();
  for (size_t p = 0; p < element.properties.size(); ++p) {
    const PlyProperty& property = element.properties[p];
    if (!property.is_list) {
      int slot = -1;
      for (int d = 0; d < 3; ++d) {
        slot = layout.coordinate_slot[d] == static_cast<int>(p) ? d : slot;
        if (read_normals && layout.normal_slot[d] == static_cast<int>(p)) slot = 3 + d;
      }
      bool ok = false;
      if (is_vertex && slot >= 0) {
        ok = reader.ReadDouble(property.type, xyz[slot]);
      } else if (&element == capture.element && static_cast<int>(p) == capture.slot) {
        double value = 0.0;
        ok = reader.ReadDouble(property.type, value);
        capture.values->push_back(value);
      } else {
        ok = reader.Skip(property.type);
      }
      if (!ok) truncated();
      continue;
    }
    const std::string count_where = reader.Where();
    int64_t count = 0;
    if (!reader.ReadInteger(property.count_type, count)) truncated();
    if (count < 0) {
      Fail(what, fmt::format("{}: PLY element '{}' item {}: negative list length {}", count_where,
                             element.name, item, count));
    }
    if (!is_face || static_cast<int>(p) != layout.index_slot) {
      if (!reader.Skip(property.type, static_cast<uint64_t>(count))) truncated();
      continue;
    }
    if (count < 3) {
      Fail(what, fmt::format("{}: face {}: face has {} vertices (at least 3 are needed)",
                             count_where, item, count));
    }
    polygon.clear();
    for (int64_t i = 0; i < count; ++i) {
      int64_t index = 0;
      if (!reader.ReadInteger(property.type, index)) truncated();
      polygon.push_back(index);
    }
    raw.AddPolygon(polygon, item);
    raw.location.resize(raw.origin.size(), item_location);
  }
  if (is_vertex) {
    if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2])) {
      Fail(what, fmt::format("{} {}: non-finite coordinate: vertex {} (0-based) is ({}, {}, "
                             "{})",
                             raw.location_kind, item_location, item, xyz[0], xyz[1], xyz[2]));
    }
    raw.xyz.insert(raw.xyz.end(), xyz, xyz + 3);
    if (read_normals) {
      if (!std::isfinite(xyz[3]) || !std::isfinite(xyz[4]) || !std::isfinite(xyz[5])) {
        Fail(what, fmt::format("{} {}: non-finite normal: vertex {} (0-based) has ({}, {}, {})",
                               raw.location_kind, item_location, item, xyz[3], xyz[4], xyz[5]));
      }
      normals->insert(normals->end(), xyz + 3, xyz + 6);
    }
  }
}

}  // namespace

namespace {

// ParsePly's reading, with `capture` read on the way; `raw` as read.
RawMesh ReadPlyMesh(std::string_view data, const std::string& what, const PlyHeader& header,
                    const PlyLayout& layout, const PlyCapture& capture = {}) {
  CheckPlyCounts(header, data.substr(header.data_offset), what);
  RawMesh raw;
  raw.origin_kind = "face";
  raw.xyz.reserve(static_cast<size_t>(layout.vertex_element->count) * 3);
  raw.corners.reserve(static_cast<size_t>(layout.face_element->count) * 3);
  raw.origin.reserve(static_cast<size_t>(layout.face_element->count));
  std::vector<int64_t> polygon;
  PlyBodyReader reader(data, header, what);
  raw.location_kind = reader.location_kind();
  bool vertices_done = false;
  for (const PlyElement& element : header.elements) {
    if (element.properties.empty()) continue;  // nothing stored per item
    for (int64_t item = 0; item < element.count; ++item) {
      ReadPlyItem(reader, layout, element, item, raw, polygon, what, nullptr, capture);
    }
    vertices_done = vertices_done || &element == layout.vertex_element;
    // Later elements hold nothing we use.
    if (&element == layout.face_element && vertices_done) break;
  }
  return raw;
}

}  // namespace

Mesh ParsePly(std::string_view data, const std::string& what) {
  const PlyHeader header = ParsePlyHeader(data, what);
  const PlyLayout layout = LocatePlyData(header, what);
  return BuildMesh(ReadPlyMesh(data, what, header, layout), what);
}

PlyMeshProperty ParsePlyMeshProperty(std::string_view data, const std::string& what,
                                     const std::string& name) {
  const PlyHeader header = ParsePlyHeader(data, what);
  const PlyLayout layout = LocatePlyData(header, what);
  PlyCapture capture;
  std::vector<std::string> scalars;
  for (const PlyElement* element : {layout.vertex_element, layout.face_element}) {
    for (size_t p = 0; p < element->properties.size(); ++p) {
      const PlyProperty& property = element->properties[p];
      if (property.is_list) continue;
      scalars.push_back(fmt::format("{} {}", element->name, property.name));
      if (property.name != name) continue;
      if (capture.element != nullptr) {
        Fail(what, fmt::format("both the vertices and the faces have a property '{}': rename "
                               "one of them",
                               name));
      }
      capture.element = element;
      capture.slot = static_cast<int>(p);
    }
  }
  if (capture.element == nullptr) {
    Fail(what, fmt::format("no vertex or face property '{}'; the scalar properties are: {}", name,
                           scalars.empty() ? std::string("none")
                                           : fmt::format("{}", fmt::join(scalars, ", "))));
  }
  std::vector<double> values;
  capture.values = &values;
  const RawMesh raw = ReadPlyMesh(data, what, header, layout, capture);
  PlyMeshProperty property;
  property.element = capture.element->name;
  if (capture.element == layout.vertex_element) {
    property.values = std::move(values);
    return property;
  }
  // One value per triangle of the fans ParsePly makes.
  property.values.reserve(raw.origin.size());
  for (const int64_t face : raw.origin) {
    property.values.push_back(values[static_cast<size_t>(face)]);
  }
  return property;
}

PointCloud ParsePlyPoints(std::string_view data, const std::string& what) {
  const PlyHeader header = ParsePlyHeader(data, what);
  const PlyLayout layout = LocatePlyData(header, what, /*faces=*/false);
  CheckPlyCounts(header, data.substr(header.data_offset), what);
  if (layout.vertex_element->count == 0) Fail(what, "the PLY file declares no vertices");
  RawMesh raw;
  std::vector<double> normals;
  raw.xyz.reserve(static_cast<size_t>(layout.vertex_element->count) * 3);
  std::vector<int64_t> polygon;
  PlyBodyReader reader(data, header, what);
  raw.location_kind = reader.location_kind();
  for (const PlyElement& element : header.elements) {
    if (element.properties.empty()) continue;
    for (int64_t item = 0; item < element.count; ++item) {
      ReadPlyItem(reader, layout, element, item, raw, polygon, what, &normals);
    }
    if (&element == layout.vertex_element) break;  // nothing later is used
  }
  PointCloud cloud;
  cloud.points = ToPositions(raw.xyz);
  if (!normals.empty()) cloud.normals = ToPositions(normals);
  return cloud;
}

bool PlyDeclaresFaces(std::string_view data, const std::string& what) {
  const PlyHeader header = ParsePlyHeader(data, what);
  return std::any_of(header.elements.begin(), header.elements.end(),
                     [](const PlyElement& e) { return e.name == "face" && e.count > 0; });
}

}  // namespace harap
