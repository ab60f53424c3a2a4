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
#include <vector>

#include "io/raw_mesh.h"
#include "io/text_scanning.h"

namespace harap {

using namespace io_internal;

// OFF (ASCII): header `OFF` (or COFF, NOFF, STOFF, ...), counts `nv nf ne`, then one vertex per
// line (x y z, further values ignored) and one face per line (n i1 ... in, 0-based).

namespace {

// Reads the header line and the counts that follow it: {vertices, faces}.
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
    if (first == "BINARY") {
      Fail(what, "binary OFF is not supported (convert it to PLY or ASCII OFF)");
    }
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
