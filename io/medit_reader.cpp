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

// One pass over the file's tokens, section by section.
class MeditParser {
 public:
  MeditParser(std::string_view data, const std::string& what)
      : data_(data), what_(what), cursor_(data, 1, /*skip_comments=*/true) {
    medit_.raw.tets_file = what;
  }

  MeditData Parse() {
    while (true) {
      const std::string_view token = cursor_.Next();
      if (token.empty()) break;
      const std::string keyword = Lower(std::string(token));
      if (keyword == "end") break;
      if (keyword == "meshversionformatted") {
        ReadVersion();
      } else if (keyword == "dimension") {
        ReadDimension();  // absent: 3, the only dimension harap reads
      } else if (keyword == "vertices") {
        ReadVertices();
      } else if (keyword == "tetrahedra") {
        ReadTetrahedra();
      } else {
        SkipSection(token, keyword);
      }
    }
    if (!medit_.have_vertices) Fail(what_, "no Vertices section");
    if (!medit_.have_tetrahedra) {
      Fail(what_,
           "no Tetrahedra section (harap reads tetrahedral .mesh files; give surfaces as "
           "OBJ, PLY, OFF or STL)");
    }
    CheckCorners();
    return std::move(medit_);
  }

 private:
  // Reads the count after a section keyword.
  int64_t ReadCount(std::string_view section) {
    const std::string_view token = cursor_.Next();
    int64_t count = 0;
    if (!ParseInteger(token, count) || count < 0) {
      Fail(what_,
           fmt::format("line {}: section {} needs its number of entries, found {}", cursor_.line(),
                       section, token.empty() ? "the end of the file" : Quote(token)));
    }
    return count;
  }
  // The next value of entry `entry` of `section`; the end of the data is a truncation.
  std::string_view NextValue(std::string_view section, int64_t entry, int64_t count) {
    const std::string_view token = cursor_.Next();
    if (token.empty()) {
      Fail(what_, fmt::format("truncated file: it ends in section {} after {} of its {} entries",
                              section, entry, count));
    }
    return token;
  }
  [[noreturn]] void NotNumber(std::string_view token, std::string_view section, int64_t entry) {
    Fail(what_, fmt::format("line {}: {} is not a number (section {}, entry {})", cursor_.line(),
                            Quote(token), section, entry + 1));
  }

  void ReadVersion() {
    const std::string_view value = cursor_.Next();
    int64_t version = 0;
    if (!ParseInteger(value, version) || version < 1 || version > 4) {
      Fail(what_, fmt::format("line {}: MeshVersionFormatted {} (expected 1 to 4)", cursor_.line(),
                              Quote(value)));
    }
  }

  void ReadDimension() {
    const std::string_view value = cursor_.Next();
    int64_t dimension = 0;
    if (!ParseInteger(value, dimension)) {
      Fail(what_,
           fmt::format("line {}: Dimension {} is not an integer", cursor_.line(), Quote(value)));
    }
    if (dimension != 3) {
      Fail(what_, fmt::format("line {}: Dimension {}: harap reads 3D .mesh files (give planar "
                              "meshes as OBJ/OFF with z = 0)",
                              cursor_.line(), dimension));
    }
  }

  void ReadVertices() {
    if (medit_.have_vertices) {
      Fail(what_, fmt::format("line {}: a second Vertices section", cursor_.line()));
    }
    medit_.have_vertices = true;
    const int64_t count = ReadCount("Vertices");
    // Each value takes at least two bytes (a digit and a separator).
    medit_.raw.xyz.reserve(ReserveFor(count, data_.size(), 8, what_, "vertices") * 3);
    for (int64_t v = 0; v < count; ++v) {
      for (int d = 0; d < 4; ++d) {
        const std::string_view value = NextValue("Vertices", v, count);
        double number = 0.0;
        if (!ParseDouble(value, number)) NotNumber(value, "Vertices", v);
        if (d == 3) break;  // the reference: any number
        if (!std::isfinite(number)) {
          Fail(what_, fmt::format("line {}: non-finite coordinate {} (vertex {}, 1-based)",
                                  cursor_.line(), Quote(value), v + 1));
        }
        medit_.raw.xyz.push_back(number);
      }
    }
  }

  void ReadTetrahedra() {
    if (medit_.have_tetrahedra) {
      Fail(what_, fmt::format("line {}: a second Tetrahedra section", cursor_.line()));
    }
    medit_.have_tetrahedra = true;
    const int64_t count = ReadCount("Tetrahedra");
    const size_t reserve = ReserveFor(count, data_.size(), 10, what_, "tetrahedra");
    medit_.corners.reserve(reserve);
    medit_.raw.lines.reserve(reserve);
    for (int64_t t = 0; t < count; ++t) {
      std::array<int64_t, 4> tet{};
      for (int a = 0; a < 5; ++a) {
        const std::string_view value = NextValue("Tetrahedra", t, count);
        int64_t index = 0;
        if (!ParseInteger(value, index)) {
          Fail(what_, fmt::format("line {}: {} is not an integer (section Tetrahedra, entry {})",
                                  cursor_.line(), Quote(value), t + 1));
        }
        if (a < 4) tet[a] = index;
      }
      medit_.corners.push_back(tet);
      medit_.raw.lines.push_back(cursor_.line());
    }
  }

  // A section harap does not keep: its entries are read and checked to be numbers.
  void SkipSection(std::string_view token, const std::string& keyword) {
    const auto* section = std::find_if(std::begin(kSkippedSections), std::end(kSkippedSections),
                                       [&](const MeditSection& s) { return s.keyword == keyword; });
    if (section == std::end(kSkippedSections)) {
      double ignored = 0.0;
      if (ParseDouble(token, ignored)) {
        Fail(what_, fmt::format("line {}: number {} where a section keyword was expected (does "
                                "the previous section hold more entries than it declares?)",
                                cursor_.line(), Quote(token)));
      }
      std::vector<std::string_view> known = {"MeshVersionFormatted", "Dimension", "Vertices",
                                             "Tetrahedra", "End"};
      for (const auto& s : kSkippedSections) known.push_back(s.keyword);
      Fail(what_, fmt::format("line {}: unknown section keyword {} (known, case-insensitive: "
                              "{})",
                              cursor_.line(), Quote(token), fmt::join(known, ", ")));
    }
    const std::string name(token);
    const int64_t count = ReadCount(name);
    for (int64_t entry = 0; entry < count; ++entry) {
      for (int value = 0; value < section->values_per_entry; ++value) {
        const std::string_view text = NextValue(name, entry, count);
        double ignored = 0.0;
        if (!ParseDouble(text, ignored)) NotNumber(text, name, entry);
      }
    }
  }

  // Range checks once both sections are known (the format does not order them).
  void CheckCorners() {
    const int64_t num_vertices = static_cast<int64_t>(medit_.raw.xyz.size() / 3);
    medit_.raw.tets.reserve(medit_.corners.size());
    for (size_t t = 0; t < medit_.corners.size(); ++t) {
      std::array<Index, 4> tet{};
      for (int a = 0; a < 4; ++a) {
        const int64_t index = medit_.corners[t][a];
        if (index < 1 || index > num_vertices) {
          Fail(what_, fmt::format("line {}: tetrahedron {} (1-based) uses vertex {}, but the "
                                  "vertices are numbered 1..{}",
                                  medit_.raw.lines[t], t + 1, index, num_vertices));
        }
        tet[a] = static_cast<Index>(index - 1);
        for (int b = 0; b < a; ++b) {
          if (tet[b] == tet[a]) {
            Fail(what_, fmt::format("line {}: tetrahedron {} (1-based) uses vertex {} twice",
                                    medit_.raw.lines[t], t + 1, index));
          }
        }
      }
      medit_.raw.tets.push_back(tet);
    }
  }

  std::string_view data_;
  const std::string& what_;
  TokenCursor cursor_;
  MeditData medit_;
};

MeditData ParseMedit(std::string_view data, const std::string& what) {
  return MeditParser(data, what).Parse();
}

}  // namespace

Mesh ReadMeditMesh(const std::filesystem::path& file, std::vector<std::string>* notes) {
  return BuildTetrahedralMesh(ParseMedit(ReadFileMaybeXz(file), file.string()).raw, notes);
}

Positions ReadMeditVertices(const std::filesystem::path& file) {
  return ToPositions(ParseMedit(ReadFileMaybeXz(file), file.string()).raw.xyz);
}

}  // namespace harap
