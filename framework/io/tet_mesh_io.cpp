// SPDX-License-Identifier: MIT
//
// TetGen .node/.ele and MEDIT .mesh readers. Decisions the formats leave open:
//   - TetGen: the base (0 or 1) is the first point id of the .node file, as TetGen itself and
//     WRAPD's loader decide it (the WRAPD scenes use both). Point ids must then be consecutive
//     (TetGen reads only the first id and trusts the rest, so a file with gaps would be misread
//     silently), and the .ele file must number its tetrahedra from the same base: if the two
//     disagree, which base the corner indices use is ambiguous, and guessing could shift every
//     corner by one.
//   - Rows must have exactly the values the header declares; data beyond the declared count is an
//     error. Both catch files whose header does not match their body.
//   - Orientation: every tetrahedron comes out positively oriented (OrientTetrahedra): a rest
//     tetrahedron's corner order carries no meaning, so files written with the opposite
//     convention are accepted (with a note). Flat tetrahedra are errors: no energy can use them.
#include "framework/io/tet_mesh_io.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <system_error>

#include "framework/error.h"
#include "framework/io/mesh_io.h"
#include "framework/io/text_scanning.h"

namespace harap {

namespace {

using namespace io_internal;

// Tetrahedra as read: 0-based corners (range-checked by the parser) and the line of each.
struct RawTetrahedra {
  std::vector<double> xyz;                 // 3 per vertex
  std::vector<std::array<Index, 4>> tets;  // 0-based
  std::vector<size_t> lines;               // per tetrahedron
  std::string tets_file;                   // where the tetrahedra were read (for messages)
};

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

// Memory to reserve for `count` declared items of at least `min_bytes` each in `size` bytes of
// data: a corrupt header must not trigger a huge allocation (a truncated file is then reported
// where it ends). Counts beyond the Index range are errors.
size_t ReserveFor(int64_t count, size_t size, int64_t min_bytes, const std::string& what,
                  std::string_view items) {
  if (count > std::numeric_limits<Index>::max()) {
    Fail(what, fmt::format("{} {}: more than harap's limit of {}", count, items,
                           std::numeric_limits<Index>::max()));
  }
  return static_cast<size_t>(std::min<int64_t>(count, static_cast<int64_t>(size) / min_bytes + 1));
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
    Fail(what, fmt::format("line {}: {} id {} is not an integer", row.line, item,
                           Quote(id_token)));
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
        Fail(what, fmt::format("line {}: non-finite coordinate {} (point {})", number,
                               Quote(token), id));
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
  ParseHeader<3>(line, lines.line_number(), what, {"tetrahedra", "nodes per tetrahedron",
                                                   "attributes"},
                 header);
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
  if (count == 0) Fail(what, fmt::format("line {}: the header declares 0 tetrahedra",
                                         lines.line_number()));
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
        Fail(what, fmt::format("line {}: tetrahedron {} uses point {}, but the points are "
                               "numbered {}..{} ({}-based, {} points)",
                               number, id, index, base, base + num_vertices - 1, base,
                               num_vertices));
      }
      tet[a] = static_cast<Index>(index - base);
      for (int b = 0; b < a; ++b) {
        if (tet[b] == tet[a]) {
          Fail(what, fmt::format("line {}: tetrahedron {} uses point {} twice", number, id,
                                 index));
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

// ---------------------------------------------------------------------------------------------
// MEDIT .mesh (ASCII): keyword-led sections, `#` comments, 1-based indices.

struct MeditSection {
  std::string_view keyword;  // lower case
  int values_per_entry;
};

// Sections harap skips, with the values per entry (references included), from the MEDIT/libMesh
// specification. Anything else is refused rather than guessed.
constexpr MeditSection kSkippedSections[] = {
    {"edges", 3},
    {"triangles", 4},
    {"quadrilaterals", 5},
    {"hexahedra", 9},
    {"prisms", 7},
    {"pyramids", 6},
    {"corners", 1},
    {"ridges", 1},
    {"requiredvertices", 1},
    {"requirededges", 1},
    {"requiredtriangles", 1},
    {"requiredquadrilaterals", 1},
    {"requiredtetrahedra", 1},
    {"normals", 3},
    {"tangents", 3},
    {"normalatvertices", 2},
    {"tangentatvertices", 2},
    {"normalattrianglevertices", 3},
    {"normalatquadrilateralvertices", 3},
    {"tangentatedgevertices", 3},
};

struct MeditData {
  RawTetrahedra raw;
  std::vector<std::array<int64_t, 4>> corners;  // 1-based as read, range-checked later
  bool have_vertices = false;
  bool have_tetrahedra = false;
};

MeditData ParseMedit(std::string_view data, const std::string& what) {
  MeditData medit;
  medit.raw.tets_file = what;
  TokenCursor cursor(data, 1, /*skip_comments=*/true);
  // Reads the count after a section keyword.
  auto read_count = [&](std::string_view section) {
    const std::string_view token = cursor.Next();
    int64_t count = 0;
    if (!ParseInteger(token, count) || count < 0) {
      Fail(what, fmt::format("line {}: section {} needs its number of entries, found {}",
                             cursor.line(), section, token.empty() ? "the end of the file"
                                                                   : Quote(token)));
    }
    return count;
  };
  // The next value of entry `entry` of `section`; the end of the data is a truncation.
  auto next_value = [&](std::string_view section, int64_t entry, int64_t count) {
    const std::string_view token = cursor.Next();
    if (token.empty()) {
      Fail(what, fmt::format("truncated file: it ends in section {} after {} of its {} entries",
                             section, entry, count));
    }
    return token;
  };
  auto not_number = [&](std::string_view token, std::string_view section, int64_t entry) {
    Fail(what, fmt::format("line {}: {} is not a number (section {}, entry {})", cursor.line(),
                           Quote(token), section, entry + 1));
  };
  bool have_dimension = false;
  while (true) {
    const std::string_view token = cursor.Next();
    if (token.empty()) break;
    const std::string keyword = Lower(std::string(token));
    if (keyword == "end") break;
    if (keyword == "meshversionformatted") {
      const std::string_view value = cursor.Next();
      int64_t version = 0;
      if (!ParseInteger(value, version) || version < 1 || version > 4) {
        Fail(what, fmt::format("line {}: MeshVersionFormatted {} (expected 1 to 4)",
                               cursor.line(), Quote(value)));
      }
    } else if (keyword == "dimension") {
      const std::string_view value = cursor.Next();
      int64_t dimension = 0;
      if (!ParseInteger(value, dimension)) {
        Fail(what, fmt::format("line {}: Dimension {} is not an integer", cursor.line(),
                               Quote(value)));
      }
      if (dimension != 3) {
        Fail(what, fmt::format("line {}: Dimension {}: harap reads 3D .mesh files (give planar "
                               "meshes as OBJ/OFF with z = 0)",
                               cursor.line(), dimension));
      }
      have_dimension = true;
    } else if (keyword == "vertices") {
      if (medit.have_vertices) Fail(what, fmt::format("line {}: a second Vertices section",
                                                      cursor.line()));
      medit.have_vertices = true;
      const int64_t count = read_count("Vertices");
      // Each value takes at least two bytes (a digit and a separator).
      medit.raw.xyz.reserve(ReserveFor(count, data.size(), 8, what, "vertices") * 3);
      for (int64_t v = 0; v < count; ++v) {
        for (int d = 0; d < 4; ++d) {
          const std::string_view value = next_value("Vertices", v, count);
          double number = 0.0;
          if (!ParseDouble(value, number)) not_number(value, "Vertices", v);
          if (d == 3) break;  // the reference: any number
          if (!std::isfinite(number)) {
            Fail(what, fmt::format("line {}: non-finite coordinate {} (vertex {}, 1-based)",
                                   cursor.line(), Quote(value), v + 1));
          }
          medit.raw.xyz.push_back(number);
        }
      }
    } else if (keyword == "tetrahedra") {
      if (medit.have_tetrahedra) Fail(what, fmt::format("line {}: a second Tetrahedra section",
                                                        cursor.line()));
      medit.have_tetrahedra = true;
      const int64_t count = read_count("Tetrahedra");
      const size_t reserve = ReserveFor(count, data.size(), 10, what, "tetrahedra");
      medit.corners.reserve(reserve);
      medit.raw.lines.reserve(reserve);
      for (int64_t t = 0; t < count; ++t) {
        std::array<int64_t, 4> tet{};
        for (int a = 0; a < 5; ++a) {
          const std::string_view value = next_value("Tetrahedra", t, count);
          int64_t index = 0;
          if (!ParseInteger(value, index)) {
            Fail(what, fmt::format("line {}: {} is not an integer (section Tetrahedra, entry {})",
                                   cursor.line(), Quote(value), t + 1));
          }
          if (a < 4) tet[a] = index;
        }
        medit.corners.push_back(tet);
        medit.raw.lines.push_back(cursor.line());
      }
    } else {
      const auto* section =
          std::find_if(std::begin(kSkippedSections), std::end(kSkippedSections),
                       [&](const MeditSection& s) { return s.keyword == keyword; });
      if (section == std::end(kSkippedSections)) {
        double ignored = 0.0;
        if (ParseDouble(token, ignored)) {
          Fail(what, fmt::format("line {}: number {} where a section keyword was expected (does "
                                 "the previous section hold more entries than it declares?)",
                                 cursor.line(), Quote(token)));
        }
        std::vector<std::string_view> known = {"MeshVersionFormatted", "Dimension", "Vertices",
                                               "Tetrahedra", "End"};
        for (const auto& s : kSkippedSections) known.push_back(s.keyword);
        Fail(what, fmt::format("line {}: unknown section keyword {} (known, case-insensitive: "
                               "{})",
                               cursor.line(), Quote(token), fmt::join(known, ", ")));
      }
      const std::string name(token);
      const int64_t count = read_count(name);
      for (int64_t entry = 0; entry < count; ++entry) {
        for (int value = 0; value < section->values_per_entry; ++value) {
          const std::string_view text = next_value(name, entry, count);
          double ignored = 0.0;
          if (!ParseDouble(text, ignored)) not_number(text, name, entry);
        }
      }
    }
  }
  (void)have_dimension;  // absent Dimension: 3, the only dimension harap reads
  if (!medit.have_vertices) Fail(what, "no Vertices section");
  if (!medit.have_tetrahedra) {
    Fail(what, "no Tetrahedra section (harap reads tetrahedral .mesh files; give surfaces as "
               "OBJ, PLY, OFF or STL)");
  }
  // Range checks once both sections are known (the format does not order them).
  const int64_t num_vertices = static_cast<int64_t>(medit.raw.xyz.size() / 3);
  medit.raw.tets.reserve(medit.corners.size());
  for (size_t t = 0; t < medit.corners.size(); ++t) {
    std::array<Index, 4> tet{};
    for (int a = 0; a < 4; ++a) {
      const int64_t index = medit.corners[t][a];
      if (index < 1 || index > num_vertices) {
        Fail(what, fmt::format("line {}: tetrahedron {} (1-based) uses vertex {}, but the "
                               "vertices are numbered 1..{}",
                               medit.raw.lines[t], t + 1, index, num_vertices));
      }
      tet[a] = static_cast<Index>(index - 1);
      for (int b = 0; b < a; ++b) {
        if (tet[b] == tet[a]) {
          Fail(what, fmt::format("line {}: tetrahedron {} (1-based) uses vertex {} twice",
                                 medit.raw.lines[t], t + 1, index));
        }
      }
    }
    medit.raw.tets.push_back(tet);
  }
  return medit;
}

// ---------------------------------------------------------------------------------------------

Positions ToPositions(const std::vector<double>& xyz) {
  Positions positions(static_cast<Index>(xyz.size() / 3), 3);
  for (Index v = 0; v < positions.rows(); ++v) {
    for (int d = 0; d < 3; ++d) positions(v, d) = xyz[3 * static_cast<size_t>(v) + d];
  }
  return positions;
}

// The Mesh of `raw`, oriented; flat tetrahedra are errors naming their line.
Mesh BuildTetrahedralMesh(const RawTetrahedra& raw, std::vector<std::string>* notes) {
  Mesh mesh;
  mesh.vertices = ToPositions(raw.xyz);
  mesh.elements.resize(static_cast<Index>(raw.tets.size()), 4);
  for (Index t = 0; t < mesh.num_elements(); ++t) {
    for (int a = 0; a < 4; ++a) mesh.elements(t, a) = raw.tets[t][a];
  }
  const TetrahedronOrientation orientation = OrientTetrahedra(mesh);
  if (!orientation.degenerate.empty()) {
    const Index t = orientation.degenerate.front();
    Fail(raw.tets_file,
         fmt::format("line {}: tetrahedron {} (0-based; corners {}, 0-based) is flat (zero "
                     "volume){}; flat tetrahedra have no orientation and no finite "
                     "cotangent weights",
                     raw.lines[t], t, fmt::join(raw.tets[t], " "),
                     orientation.degenerate.size() > 1
                         ? fmt::format(", one of {} flat tetrahedra",
                                       orientation.degenerate.size())
                         : std::string()));
  }
  if (orientation.reoriented > 0 && notes) {
    notes->push_back(fmt::format("{}: {} of {} tetrahedra had negative signed volume and were "
                                 "reoriented (last two corners swapped)",
                                 raw.tets_file, orientation.reoriented, mesh.num_elements()));
  }
  ValidateMesh(mesh, raw.tets_file);
  return mesh;
}

}  // namespace

double TetrahedronDeterminant(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  return (b - a).dot((c - a).cross(d - a));
}

TetrahedronOrientation OrientTetrahedra(Mesh& mesh) {
  TetrahedronOrientation result;
  if (mesh.kind() != ElementKind::kTetrahedron) return result;
  // Relative flatness below which the determinant is rounding noise (see the header).
  constexpr double kFlatness = 1e-12;
  for (Index t = 0; t < mesh.num_elements(); ++t) {
    auto corner = [&](int a) -> Eigen::Vector3d {
      return mesh.vertices.row(mesh.elements(t, a)).transpose();
    };
    const Eigen::Vector3d p = corner(0);
    const Eigen::Vector3d q = corner(1);
    const Eigen::Vector3d r = corner(2);
    const Eigen::Vector3d s = corner(3);
    const double det = TetrahedronDeterminant(p, q, r, s);
    const double scale = (q - p).norm() * (r - p).norm() * (s - p).norm();
    if (!(std::abs(det) > kFlatness * scale)) {
      result.degenerate.push_back(t);
    } else if (det < 0.0) {
      std::swap(mesh.elements(t, 2), mesh.elements(t, 3));
      ++result.reoriented;
    }
  }
  return result;
}

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

Mesh ReadMeditMesh(const std::filesystem::path& file, std::vector<std::string>* notes) {
  return BuildTetrahedralMesh(ParseMedit(ReadFileMaybeXz(file), file.string()).raw, notes);
}

Positions ReadMeditVertices(const std::filesystem::path& file) {
  return ToPositions(ParseMedit(ReadFileMaybeXz(file), file.string()).raw.xyz);
}

}  // namespace harap
