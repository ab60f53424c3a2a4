// SPDX-License-Identifier: MIT
//
// TetGen .node/.ele reader. Decisions the format leaves open:
//   - The base (0 or 1) is the first point id of the .node file, as TetGen itself and
//     WRAPD's loader decide it (the WRAPD scenes use both). Point ids must then be consecutive
//     (TetGen reads only the first id and trusts the rest, so a file with gaps would be misread
//     silently), and the .ele file must number its tetrahedra from the same base: if the two
//     disagree, which base the corner indices use is ambiguous, and guessing could shift every
//     corner by one.
//   - Rows must have exactly the values the header declares; data beyond the declared count is an
//     error. Both catch files whose header does not match their body.
//   - Orientation: every tetrahedron comes out positively oriented (BuildTetrahedralMesh).
#include "io/tetgen_reader.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <array>
#include <cmath>
#include <system_error>
#include <utility>

#include "io/file_reading.h"
#include "io/raw_mesh.h"
#include "io/text_scanning.h"

namespace harap {

namespace {

using namespace io_internal;

// The file name with its format extension and an optional trailing ".xz" removed, and whether
// it was compressed: "a/x_rest.node.xz" -> ("a/x_rest", true).
std::pair<std::filesystem::path, bool> SplitName(const std::filesystem::path& file) {
  std::filesystem::path name = file;
  bool xz = false;
  if (Lower(name.extension().string()) == ".xz") {
    xz = true;
    name.replace_extension();
  }
  name.replace_extension();
  return {name, xz};
}

// The companion of a TetGen file: same stem, extension `extension`, preferring the same
// compression.
std::filesystem::path FindCompanion(const std::filesystem::path& file, const char* extension,
                                    const char* role) {
  const auto [stem, xz] = SplitName(file);
  const std::filesystem::path plain = stem.string() + extension;
  const std::filesystem::path compressed = plain.string() + ".xz";
  std::error_code error;
  for (const auto& candidate : xz ? std::array{compressed, plain} : std::array{plain, compressed}) {
    if (std::filesystem::is_regular_file(candidate, error)) return candidate;
  }
  Fail(file.string(), fmt::format("the {} file with its {} is missing (looked for {} and {})",
                                  extension, role, plain.string(), compressed.string()));
}

// Reads the integers of a header line into `values` (absent trailing ones keep their defaults).
template <size_t N>
void ParseHeader(std::string_view line, size_t line_number, const std::string& what,
                 const std::array<const char*, N>& names, std::array<int64_t, N>& values) {
  for (size_t i = 0; i < N; ++i) {
    const std::string_view token = NextToken(line);
    if (token.empty()) break;
    if (!ParseInteger(token, values[i]) || values[i] < 0) {
      Fail(what, fmt::format("line {}: header value {} ({}) is not a non-negative integer",
                             line_number, Quote(token), names[i]));
    }
  }
  if (!NextToken(line).empty()) {
    Fail(what, fmt::format("line {}: the header has more than {} values ({})", line_number, N,
                           fmt::join(names, ", ")));
  }
}

// ---------------------------------------------------------------------------------------------
// TetGen .node: `N 3 A B` then `id x y z [A attributes] [B boundary marker]` per point.

// The next data row of a TetGen file (row `index` of the `count` the header declares): its line
// number and leading id; `line` is left after the id.
struct TetGenRow {
  size_t line = 0;
  int64_t id = 0;
};

TetGenRow NextTetGenRow(LineReader& lines, std::string_view& line, int64_t index, int64_t count,
                        std::string_view item, std::string_view items, const std::string& what) {
  if (!lines.NextContent(line)) {
    Fail(what, fmt::format("truncated file: it ends after {} of the {} {} the header declares",
                           index, count, items));
  }
  TetGenRow row;
  row.line = lines.line_number();
  const std::string_view id_token = NextToken(line);
  if (!ParseInteger(id_token, row.id)) {
    Fail(what, fmt::format("line {}: {} id {} is not an integer", row.line, item, Quote(id_token)));
  }
  return row;
}

// How many values (attributes, markers) are left on `line`; each must be a number.
int64_t CountTrailingNumbers(std::string_view line, const TetGenRow& row, std::string_view item,
                             const std::string& what) {
  int64_t found = 0;
  for (std::string_view token = NextToken(line); !token.empty(); token = NextToken(line)) {
    double ignored = 0.0;
    if (!ParseDouble(token, ignored)) {
      Fail(what, fmt::format("line {}: {} is not a number ({} {})", row.line, Quote(token), item,
                             row.id));
    }
    ++found;
  }
  return found;
}

struct TetGenNodes {
  std::vector<double> xyz;
  int64_t base = 0;
};

TetGenNodes ParseTetGenNodes(std::string_view data, const std::string& what) {
  LineReader lines(data);
  std::string_view line;
  if (!lines.NextContent(line)) Fail(what, "empty file (no .node header)");
  std::array<int64_t, 4> header = {0, 3, 0, 0};
  ParseHeader<4>(line, lines.line_number(), what,
                 {"points", "dimension", "attributes", "boundary markers"}, header);
  const auto [count, dimension, attributes, markers] = header;
  if (dimension != 3) {
    Fail(what, fmt::format("line {}: dimension {}: harap reads 3D .node files (give planar "
                           "meshes as OBJ/OFF with z = 0)",
                           lines.line_number(), dimension));
  }
  if (markers > 1) {
    Fail(what, fmt::format("line {}: {} boundary markers per point (TetGen allows 0 or 1)",
                           lines.line_number(), markers));
  }
  if (count == 0) {
    Fail(what, fmt::format("line {}: the header declares 0 points (a .node file that only "
                           "accompanies a .poly file holds no mesh)",
                           lines.line_number()));
  }
  TetGenNodes nodes;
  nodes.xyz.reserve(ReserveFor(count, data.size(), 8, what, "points") * 3);
  const int64_t extra = attributes + markers;
  for (int64_t i = 0; i < count; ++i) {
    const TetGenRow row = NextTetGenRow(lines, line, i, count, "point", "points", what);
    const size_t number = row.line;
    const int64_t id = row.id;
    if (i == 0) {
      if (id != 0 && id != 1) {
        Fail(what, fmt::format("line {}: the first point id is {}; TetGen files number from 0 "
                               "or 1",
                               number, id));
      }
      nodes.base = id;
    } else if (id != nodes.base + i) {
      Fail(what, fmt::format("line {}: point id {} out of sequence (expected {}; ids must be "
                             "consecutive)",
                             number, id, nodes.base + i));
    }
    for (int d = 0; d < 3; ++d) {
      const std::string_view token = NextToken(line);
      double value = 0.0;
      if (!ParseDouble(token, value)) {
        Fail(what, fmt::format("line {}: coordinate {} of point {} is not a number", number,
                               token.empty() ? "(missing)" : Quote(token), id));
      }
      if (!std::isfinite(value)) {
        Fail(what,
             fmt::format("line {}: non-finite coordinate {} (point {})", number, Quote(token), id));
      }
      nodes.xyz.push_back(value);
    }
    const int64_t found = CountTrailingNumbers(line, row, "point", what);
    if (found != extra) {
      Fail(what, fmt::format("line {}: point {} has {} values after its coordinates, but the "
                             "header declares {} attributes and {} boundary markers",
                             number, id, found, attributes, markers));
    }
  }
  if (lines.NextContent(line)) {
    Fail(what, fmt::format("line {}: more data after the {} points the header declares",
                           lines.line_number(), count));
  }
  return nodes;
}

// TetGen .ele: `T 4 A` then `id v0 v1 v2 v3 [A attributes]` per tetrahedron, indices in the
// .node file's base.
void ParseTetGenElements(std::string_view data, const std::string& what, int64_t base,
                         int64_t num_vertices, RawTetrahedra& raw) {
  LineReader lines(data);
  std::string_view line;
  if (!lines.NextContent(line)) Fail(what, "empty file (no .ele header)");
  std::array<int64_t, 3> header = {0, 4, 0};
  ParseHeader<3>(line, lines.line_number(), what,
                 {"tetrahedra", "nodes per tetrahedron", "attributes"}, header);
  const auto [count, corners, attributes] = header;
  if (corners == 10) {
    Fail(what, fmt::format("line {}: 10-node (quadratic) tetrahedra are not supported; "
                           "tetrahedralize without -o2",
                           lines.line_number()));
  }
  if (corners != 4) {
    Fail(what, fmt::format("line {}: {} nodes per tetrahedron (TetGen writes 4, or 10 for "
                           "quadratic ones)",
                           lines.line_number(), corners));
  }
  if (count == 0)
    Fail(what, fmt::format("line {}: the header declares 0 tetrahedra", lines.line_number()));
  const size_t reserve = ReserveFor(count, data.size(), 10, what, "tetrahedra");
  raw.tets.reserve(reserve);
  raw.lines.reserve(reserve);
  for (int64_t t = 0; t < count; ++t) {
    const TetGenRow row = NextTetGenRow(lines, line, t, count, "tetrahedron", "tetrahedra", what);
    const size_t number = row.line;
    const int64_t id = row.id;
    if (id != base + t) {
      Fail(what, fmt::format("line {}: tetrahedron id {} where {} was expected (ids must be "
                             "consecutive from {}, the base of the .node file's point ids)",
                             number, id, base + t, base));
    }
    std::array<Index, 4> tet{};
    for (int a = 0; a < 4; ++a) {
      const std::string_view token = NextToken(line);
      int64_t index = 0;
      if (!ParseInteger(token, index)) {
        Fail(what, fmt::format("line {}: corner {} of tetrahedron {} is {}, not a point index",
                               number, a + 1, id, token.empty() ? "missing" : Quote(token)));
      }
      if (index < base || index >= base + num_vertices) {
        Fail(what,
             fmt::format("line {}: tetrahedron {} uses point {}, but the points are "
                         "numbered {}..{} ({}-based, {} points)",
                         number, id, index, base, base + num_vertices - 1, base, num_vertices));
      }
      tet[a] = static_cast<Index>(index - base);
      for (int b = 0; b < a; ++b) {
        if (tet[b] == tet[a]) {
          Fail(what, fmt::format("line {}: tetrahedron {} uses point {} twice", number, id, index));
        }
      }
    }
    const int64_t found = CountTrailingNumbers(line, row, "tetrahedron", what);
    if (found != attributes) {
      Fail(what, fmt::format("line {}: tetrahedron {} has {} values after its corners, but the "
                             "header declares {} attributes",
                             number, id, found, attributes));
    }
    raw.tets.push_back(tet);
    raw.lines.push_back(number);
  }
  if (lines.NextContent(line)) {
    Fail(what, fmt::format("line {}: more data after the {} tetrahedra the header declares",
                           lines.line_number(), count));
  }
}

}  // namespace

Mesh ReadTetGenMesh(const std::filesystem::path& file, std::vector<std::string>* notes) {
  std::filesystem::path node_file = file;
  std::filesystem::path ele_file = file;
  {
    const std::string name = Lower(file.filename().string());
    if (EndsWith(name, ".node") || EndsWith(name, ".node.xz")) {
      ele_file = FindCompanion(file, ".ele", "tetrahedra");
    } else if (EndsWith(name, ".ele") || EndsWith(name, ".ele.xz")) {
      node_file = FindCompanion(file, ".node", "points");
    } else {
      Fail(file.string(), "a TetGen mesh is named by its .node or .ele file");
    }
  }
  const TetGenNodes nodes = ParseTetGenNodes(ReadFileMaybeXz(node_file), node_file.string());
  RawTetrahedra raw;
  raw.tets_file = ele_file.string();
  raw.xyz = nodes.xyz;
  ParseTetGenElements(ReadFileMaybeXz(ele_file), raw.tets_file, nodes.base,
                      static_cast<int64_t>(nodes.xyz.size() / 3), raw);
  return BuildTetrahedralMesh(raw, notes);
}

Positions ReadTetGenNodes(const std::filesystem::path& node_file) {
  return ToPositions(ParseTetGenNodes(ReadFileMaybeXz(node_file), node_file.string()).xyz);
}

}  // namespace harap
