// SPDX-License-Identifier: MIT
//
// Parsed here, not by OpenMesh: OpenMesh's readers hand every coordinate to the importer as a
// float (Vec3f) even when the file stores doubles, so coordinates such as "0.354446" would be
// rounded to float. OpenMesh's OFF reader also produces silent garbage on bad input: a
// non-numeric coordinate leaves later reads failing and faces are filled with uninitialized
// indices; a header that declares 2e9 faces on a short file, or random bytes, keep the reader
// looping for minutes. Here the counts are checked against the data's size before anything is
// reserved, and every problem is an error naming its line.
#include "io/off_reader.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "io/raw_mesh.h"
#include "io/text_scanning.h"

namespace harap {

using namespace io_internal;

// OFF (ASCII): header `OFF` (or COFF, NOFF, STOFF, ...), counts `nv nf ne`, then one vertex per
// line (x y z, further values ignored) and one face per line (n i1 ... in, 0-based).
//
// Binary OFF: header line `OFF BINARY`, then int32 counts nv nf ne, nv × float32 x y z, and per
// face int32 n and n int32 indices. Two layouts exist in the wild: Geomview's (big-endian, each
// face followed by an int32 colour count and that many float32 values) and the one written by
// pmp-library and others (little-endian, no colour count). The file does not say which, so each
// layout is tried and the one that reads the file to its last byte is taken.

namespace {

// One binary OFF layout: byte order and whether faces carry a colour count.
struct BinaryOffLayout {
  bool big_endian;
  bool colour_counts;
  std::string Name() const {
    return fmt::format("{}-endian{}", big_endian ? "big" : "little",
                       colour_counts ? " with per-face colour counts (Geomview)"
                                     : " without per-face colour counts");
  }
};

// Reads 4-byte values of a binary OFF body with bounds checks; positions in messages are bytes
// from the start of the file.
class BinaryCursor {
 public:
  BinaryCursor(std::string_view body, size_t body_offset, bool big_endian)
      : body_(body), body_offset_(body_offset), big_endian_(big_endian) {}

  bool ReadInt(int64_t& value) {
    uint32_t bits = 0;
    if (!ReadBits(bits)) return false;
    value = static_cast<int32_t>(bits);
    return true;
  }
  bool ReadFloat(double& value) {
    uint32_t bits = 0;
    if (!ReadBits(bits)) return false;
    float f = 0.0F;
    std::memcpy(&f, &bits, sizeof f);
    value = f;
    return true;
  }
  size_t Remaining() const { return body_.size() - position_; }
  /// Byte offset in the file of the next value.
  int64_t FilePosition() const { return static_cast<int64_t>(body_offset_ + position_); }

 private:
  bool ReadBits(uint32_t& bits) {
    if (Remaining() < 4) return false;
    const auto* bytes = reinterpret_cast<const unsigned char*>(body_.data() + position_);
    position_ += 4;
    bits = big_endian_ ? (uint32_t{bytes[0]} << 24 | uint32_t{bytes[1]} << 16 |
                          uint32_t{bytes[2]} << 8 | uint32_t{bytes[3]})
                       : (uint32_t{bytes[3]} << 24 | uint32_t{bytes[2]} << 16 |
                          uint32_t{bytes[1]} << 8 | uint32_t{bytes[0]});
    return true;
  }

  std::string_view body_;
  size_t body_offset_;
  size_t position_ = 0;
  bool big_endian_;
};

// Parses the binary body (after the header line, which ends at byte `body_offset`) in `layout`.
// Returns an empty string and fills `raw` when the layout reads the body exactly, else the
// problem (for the message when no layout fits).
std::string TryBinaryOff(std::string_view body, size_t body_offset, BinaryOffLayout layout,
                         RawMesh& raw) {
  raw = RawMesh{};
  raw.origin_kind = "face";
  raw.location_kind = "byte";
  BinaryCursor cursor(body, body_offset, layout.big_endian);
  int64_t num_vertices = 0;
  int64_t num_faces = 0;
  int64_t num_edges = 0;
  if (!cursor.ReadInt(num_vertices) || !cursor.ReadInt(num_faces) || !cursor.ReadInt(num_edges)) {
    return "truncated file: it ends inside the vertex/face/edge counts";
  }
  if (num_vertices < 0 || num_faces < 0) {
    return fmt::format("negative counts ({} vertices, {} faces)", num_vertices, num_faces);
  }
  // 12 bytes per vertex and at least 16 per face (a triangle): larger counts cannot fit.
  if (num_vertices > static_cast<int64_t>(cursor.Remaining() / 12) ||
      num_faces > static_cast<int64_t>(cursor.Remaining() / 16)) {
    return fmt::format(
        "truncated file: the counts declare {} vertices and {} faces, more than "
        "the {} bytes after them can hold",
        num_vertices, num_faces, cursor.Remaining());
  }
  raw.xyz.resize(static_cast<size_t>(num_vertices) * 3);
  for (double& value : raw.xyz) cursor.ReadFloat(value);  // the size check above covers these
  std::vector<int64_t> polygon;
  for (int64_t f = 0; f < num_faces; ++f) {
    const int64_t face_start = cursor.FilePosition();
    int64_t count = 0;
    if (!cursor.ReadInt(count)) {
      return fmt::format("truncated file: it ends after {} of the {} faces the header declares", f,
                         num_faces);
    }
    if (count < 3 || count > std::numeric_limits<int32_t>::max() / 4) {
      return fmt::format("byte {}: face {} declares {} vertices", face_start, f, count);
    }
    if (count > static_cast<int64_t>(cursor.Remaining() / 4)) {
      return fmt::format(
          "truncated file: it ends inside face {} of the {} faces the header "
          "declares",
          f, num_faces);
    }
    polygon.resize(static_cast<size_t>(count));
    for (int64_t& index : polygon) cursor.ReadInt(index);
    if (layout.colour_counts) {
      int64_t colours = 0;
      if (!cursor.ReadInt(colours)) {
        return fmt::format("truncated file: it ends inside face {} of {}", f, num_faces);
      }
      // Geomview allows 0 (no colour), 1 (colour map index), 3 (RGB) or 4 (RGBA) values.
      if (colours < 0 || colours > 4 || colours > static_cast<int64_t>(cursor.Remaining() / 4)) {
        return fmt::format("byte {}: face {} declares {} colour values", face_start, f, colours);
      }
      double ignored = 0.0;
      for (int64_t c = 0; c < colours; ++c) cursor.ReadFloat(ignored);
    }
    raw.AddPolygon(polygon, f);
    raw.location.resize(raw.origin.size(), face_start);
  }
  if (cursor.Remaining() != 0) {
    return fmt::format("{} bytes follow the last face", cursor.Remaining());
  }
  return {};
}

Mesh ParseBinaryOff(std::string_view data, size_t body_offset, const std::string& what) {
  const std::string_view body = data.substr(body_offset);
  // pmp-library's layout first: it is what current tools write; Geomview's is the original.
  const std::array<BinaryOffLayout, 4> layouts = {{
      {false, false},
      {true, true},
      {false, true},
      {true, false},
  }};
  std::string problems;
  RawMesh raw;
  for (const BinaryOffLayout& layout : layouts) {
    const std::string problem = TryBinaryOff(body, body_offset, layout, raw);
    if (problem.empty()) return BuildMesh(raw, what);
    problems += fmt::format("\n  as {}: {}", layout.Name(), problem);
  }
  Fail(what,
       "binary OFF that reads in none of the known layouts (int32 counts, float32 "
       "coordinates, int32 faces):" +
           problems);
}

// Reads the header line and the counts that follow it: {vertices, faces}; for a binary OFF,
// {-1, offset of the first byte after the header line}.
std::array<int64_t, 2> ReadOffCounts(LineReader& lines, std::string_view data,
                                     const std::string& what) {
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
    if (first == "BINARY") return {-1, static_cast<int64_t>(lines.position())};
    if (first.empty() && !lines.NextContent(counts_line)) {
      Fail(what, "the file ends after the OFF header (no vertex/face counts)");
    }
  }
  std::array<int64_t, 2> counts = {0, 0};
  for (int64_t& count : counts) {
    const std::string_view token = NextToken(counts_line);
    if (!ParseInteger(token, count) || count < 0) {
      Fail(what, fmt::format("line {}: expected the vertex and face counts, found {}",
                             lines.line_number(), Quote(token)));
    }
  }
  // Each vertex line has at least 6 bytes ("0 0 0\n"): a larger count cannot be right, and
  // checking it here keeps a corrupt header from triggering a huge allocation.
  if (counts[0] > static_cast<int64_t>(data.size() / 6) + 1) {
    Fail(what, fmt::format("truncated file: the header declares {} vertices, more than a file of "
                           "{} bytes can hold",
                           counts[0], data.size()));
  }
  return counts;
}

}  // namespace

Mesh ParseOff(std::string_view data, const std::string& what) {
  RawMesh raw;
  LineReader lines(data);
  const auto [num_vertices, num_faces] = ReadOffCounts(lines, data, what);
  if (num_vertices < 0) return ParseBinaryOff(data, static_cast<size_t>(num_faces), what);
  std::string_view line;
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
        Fail(what, fmt::format("line {}: vertex coordinate {} is not a number", lines.line_number(),
                               token.empty() ? "(missing)" : Quote(token)));
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
  return BuildMesh(raw, what);
}

}  // namespace harap
