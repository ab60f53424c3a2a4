// SPDX-License-Identifier: MIT
//
// Parsed here, not by OpenMesh: OpenMesh's readers hand every coordinate to the importer as a
// float (Vec3f) even when the file stores doubles, so coordinates such as "0.354446" would be
// rounded to float. OpenMesh's OBJ reader also produces silent garbage on bad input: a vertex
// line that fails to parse ("v nan 0 0", "v 1e39 0 0") is dropped, which shifts every later
// vertex index; faces with a repeated index ("f 1 1 3") are dropped; index 0 becomes vertex -1.
// Here every problem is an error naming its line, the vertex order of the file is kept
// (unreferenced vertices included) and polygons are fan-triangulated.
#include "io/obj_reader.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "io/raw_mesh.h"
#include "io/text_scanning.h"

namespace harap {

using namespace io_internal;

// OBJ: `v x y z` and `f a b c ...` (a = i, i/t, i//n or i/t/n; 1-based, negative = relative).

Mesh ParseObj(std::string_view data, const std::string& what) {
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
  return BuildMesh(raw, what);
}

}  // namespace harap
