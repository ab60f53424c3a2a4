// SPDX-License-Identifier: MIT
//
// MEDIT .mesh reader. Decisions the format leaves open:
//   - Only Vertices and Tetrahedra are kept; the other standard sections are parsed (so their
//     entry counts are checked) and skipped; an unknown keyword is an error, not a guess.
//   - Orientation: every tetrahedron comes out positively oriented (BuildTetrahedralMesh).
#include "io/medit_reader.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>

#include "io/file_reading.h"
#include "io/raw_mesh.h"
#include "io/text_scanning.h"

namespace harap {

namespace {

using namespace io_internal;

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
      Fail(what,
           fmt::format("line {}: section {} needs its number of entries, found {}", cursor.line(),
                       section, token.empty() ? "the end of the file" : Quote(token)));
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
        Fail(what, fmt::format("line {}: MeshVersionFormatted {} (expected 1 to 4)", cursor.line(),
                               Quote(value)));
      }
    } else if (keyword == "dimension") {
      const std::string_view value = cursor.Next();
      int64_t dimension = 0;
      if (!ParseInteger(value, dimension)) {
        Fail(what,
             fmt::format("line {}: Dimension {} is not an integer", cursor.line(), Quote(value)));
      }
      if (dimension != 3) {
        Fail(what, fmt::format("line {}: Dimension {}: harap reads 3D .mesh files (give planar "
                               "meshes as OBJ/OFF with z = 0)",
                               cursor.line(), dimension));
      }
      have_dimension = true;
    } else if (keyword == "vertices") {
      if (medit.have_vertices)
        Fail(what, fmt::format("line {}: a second Vertices section", cursor.line()));
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
      if (medit.have_tetrahedra)
        Fail(what, fmt::format("line {}: a second Tetrahedra section", cursor.line()));
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
    Fail(what,
         "no Tetrahedra section (harap reads tetrahedral .mesh files; give surfaces as "
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

}  // namespace

Mesh ReadMeditMesh(const std::filesystem::path& file, std::vector<std::string>* notes) {
  return BuildTetrahedralMesh(ParseMedit(ReadFileMaybeXz(file), file.string()).raw, notes);
}

Positions ReadMeditVertices(const std::filesystem::path& file) {
  return ToPositions(ParseMedit(ReadFileMaybeXz(file), file.string()).raw.xyz);
}

}  // namespace harap
