// SPDX-License-Identifier: MIT
//
// Scenario files (shared/scenarios/FORMAT.md). Decisions the format leaves open:
//   - "The bounding box of the rest mesh" is the box of the vertices referenced by some triangle
//     (the same set BoundingBoxDiagonal uses), after `refine`. Unreferenced vertices (the
//     Stanford bunny has 1,113) are stray points, not surface: they neither stretch the box nor
//     get picked by `slab`/`ball` selections. `indices`/`index_file` may name any vertex.
//   - An axis along which the box is flat (extent 0) gives every vertex the fraction 0 there.
//   - Everything written in the scenario text (unknown keys, bad values, selections that match
//     nothing) is a ConfigError; problems with the files it names (missing, unreadable, bad
//     index files) are InputErrors. Every message starts with "file:line:column".
//   - The whole text is checked before the mesh is read, so a typo does not cost a mesh load
//     (the keys of a `mesh` table are the exception: they are checked when it is built).
//   - `refine` of a non-manifold surface uses the crease variant of Loop subdivision, with a note.
//   - `units = "absolute"` (per handle, or at the top level for every handle) reads slab bounds,
//     ball centre and radius, rotate.center and translate in mesh coordinates instead of box
//     fractions and diagonals.
//   - `refine` of a tetrahedralized surface subdivides the surface before TetGen fills it; `refine`
//     of a tetrahedral file is an error (Loop subdivision is for triangles).
//   - `initial` reads vertex positions only (ReadMeshVertices): a start configuration may have
//     inverted or flat tetrahedra, and for TetGen only its .node file is needed.
//   - Planar (Mesh::planar) is `planar = true/false` if given, else automatic: a triangle mesh
//     whose vertices, handle targets and initial positions all have z = 0 exactly. A flat mesh
//     with a handle that leaves the plane is a surface problem (lifting a sheet), not an error.
#include "framework/io/scenario.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <toml++/toml.h>
#include <type_traits>

#include "framework/config.h"
#include "framework/error.h"
#include "framework/io/builtin_meshes.h"
#include "framework/io/mesh_io.h"
#include "framework/io/subdivision.h"
#include "framework/io/file_reading.h"
#include "framework/io/tetrahedra.h"
#include "framework/io/tetrahedralize.h"
#include "framework/io/text_scanning.h"

namespace harap {

namespace {

enum class SelectionKind { kSlab, kBall, kIndices, kIndexFile };
enum class TargetKind { kMotion, kInitial, kFile };

// How the numbers of slab/ball selections, rotate.center and translate are meant.
enum class Units { kFractions, kAbsolute };

struct HandleSpec {
  std::string name;
  std::string label;         // "handle 'feet'" or "handle 2" (for messages)
  std::string select_where;  // position of `select`, for selection errors
  SelectionKind kind = SelectionKind::kSlab;
  int axis = 0;  // slab
  double from = 0.0, to = 0.0;
  Eigen::Vector3d ball_center = Eigen::Vector3d::Zero();  // box fractions
  double radius = 0.0;                                    // in box diagonals
  std::vector<int64_t> indices;
  std::vector<std::string> index_where;  // per inline index
  std::filesystem::path index_file;
  std::string index_file_where;
  Units units = Units::kFractions;  // slab, ball, rotate center, translate

  TargetKind target = TargetKind::kMotion;
  bool has_rotation = false;
  Eigen::Vector3d axis_vector = Eigen::Vector3d::UnitZ();
  double degrees = 0.0;
  std::optional<Eigen::Vector3d> center;  // box fractions
  bool has_translation = false;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  std::filesystem::path target_file;  // target_file = "...": per-vertex "index x y z" lines
  std::string target_file_where;
};

std::string Vec(const Eigen::Vector3d& v) { return fmt::format("({:.6g}, {:.6g}, {:.6g})", v[0], v[1], v[2]); }

// A computed point (a centroid) of a mesh of size `scale`: rounding noise far below the mesh's
// size (a centred mesh's centroid at 1e-17) prints as 0, not as a number that looks meaningful.
std::string Point(Eigen::Vector3d v, double scale) {
  for (int k = 0; k < 3; ++k) {
    if (std::abs(v[k]) <= 1e-12 * scale) v[k] = 0.0;
  }
  return Vec(v);
}

// The box, for every message about a selection: the numbers only mean something against it.
std::string DescribeBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return fmt::format("x in [{:.6g}, {:.6g}], y in [{:.6g}, {:.6g}], z in [{:.6g}, {:.6g}]", lo[0],
                     hi[0], lo[1], hi[1], lo[2], hi[2]);
}

// What a handle selects, with its kind and units; `lo`/`hi` the mesh's bounding box.
std::string DescribeSelection(const HandleSpec& spec, const Eigen::Vector3d& lo,
                              const Eigen::Vector3d& hi) {
  const bool absolute = spec.units == Units::kAbsolute;
  const std::string units =
      absolute ? fmt::format("absolute coordinates (units = \"absolute\"); the mesh's bounding box "
                             "is {}",
                             DescribeBox(lo, hi))
               : fmt::format("fractions of the bounding box {}{}", DescribeBox(lo, hi),
                             spec.kind == SelectionKind::kBall ? ", radius in box diagonals" : "");
  switch (spec.kind) {
    case SelectionKind::kSlab:
      return fmt::format("select.slab {} in [{}, {}] ({})", "xyz"[spec.axis], spec.from, spec.to,
                         units);
    case SelectionKind::kBall:
      return fmt::format("select.ball at {} of radius {} ({})", Vec(spec.ball_center),
                         spec.radius, units);
    case SelectionKind::kIndices:
      return fmt::format("select.indices ({} 0-based vertex indices)", spec.indices.size());
    case SelectionKind::kIndexFile:
      return fmt::format("select.index_file {} (0-based vertex indices)",
                         spec.index_file.string());
  }
  return "";
}

class Parser {
 public:
  Parser(std::string source, std::filesystem::path base, const ScenarioLimits& limits)
      : source_(std::move(source)), base_(std::move(base)), limits_(limits) {}

  std::string Where(const toml::source_region& region) const {
    if (region.begin.line == 0) return source_;
    return fmt::format("{}:{}:{}", source_, region.begin.line, region.begin.column);
  }
  std::string Where(const toml::node& node) const { return Where(node.source()); }

  [[noreturn]] void Fail(const std::string& where, const std::string& label,
                         std::string_view problem) const {
    if (label.empty()) throw ConfigError(fmt::format("{}: {}", where, problem));
    throw ConfigError(fmt::format("{}: {}: {}", where, label, problem));
  }

  // Rejects keys of `table` not in `valid`; `what` names the table in the message.
  void CheckKeys(const toml::table& table, std::initializer_list<std::string_view> valid,
                 const std::string& label, std::string_view what) const {
    for (const auto& [key, value] : table) {
      if (std::find(valid.begin(), valid.end(), key.str()) != valid.end()) continue;
      Fail(Where(key.source()), label,
           fmt::format("unknown key '{}' in {}; valid keys: {}", key.str(), what,
                       fmt::join(valid, ", ")));
    }
  }

  double Number(const toml::node& node, const std::string& label, std::string_view what) const {
    double value = 0.0;
    if (const auto* integer = node.as_integer()) {
      value = static_cast<double>(integer->get());
    } else if (const auto* floating = node.as_floating_point()) {
      value = floating->get();
    } else {
      Fail(Where(node), label, fmt::format("{} must be a number", what));
    }
    if (!std::isfinite(value)) {
      Fail(Where(node), label, fmt::format("{} is a non-finite number ({})", what, value));
    }
    return value;
  }

  Eigen::Vector3d Vector3(const toml::node& node, const std::string& label,
                          std::string_view what) const {
    const toml::array* array = node.as_array();
    if (!array || array->size() != 3) {
      Fail(Where(node), label, fmt::format("{} must be an array of three numbers", what));
    }
    Eigen::Vector3d vector;
    for (int d = 0; d < 3; ++d) vector[d] = Number(*array->get(d), label, what);
    return vector;
  }

  const toml::node& Required(const toml::table& table, std::string_view key,
                             const std::string& where, const std::string& label,
                             std::string_view what) const {
    const toml::node* node = table.get(key);
    if (!node) Fail(where, label, fmt::format("{} needs '{}'", what, key));
    return *node;
  }

  std::filesystem::path Resolve(const std::string& relative) const {
    std::filesystem::path path(relative);
    if (path.is_relative()) path = base_ / path;
    return path.lexically_normal();
  }

  // `units = "fractions" | "absolute"` of `table` (a handle or the top level), else `fallback`.
  Units ParseUnits(const toml::table& table, Units fallback, const std::string& label) const {
    const toml::node* node = table.get("units");
    if (!node) return fallback;
    const std::string value = node->value_or(std::string());
    if (value == "fractions") return Units::kFractions;
    if (value == "absolute") return Units::kAbsolute;
    Fail(Where(*node), label,
         "'units' must be \"fractions\" (slab/ball/center as fractions of the bounding box, "
         "radius and translate in box diagonals; the default) or \"absolute\" (mesh coordinates)");
  }

  // `units` belongs to the handle (it also applies to rotate.center and translate).
  void UnitsInsideSelection(const toml::table& selection, const std::string& label,
                            std::string_view what) const {
    if (const toml::node* units = selection.get("units")) {
      Fail(Where(*units), label,
           fmt::format("'units' is a key of the [[handle]] (or of the top level), not of {}: "
                       "write units = \"absolute\" on its own line in the handle; it applies to "
                       "the selection, rotate.center and translate",
                       what));
    }
  }

  HandleSpec ParseHandle(const toml::table& table, int number, Units default_units) const {
    HandleSpec spec;
    spec.label = fmt::format("handle {}", number);
    spec.name = spec.label;
    const std::string where = Where(table);
    if (const toml::node* name = table.get("name")) {
      if (!name->is_string()) Fail(Where(*name), spec.label, "'name' must be a string");
      spec.name = name->as_string()->get();
      spec.label = fmt::format("handle '{}'", spec.name);
    }
    CheckKeys(table, {"name", "select", "rotate", "translate", "target", "target_file", "units"},
              spec.label, "a [[handle]]");
    spec.units = ParseUnits(table, default_units, spec.label);

    // target_file = "moves.txt": the file's "index x y z" lines are the selection and the motion.
    if (const toml::node* file = table.get("target_file")) {
      if (!file->is_string()) Fail(Where(*file), spec.label, "'target_file' must be a file name");
      for (const char* other : {"select", "rotate", "translate", "target"}) {
        if (table.contains(other)) {
          Fail(Where(*table.get(other)), spec.label,
               fmt::format("target_file gives both the vertices and their targets; remove '{}'",
                           other));
        }
      }
      spec.target = TargetKind::kFile;
      spec.target_file = Resolve(file->as_string()->get());
      spec.target_file_where = Where(*file);
      spec.select_where = spec.target_file_where;
      return spec;
    }

    // Selection: exactly one of slab, ball, indices, index_file.
    const toml::node* select = table.get("select");
    if (!select) {
      Fail(where, spec.label,
           "has no selection; give exactly one of select.slab, select.ball, select.indices, "
           "select.index_file (or target_file = \"file\" with \"index x y z\" lines)");
    }
    spec.select_where = Where(*select);
    const toml::table* selection = select->as_table();
    if (!selection) {
      Fail(spec.select_where, spec.label,
           "'select' must be a table (select.slab = {...}, select.ball = {...}, "
           "select.indices = [...] or select.index_file = \"...\")");
    }
    CheckKeys(*selection, {"slab", "ball", "indices", "index_file"}, spec.label, "'select'");
    // toml++ iterates keys in sorted order; report them in the order written.
    std::vector<std::pair<toml::source_position, std::string>> written;
    for (const auto& [key, value] : *selection) {
      written.emplace_back(key.source().begin, std::string(key.str()));
    }
    std::sort(written.begin(), written.end(), [](const auto& x, const auto& y) {
      return std::pair(x.first.line, x.first.column) < std::pair(y.first.line, y.first.column);
    });
    std::vector<std::string> kinds;
    for (auto& entry : written) kinds.push_back(std::move(entry.second));
    if (kinds.size() != 1) {
      Fail(spec.select_where, spec.label,
           kinds.empty() ? std::string("'select' is empty; give exactly one selection")
                         : fmt::format("has {} selections ({}); give exactly one", kinds.size(),
                                       fmt::join(kinds, ", ")));
    }
    const std::string& kind = kinds.front();
    const toml::node& body = *selection->get(kind);
    if (kind == "slab") {
      spec.kind = SelectionKind::kSlab;
      const toml::table* slab = body.as_table();
      if (!slab) Fail(Where(body), spec.label, "select.slab must be a table {axis, from, to}");
      UnitsInsideSelection(*slab, spec.label, "select.slab");
      CheckKeys(*slab, {"axis", "from", "to"}, spec.label, "select.slab");
      const toml::node& axis = Required(*slab, "axis", Where(body), spec.label, "select.slab");
      const std::string axis_name = axis.value_or(std::string());
      if (axis_name != "x" && axis_name != "y" && axis_name != "z") {
        Fail(Where(axis), spec.label, "select.slab axis must be \"x\", \"y\" or \"z\"");
      }
      spec.axis = axis_name[0] - 'x';
      spec.from = Number(Required(*slab, "from", Where(body), spec.label, "select.slab"),
                         spec.label, "select.slab from");
      spec.to = Number(Required(*slab, "to", Where(body), spec.label, "select.slab"), spec.label,
                       "select.slab to");
      if (spec.from > spec.to) {
        Fail(Where(body), spec.label,
             fmt::format("select.slab has from = {} > to = {}", spec.from, spec.to));
      }
    } else if (kind == "ball") {
      spec.kind = SelectionKind::kBall;
      const toml::table* ball = body.as_table();
      if (!ball) Fail(Where(body), spec.label, "select.ball must be a table {center, radius}");
      UnitsInsideSelection(*ball, spec.label, "select.ball");
      CheckKeys(*ball, {"center", "radius"}, spec.label, "select.ball");
      spec.ball_center = Vector3(Required(*ball, "center", Where(body), spec.label, "select.ball"),
                                 spec.label, "select.ball center");
      spec.radius = Number(Required(*ball, "radius", Where(body), spec.label, "select.ball"),
                           spec.label, "select.ball radius");
      if (spec.radius < 0.0) {
        Fail(Where(*ball->get("radius")), spec.label, "select.ball radius must be >= 0");
      }
    } else if (kind == "indices") {
      spec.kind = SelectionKind::kIndices;
      const toml::array* indices = body.as_array();
      if (!indices) Fail(Where(body), spec.label, "select.indices must be an array of integers");
      for (const toml::node& index : *indices) {
        const auto* integer = index.as_integer();
        if (!integer) {
          Fail(Where(index), spec.label, "select.indices must hold integers (0-based indices)");
        }
        spec.indices.push_back(integer->get());
        spec.index_where.push_back(Where(index));
      }
    } else {
      spec.kind = SelectionKind::kIndexFile;
      if (!body.is_string()) Fail(Where(body), spec.label, "select.index_file must be a string");
      spec.index_file = Resolve(body.as_string()->get());
      spec.index_file_where = Where(body);
    }

    // Motion.
    if (const toml::node* target = table.get("target")) {
      if (target->value_or(std::string()) != "initial") {
        Fail(Where(*target), spec.label,
             "'target' must be \"initial\" (per-vertex targets from a file are given as "
             "target_file = \"moves.txt\")");
      }
      if (table.contains("rotate") || table.contains("translate")) {
        Fail(Where(*target), spec.label,
             "target = \"initial\" cannot be combined with rotate or translate");
      }
      spec.target = TargetKind::kInitial;
    }
    if (const toml::node* rotate = table.get("rotate")) {
      const toml::table* rotation = rotate->as_table();
      if (!rotation) {
        Fail(Where(*rotate), spec.label, "'rotate' must be a table {axis, degrees, center?}");
      }
      CheckKeys(*rotation, {"axis", "degrees", "center"}, spec.label, "'rotate'");
      spec.has_rotation = true;
      const toml::node& axis = Required(*rotation, "axis", Where(*rotate), spec.label, "'rotate'");
      spec.axis_vector = Vector3(axis, spec.label, "rotate axis");
      if (spec.axis_vector.norm() == 0.0) {
        Fail(Where(axis), spec.label, "the rotation axis is zero (it cannot be normalized)");
      }
      spec.degrees = Number(Required(*rotation, "degrees", Where(*rotate), spec.label, "'rotate'"),
                            spec.label, "rotate degrees");
      if (const toml::node* center = rotation->get("center")) {
        spec.center = Vector3(*center, spec.label, "rotate center");
      }
    }
    if (const toml::node* translate = table.get("translate")) {
      spec.has_translation = true;
      spec.translation = Vector3(*translate, spec.label, "translate");
    }
    return spec;
  }

  // Vertices `spec` selects, ascending.
  std::vector<Index> Select(const HandleSpec& spec, const Mesh& mesh,
                            const std::vector<bool>& referenced, const Eigen::Vector3d& lo,
                            const Eigen::Vector3d& extent, double diagonal) const {
    std::vector<Index> selected;
    const Index n = mesh.num_vertices();
    const bool absolute = spec.units == Units::kAbsolute;
    // Slab bounds are compared as written: fractions to fractions, coordinates to coordinates.
    auto coordinate = [&](Index v, int d) {
      if (absolute) return mesh.vertices(v, d);
      return extent[d] > 0.0 ? (mesh.vertices(v, d) - lo[d]) / extent[d] : 0.0;
    };
    switch (spec.kind) {
      case SelectionKind::kSlab:
        for (Index v = 0; v < n; ++v) {
          if (!referenced[v]) continue;
          const double f = coordinate(v, spec.axis);
          if (f >= spec.from && f <= spec.to) selected.push_back(v);
        }
        break;
      case SelectionKind::kBall: {
        const Eigen::Vector3d center =
            absolute ? spec.ball_center : Eigen::Vector3d(lo + spec.ball_center.cwiseProduct(extent));
        const double radius = absolute ? spec.radius : spec.radius * diagonal;
        for (Index v = 0; v < n; ++v) {
          if (!referenced[v]) continue;
          if ((mesh.vertices.row(v).transpose() - center).norm() <= radius) selected.push_back(v);
        }
        break;
      }
      case SelectionKind::kIndices:
        for (size_t i = 0; i < spec.indices.size(); ++i) {
          const int64_t index = spec.indices[i];
          if (index < 0 || index >= n) {
            Fail(spec.index_where[i], spec.label,
                 fmt::format("select.indices: index {} out of range (the mesh has {} vertices, "
                             "valid 0..{})",
                             index, n, n - 1));
          }
          selected.push_back(static_cast<Index>(index));
        }
        break;
      case SelectionKind::kIndexFile:
        selected = ReadIndexFile(spec, n);
        break;
    }
    std::sort(selected.begin(), selected.end());
    selected.erase(std::unique(selected.begin(), selected.end()), selected.end());
    if (selected.empty()) {
      Fail(spec.select_where, spec.label,
           fmt::format("{} matches no vertex{}", DescribeSelection(spec, lo, lo + extent),
                       spec.units == Units::kFractions &&
                               (spec.kind == SelectionKind::kSlab || spec.kind == SelectionKind::kBall)
                           ? "; for mesh coordinates write units = \"absolute\" in the handle"
                           : ""));
    }
    return selected;
  }

  std::vector<Index> ReadIndexFile(const HandleSpec& spec, Index num_vertices) const {
    const std::string file = spec.index_file.string();
    auto fail = [&](const std::string& problem) {
      throw InputError(fmt::format("{}: {}: index file {}: {}", spec.index_file_where, spec.label,
                                   file, problem));
    };
    std::string text;
    try {
      text = ReadFileMaybeXz(spec.index_file);
    } catch (const InputError& error) {
      fail(error.what());
    }
    std::vector<Index> indices;
    size_t line = 1;
    size_t position = 0;
    while (position < text.size()) {
      const char c = text[position];
      if (c == '\n') ++line;
      if (std::isspace(static_cast<unsigned char>(c))) {
        ++position;
        continue;
      }
      size_t end = position;
      while (end < text.size() && !std::isspace(static_cast<unsigned char>(text[end]))) ++end;
      const std::string_view token(text.data() + position, end - position);
      int64_t index = 0;
      const auto [stop, error] = std::from_chars(token.data(), token.data() + token.size(), index);
      if (error != std::errc() || stop != token.data() + token.size()) {
        fail(fmt::format("line {}: '{}' is not a vertex index", line,
                         token.substr(0, std::min<size_t>(token.size(), 40))));
      }
      if (index < 0 || index >= num_vertices) {
        fail(fmt::format("line {}: index {} out of range (the mesh has {} vertices, valid 0..{})",
                         line, index, num_vertices, num_vertices - 1));
      }
      indices.push_back(static_cast<Index>(index));
      position = end;
    }
    return indices;
  }

  // text of a file the scenario names; read errors become InputErrors naming `where` and `what`.
  static std::string ReadNamedText(const std::filesystem::path& path, const std::string& where,
                                   std::string_view what) {
    std::error_code error;
    if (!std::filesystem::exists(path, error)) {
      throw InputError(fmt::format("{}: {} file {} not found", where, what, path.string()));
    }
    try {
      return ReadFileMaybeXz(path);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: {}: {}", where, what, e.what()));
    }
  }

  // target_file: lines "index x y z" (absolute coordinates; `#` comments, blank lines skipped).
  // Fills the handle's vertices (ascending) and targets.
  void ReadTargetFile(const HandleSpec& spec, Index num_vertices, ScenarioHandle& handle) const {
    const std::string file = spec.target_file.string();
    const std::string text = ReadNamedText(spec.target_file, spec.target_file_where, "target_file");
    io_internal::LineReader lines(text);
    auto fail = [&](const std::string& problem) {
      throw InputError(fmt::format("{}: {}: target file {}:{}: {}", spec.target_file_where,
                                   spec.label, file, lines.line_number(), problem));
    };
    std::vector<std::pair<Index, Eigen::Vector3d>> entries;
    std::vector<size_t> line_of(static_cast<size_t>(num_vertices), 0);
    std::string_view line;
    while (lines.NextContent(line)) {
      std::string_view tokens[5];
      int count = 0;
      for (std::string_view token; !(token = io_internal::NextToken(line)).empty();) {
        if (count < 5) tokens[count] = token;
        ++count;
      }
      if (count != 4) {
        fail(fmt::format("expected 'index x y z' (4 values), found {} value{}", count,
                         count == 1 ? "" : "s"));
      }
      int64_t index = 0;
      if (!io_internal::ParseInteger(tokens[0], index)) {
        fail(fmt::format("{} is not a vertex index", io_internal::Quote(tokens[0])));
      }
      if (index < 0 || index >= num_vertices) {
        fail(fmt::format("index {} out of range (the mesh has {} vertices, valid 0..{})", index,
                         num_vertices, num_vertices - 1));
      }
      if (line_of[index] != 0) {
        fail(fmt::format("vertex {} has a target already (line {})", index, line_of[index]));
      }
      line_of[index] = lines.line_number();
      Eigen::Vector3d target;
      for (int d = 0; d < 3; ++d) {
        if (!io_internal::ParseDouble(tokens[d + 1], target[d])) {
          fail(fmt::format("{} is not a number", io_internal::Quote(tokens[d + 1])));
        }
        if (!std::isfinite(target[d])) {
          fail(fmt::format("{} is not a finite number", io_internal::Quote(tokens[d + 1])));
        }
      }
      entries.emplace_back(static_cast<Index>(index), target);
    }
    if (entries.empty()) {
      throw InputError(fmt::format("{}: {}: target file {} has no 'index x y z' line",
                                   spec.target_file_where, spec.label, file));
    }
    std::sort(entries.begin(), entries.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    handle.vertices.clear();
    handle.targets.resize(static_cast<Index>(entries.size()), 3);
    for (size_t i = 0; i < entries.size(); ++i) {
      handle.vertices.push_back(entries[i].first);
      handle.targets.row(static_cast<Index>(i)) = entries[i].second.transpose();
    }
  }

  // The deformation benchmark of Botsch & Sorkine's survey: `selection` (.sel: one label per
  // vertex, 0 fixed, 1 free, 2 handle) and `deformation` (.def: the handle's 4x4 transform,
  // row-major, applied to (x, y, z, 1)). Makes the handles "fixed" (if any 0) and "handle".
  void AddBenchmarkHandles(const std::filesystem::path& selection_file,
                           const std::string& selection_where,
                           const std::filesystem::path& deformation_file,
                           const std::string& deformation_where, Scenario& scenario) const {
    const Index n = scenario.mesh.num_vertices();
    const std::string sel_text = ReadNamedText(selection_file, selection_where, "selection");
    io_internal::LineReader lines(sel_text);
    auto fail_sel = [&](const std::string& problem) {
      throw InputError(fmt::format("{}: selection file {}:{}: {}", selection_where,
                                   selection_file.string(), lines.line_number(), problem));
    };
    ScenarioHandle fixed, moved;
    fixed.name = "fixed";
    moved.name = "handle";
    Index count = 0;
    std::string_view line;
    while (lines.NextContent(line)) {
      for (std::string_view token; !(token = io_internal::NextToken(line)).empty();) {
        int64_t label = 0;
        if (!io_internal::ParseInteger(token, label) || label < 0 || label > 2) {
          fail_sel(fmt::format("{} is not a vertex label (0 fixed, 1 free, 2 handle)",
                               io_internal::Quote(token)));
        }
        if (count >= n) {
          fail_sel(fmt::format("more labels than the mesh's {} vertices (one label per vertex)",
                               n));
        }
        if (label == 0) fixed.vertices.push_back(count);
        if (label == 2) moved.vertices.push_back(count);
        ++count;
      }
    }
    if (count != n) {
      throw InputError(fmt::format("{}: selection file {} has {} labels, but the mesh has {} "
                                   "vertices{} (one label per vertex: 0 fixed, 1 free, 2 handle)",
                                   selection_where, selection_file.string(), count, n,
                                   scenario.mesh_source.empty() ? "" : " (" + scenario.mesh_source + ")"));
    }
    if (moved.vertices.empty()) {
      throw InputError(fmt::format("{}: selection file {} marks no vertex as handle (label 2)",
                                   selection_where, selection_file.string()));
    }

    const std::string def_text = ReadNamedText(deformation_file, deformation_where, "deformation");
    io_internal::TokenCursor cursor(def_text, 1, /*skip_comments=*/true);
    Eigen::Matrix4d transform;
    for (int k = 0; k < 17; ++k) {
      const std::string_view token = cursor.Next();
      auto fail_def = [&](const std::string& problem) {
        throw InputError(fmt::format("{}: deformation file {}:{}: {}", deformation_where,
                                     deformation_file.string(), cursor.line(), problem));
      };
      if (k == 16) {
        if (!token.empty()) fail_def("more than the 16 numbers of a 4x4 matrix");
        break;
      }
      if (token.empty()) {
        fail_def(fmt::format("ends after {} of the 16 numbers of the 4x4 matrix (row-major)", k));
      }
      double value = 0.0;
      if (!io_internal::ParseDouble(token, value) || !std::isfinite(value)) {
        fail_def(fmt::format("{} is not a finite number", io_internal::Quote(token)));
      }
      transform(k / 4, k % 4) = value;
    }
    if (transform.row(3) != Eigen::RowVector4d(0.0, 0.0, 0.0, 1.0)) {
      throw InputError(fmt::format("{}: deformation file {}: the last row is ({}, {}, {}, {}), "
                                   "not (0, 0, 0, 1): not an affine transform",
                                   deformation_where, deformation_file.string(), transform(3, 0),
                                   transform(3, 1), transform(3, 2), transform(3, 3)));
    }
    const Eigen::Matrix3d linear = transform.topLeftCorner<3, 3>();
    const Eigen::Vector3d shift = transform.topRightCorner<3, 1>();
    moved.targets.resize(static_cast<Index>(moved.vertices.size()), 3);
    for (size_t i = 0; i < moved.vertices.size(); ++i) {
      const Eigen::Vector3d p = scenario.mesh.vertices.row(moved.vertices[i]).transpose();
      moved.targets.row(static_cast<Index>(i)) = (linear * p + shift).transpose();
    }
    moved.selection = fmt::format("label 2 of {}", selection_file.filename().string());
    moved.motion = fmt::format("4x4 transform from {}: linear part [{:.6g} {:.6g} {:.6g}; {:.6g} "
                               "{:.6g} {:.6g}; {:.6g} {:.6g} {:.6g}], translation {}",
                               deformation_file.filename().string(), linear(0, 0), linear(0, 1),
                               linear(0, 2), linear(1, 0), linear(1, 1), linear(1, 2),
                               linear(2, 0), linear(2, 1), linear(2, 2), Vec(shift));
    if (!fixed.vertices.empty()) {
      fixed.targets.resize(static_cast<Index>(fixed.vertices.size()), 3);
      for (size_t i = 0; i < fixed.vertices.size(); ++i) {
        fixed.targets.row(static_cast<Index>(i)) = scenario.mesh.vertices.row(fixed.vertices[i]);
      }
      fixed.selection = fmt::format("label 0 of {}", selection_file.filename().string());
      fixed.motion = "fixed (held at rest positions)";
      scenario.handles.push_back(std::move(fixed));
    }
    scenario.handles.push_back(std::move(moved));
  }

  Scenario Parse(std::string_view toml_text) const {
    toml::table root;
    try {
      root = toml::parse(toml_text, source_);
    } catch (const toml::parse_error& error) {
      throw ConfigError(fmt::format("{}: TOML syntax error: {}", Where(error.source()),
                                    error.description()));
    }
    CheckKeys(root,
              {"mesh", "refine", "initial", "planar", "handle", "units", "selection",
               "deformation"},
              "", "the top level");
    const Units default_units = ParseUnits(root, Units::kFractions, "");
    // selection = "x.sel" with deformation = "x.def": the deformation benchmark's handles.
    std::optional<std::filesystem::path> selection_file, deformation_file;
    std::string selection_where, deformation_where;
    auto file_key = [&](std::string_view key, std::optional<std::filesystem::path>& file,
                        std::string& where) {
      if (const toml::node* node = root.get(key)) {
        if (!node->is_string()) Fail(Where(*node), "", fmt::format("'{}' must be a file name", key));
        file = Resolve(node->as_string()->get());
        where = Where(*node);
      }
    };
    file_key("selection", selection_file, selection_where);
    file_key("deformation", deformation_file, deformation_where);
    if (selection_file.has_value() != deformation_file.has_value()) {
      Fail(selection_file ? selection_where : deformation_where, "",
           "selection = \"x.sel\" and deformation = \"x.def\" come together (the deformation "
           "benchmark's per-vertex labels and the handle's 4x4 transform)");
    }

    // Everything in the text first (see the top of this file).
    const toml::node* mesh_node = root.get("mesh");
    if (!mesh_node) {
      Fail(source_, "",
           "no 'mesh' given (mesh = \"file.obj\" or mesh = { builtin = \"cylinder\", ... })");
    }
    int refine = 0;
    if (const toml::node* node = root.get("refine")) {
      const auto* integer = node->as_integer();
      if (!integer || integer->get() < 0 || integer->get() > 10) {
        Fail(Where(*node), "", "'refine' must be an integer in 0..10 (Loop subdivision rounds)");
      }
      refine = static_cast<int>(integer->get());
    }
    std::optional<std::filesystem::path> initial_file;
    std::string initial_where;
    if (const toml::node* node = root.get("initial")) {
      if (!node->is_string()) Fail(Where(*node), "", "'initial' must be a file name (string)");
      initial_file = Resolve(node->as_string()->get());
      initial_where = Where(*node);
    }
    std::optional<bool> planar;
    std::string planar_where;
    if (const toml::node* node = root.get("planar")) {
      if (!node->is_boolean()) Fail(Where(*node), "", "'planar' must be true or false");
      planar = node->as_boolean()->get();
      planar_where = Where(*node);
    }
    std::vector<HandleSpec> specs;
    if (const toml::node* node = root.get("handle")) {
      const toml::array* handles = node->as_array();
      if (!handles) Fail(Where(*node), "", "'handle' must be an array of tables ([[handle]])");
      int number = 0;
      for (const toml::node& entry : *handles) {
        ++number;
        const toml::table* table = entry.as_table();
        if (!table) Fail(Where(entry), fmt::format("handle {}", number), "must be a table");
        specs.push_back(ParseHandle(*table, number, default_units));
        if (specs.back().target == TargetKind::kInitial && !initial_file) {
          Fail(Where(*table->get("target")), specs.back().label,
               "target = \"initial\" needs a top-level initial = \"file\"");
        }
      }
    }
    if (text_only_) return Scenario{};

    Scenario scenario;
    const toml::node* refine_node = root.get("refine");
    if (const toml::table* table = mesh_node->as_table()) {
      if (const toml::node* vertices = table->get("vertices")) {
        const auto* count = vertices->as_integer();
        if (count && count->get() > limits_.max_builtin_vertices) {
          Fail(Where(*vertices), "",
               fmt::format("mesh.vertices = {} exceeds the limit of {} vertices", count->get(),
                           limits_.max_builtin_vertices));
        }
      }
      // ConfigNode carries the line numbers and the unknown-key check into MakeBuiltinMesh.
      const ConfigNode parameters = ConfigNode::Parse(toml_text, source_).Child("mesh");
      if (const toml::node* source = table->get("tetrahedralize")) {
        TetrahedralizeSurface(*mesh_node, *source, parameters, refine, refine_node, scenario);
      } else {
        scenario.mesh = MakeBuiltinMesh(parameters);
        scenario.mesh_source = DescribeBuiltin(*table);
        Refine(scenario, refine, refine_node);
      }
    } else if (const auto* name = mesh_node->as_string()) {
      const std::filesystem::path path = Resolve(name->get());
      scenario.mesh_source = path.string();
      scenario.mesh = LoadMeshFile(path, Where(*mesh_node), "mesh", &scenario.notes);
      Refine(scenario, refine, refine_node);
    } else {
      Fail(Where(*mesh_node), "",
           "'mesh' must be a file name, a table { builtin = \"cylinder\", ... } or a table "
           "{ tetrahedralize = \"surface file\" or { builtin = ... }, ... }");
    }
    if (initial_file) {
      Positions initial = ReadNamedFile(*initial_file, initial_where, "initial",
                                        [](const auto& path) { return ReadMeshVertices(path); });
      if (initial.rows() != scenario.mesh.num_vertices()) {
        throw InputError(fmt::format("{}: initial configuration {} has {} vertices, but the mesh "
                                     "has {}{} (same count and order needed)",
                                     initial_where, initial_file->string(), initial.rows(),
                                     scenario.mesh.num_vertices(),
                                     refine > 0 ? " after refine" : ""));
      }
      scenario.initial = std::move(initial);
    }

    // Box of the referenced vertices (see the top of this file).
    const Mesh& mesh = scenario.mesh;
    const std::vector<bool> referenced = ReferencedVertices(mesh);
    const auto [box_min, box_max] = SelectionBox(mesh);
    const Eigen::Vector3d lo = box_min, hi = box_max;  // used in lambdas below
    const Eigen::Vector3d extent = hi - lo;
    const double diagonal = BoundingBoxDiagonal(mesh);
    scenario.box_min = lo;
    scenario.box_max = hi;

    if (selection_file) {
      AddBenchmarkHandles(*selection_file, selection_where, *deformation_file, deformation_where,
                          scenario);
    }
    for (const HandleSpec& spec : specs) {
      ScenarioHandle handle;
      handle.name = spec.name;
      if (spec.target == TargetKind::kFile) {
        ReadTargetFile(spec, mesh.num_vertices(), handle);
        handle.selection = fmt::format("the indices of target_file {}", spec.target_file.string());
        handle.motion = fmt::format("per-vertex targets from {} (absolute coordinates)",
                                    spec.target_file.string());
        scenario.handles.push_back(std::move(handle));
        continue;
      }
      handle.vertices = Select(spec, mesh, referenced, lo, extent, diagonal);
      handle.selection = DescribeSelection(spec, lo, hi);
      const Index count = static_cast<Index>(handle.vertices.size());
      handle.targets.resize(count, 3);
      if (spec.target == TargetKind::kInitial) {
        for (Index i = 0; i < count; ++i) {
          handle.targets.row(i) = scenario.initial->row(handle.vertices[i]);
        }
        handle.motion = "held at its positions in the initial configuration";
      } else {
        const bool absolute = spec.units == Units::kAbsolute;
        Eigen::Vector3d center = Eigen::Vector3d::Zero();
        if (spec.center) {
          center = absolute ? *spec.center : Eigen::Vector3d(lo + spec.center->cwiseProduct(extent));
        } else {
          for (const Index v : handle.vertices) center += mesh.vertices.row(v).transpose();
          center /= static_cast<double>(count);
        }
        const Eigen::Matrix3d rotation =
            Eigen::AngleAxisd(spec.degrees * std::numbers::pi / 180.0,
                              spec.axis_vector.normalized())
                .toRotationMatrix();
        const Eigen::Vector3d shift = absolute ? spec.translation : spec.translation * diagonal;
        for (Index i = 0; i < count; ++i) {
          const Eigen::Vector3d p = mesh.vertices.row(handle.vertices[i]).transpose();
          // Without a rotation, p + t*D exactly (no round trip through the centre), so a fixed
          // handle holds its vertices at bit-identical rest positions.
          const Eigen::Vector3d target =
              spec.has_rotation ? Eigen::Vector3d(center + rotation * (p - center) + shift)
                                : Eigen::Vector3d(p + shift);
          handle.targets.row(i) = target.transpose();
        }
        std::vector<std::string> parts;
        if (spec.has_rotation) {
          parts.push_back(fmt::format("rotate {}° about {} through {}{}", spec.degrees,
                                      Vec(spec.axis_vector.normalized()), Point(center, diagonal),
                                      spec.center ? "" : " (the handle's centroid)"));
        }
        if (spec.has_translation) {
          parts.push_back(absolute ? fmt::format("translate {}", Vec(shift))
                                   : fmt::format("translate {} (= {} box diagonals)", Vec(shift),
                                                 Vec(spec.translation)));
        }
        handle.motion = parts.empty() ? std::string("fixed (held at rest positions)")
                                      : fmt::format("{}", fmt::join(parts, ", then "));
      }
      scenario.handles.push_back(std::move(handle));
    }
    DecidePlanar(scenario, planar, planar_where);
    return scenario;
  }

 private:
  // read(path) of a file named by the scenario, with errors prefixed by where it was named and
  // the key (`what`: "mesh", "initial", "mesh.tetrahedralize").
  template <class Read>
  std::invoke_result_t<Read, const std::filesystem::path&> ReadNamedFile(
      const std::filesystem::path& path, const std::string& where, std::string_view what,
      Read read) const {
    std::error_code error;
    if (!std::filesystem::exists(path, error)) {
      throw InputError(fmt::format("{}: {} file {} not found", where, what, path.string()));
    }
    try {
      return read(path);
    } catch (const InputError& error) {
      throw InputError(fmt::format("{}: {}: {}", where, what, error.what()));
    }
  }

  Mesh LoadMeshFile(const std::filesystem::path& path, const std::string& where,
                    std::string_view what, std::vector<std::string>* notes) const {
    return ReadNamedFile(path, where, what, [&](const auto& file) { return ReadMesh(file, notes); });
  }

  static std::string DescribeBuiltin(const toml::table& table) {
    std::string description = "builtin";
    for (const auto& [key, value] : table) {
      std::ostringstream text;
      value.visit([&](const auto& v) { text << v; });
      description += fmt::format(" {}={}", key.str(), text.str());
    }
    return description;
  }

  // `refine` rounds of Loop subdivision of the scenario's (triangle) mesh.
  void Refine(Scenario& scenario, int refine, const toml::node* refine_node) const {
    if (refine == 0) return;
    if (scenario.mesh.kind() == ElementKind::kTetrahedron) {
      Fail(Where(*refine_node), "",
           fmt::format("refine (Loop subdivision) applies to triangle meshes, but {} has "
                       "tetrahedra (to refine a surface before filling it, use mesh = "
                       "{{ tetrahedralize = ... }})",
                       scenario.mesh_source));
    }
    const double growth = std::pow(4.0, refine);
    if (static_cast<double>(scenario.mesh.num_elements()) * growth >
        static_cast<double>(limits_.max_elements)) {
      Fail(Where(*refine_node), "",
           fmt::format("refine = {} would make more than {} triangles from {}", refine,
                       limits_.max_elements, scenario.mesh.num_elements()));
    }
    try {
      std::string note;
      scenario.mesh = LoopSubdivide(scenario.mesh, refine, &note);
      if (!note.empty()) scenario.notes.push_back(std::move(note));
    } catch (const InputError& error) {
      throw InputError(fmt::format("{}: refine = {} of mesh {}: {}", Where(*refine_node), refine,
                                   scenario.mesh_source, error.what()));
    }
  }

  // mesh = { tetrahedralize = "surface file" | { builtin = ... }, max_volume = ..., ... }: the
  // surface (after `refine`) filled with tetrahedra by TetGen, its vertices first and unchanged.
  void TetrahedralizeSurface(const toml::node& mesh_node, const toml::node& source,
                             const ConfigNode& parameters, int refine,
                             const toml::node* refine_node, Scenario& scenario) const {
    const std::string where = Where(source);
    Scenario surface;
    if (source.is_string()) {
      const std::filesystem::path path = Resolve(parameters.Get(
          "tetrahedralize", std::string(),
          "surface to fill with tetrahedra: a mesh file, or a built-in table { builtin = ... }"));
      surface.mesh_source = path.string();
      surface.mesh = LoadMeshFile(path, where, "mesh.tetrahedralize", nullptr);
    } else if (const toml::table* table = source.as_table()) {
      surface.mesh = MakeBuiltinMesh(parameters.Child("tetrahedralize"));
      surface.mesh_source = DescribeBuiltin(*table);
    } else {
      Fail(where, "", "mesh.tetrahedralize must be a surface file name or a built-in mesh table "
                      "{ builtin = \"cylinder\", ... }");
    }
    TetrahedralizeOptions options;
    options.max_volume = parameters.Get(
        "max_volume", options.max_volume,
        "largest tetrahedron volume as a fraction of the enclosed volume (0: no bound)");
    options.max_radius_edge_ratio = parameters.Get(
        "max_radius_edge_ratio", options.max_radius_edge_ratio,
        "TetGen quality bound: circumradius / shortest edge (0: no quality refinement)");
    options.min_dihedral_angle = parameters.Get(
        "min_dihedral_angle", options.min_dihedral_angle,
        "TetGen quality bound: smallest dihedral angle in degrees (0: TetGen's default)");
    parameters.RejectUnknownKeys();
    if (const std::string problem = CheckTetrahedralizeOptions(options); !problem.empty()) {
      Fail(Where(mesh_node), "", problem);
    }
    if (surface.mesh.kind() == ElementKind::kTetrahedron) {
      throw InputError(fmt::format("{}: mesh.tetrahedralize: {} has tetrahedra already; give a "
                                   "triangle surface (or name the tetrahedral file as mesh)",
                                   where, surface.mesh_source));
    }
    Refine(surface, refine, refine_node);
    scenario.mesh = Tetrahedralize(
        surface.mesh, options,
        fmt::format("{}: tetrahedralize {}", where, surface.mesh_source));
    scenario.mesh_source = fmt::format(
        "tetrahedralized {}{} (max_volume={}, max_radius_edge_ratio={}, min_dihedral_angle={})",
        surface.mesh_source, refine > 0 ? fmt::format(" refined {}x", refine) : "",
        options.max_volume, options.max_radius_edge_ratio, options.min_dihedral_angle);
    scenario.notes.push_back(fmt::format(
        "tetrahedralize: {} surface vertices (indices 0..{}, unchanged) and {} interior Steiner "
        "points, {} tetrahedra",
        surface.mesh.num_vertices(), surface.mesh.num_vertices() - 1,
        scenario.mesh.num_vertices() - surface.mesh.num_vertices(), scenario.mesh.num_elements()));
  }

  std::string source_;
  std::filesystem::path base_;
  ScenarioLimits limits_;

 public:
  bool text_only_ = false;  // CheckScenarioText: stop before reading any file
};

}  // namespace

namespace {

[[noreturn]] void FailAt(const std::string& where, std::string_view problem) {
  throw ConfigError(fmt::format("{}: {}", where, problem));
}

}  // namespace

// Sets scenario.mesh.planar: from `planar = true/false`, else automatically (see docs/input.md):
// a triangle mesh whose vertices, handle targets and initial positions all have z = 0.
void DecidePlanar(Scenario& scenario, std::optional<bool> setting,
                  const std::string& where) {
  Mesh& mesh = scenario.mesh;
  mesh.planar = false;
  if (setting == false) return;
  const bool triangles = mesh.kind() == ElementKind::kTriangle;
  if (setting == true && !triangles) {
    FailAt(where, "planar = true needs a triangle mesh, but the mesh has tetrahedra");
  }
  if (!triangles) return;
  // The first vertex, handle target or initial position off the plane, described; "" if none.
  std::string off_plane;
  for (Index v = 0; v < mesh.num_vertices() && off_plane.empty(); ++v) {
    if (mesh.vertices(v, 2) != 0.0) {
      off_plane = fmt::format("vertex {} has z = {}", v, mesh.vertices(v, 2));
    }
  }
  for (const ScenarioHandle& handle : scenario.handles) {
    for (Index i = 0; i < handle.targets.rows() && off_plane.empty(); ++i) {
      if (handle.targets(i, 2) != 0.0) {
        off_plane = fmt::format("handle '{}' moves vertex {} to z = {}", handle.name,
                                handle.vertices[i], handle.targets(i, 2));
      }
    }
  }
  if (scenario.initial) {
    for (Index v = 0; v < scenario.initial->rows() && off_plane.empty(); ++v) {
      if ((*scenario.initial)(v, 2) != 0.0) {
        off_plane = fmt::format("the initial configuration has vertex {} at z = {}", v,
                                (*scenario.initial)(v, 2));
      }
    }
  }
  if (setting == true) {
    if (!off_plane.empty()) {
      FailAt(where, fmt::format("planar = true, but {} (a planar mesh and its motion stay "
                                  "in the plane z = 0)",
                                  off_plane));
    }
    mesh.planar = true;
    return;
  }
  if (off_plane.empty()) {
    mesh.planar = true;
    scenario.notes.push_back("planar: every vertex, handle target and initial position has "
                             "z = 0, so the mesh is deformed in the plane (planar = false "
                             "deforms it as a surface)");
  } else if (off_plane.rfind("vertex", 0) != 0) {
    scenario.notes.push_back(fmt::format("not planar although the mesh is flat (z = 0): {}",
                                         off_plane));
  }
}

Constraints Scenario::MergedConstraints() const {
  return MergeHandles(mesh.num_vertices(), handles);
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> SelectionBox(const Mesh& mesh) {
  const std::vector<bool> referenced = ReferencedVertices(mesh);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (!referenced[v]) continue;
    lo = lo.cwiseMin(mesh.vertices.row(v).transpose());
    hi = hi.cwiseMax(mesh.vertices.row(v).transpose());
  }
  return {lo, hi};
}

Constraints MergeHandles(Index n, const std::vector<ScenarioHandle>& handles) {
  // For each vertex, the first handle (and row) that selects it.
  std::vector<std::pair<int, Index>> owner(n, {-1, 0});
  for (size_t h = 0; h < handles.size(); ++h) {
    const ScenarioHandle& handle = handles[h];
    for (size_t i = 0; i < handle.vertices.size(); ++i) {
      const Index v = handle.vertices[i];
      HARAP_CHECK(v >= 0 && v < n, "handle '{}' selects vertex {} of {}", handle.name, v, n);
      if (owner[v].first < 0) owner[v] = {static_cast<int>(h), static_cast<Index>(i)};
    }
  }
  Constraints constraints;
  for (Index v = 0; v < n; ++v) {
    if (owner[v].first >= 0) constraints.indices.push_back(v);
  }
  constraints.targets.resize(static_cast<Index>(constraints.indices.size()), 3);
  for (size_t k = 0; k < constraints.indices.size(); ++k) {
    const auto [h, row] = owner[constraints.indices[k]];
    constraints.targets.row(static_cast<Index>(k)) = handles[h].targets.row(row);
  }
  return constraints;
}

Scenario ParseScenario(std::string_view toml_text, const std::string& source_name,
                       const std::filesystem::path& base_directory,
                       const ScenarioLimits& limits) {
  return Parser(source_name, base_directory, limits).Parse(toml_text);
}

void CheckScenarioText(const std::filesystem::path& file) {
  std::error_code error;
  if (!std::filesystem::exists(file, error)) {
    throw InputError(fmt::format("{}: scenario file not found", file.string()));
  }
  Parser parser(file.string(), file.parent_path(), {});
  parser.text_only_ = true;
  parser.Parse(ReadFileMaybeXz(file));
}

Scenario LoadScenario(const std::filesystem::path& file) {
  std::error_code error;
  if (!std::filesystem::exists(file, error)) {
    throw InputError(fmt::format("{}: scenario file not found", file.string()));
  }
  // Refuses directories and devices with a message (an ifstream would read them as empty or
  // forever); `.toml.xz` works as for meshes.
  const std::string text = ReadFileMaybeXz(file);
  Scenario scenario = ParseScenario(text, file.string(), file.parent_path());
  scenario.file = file;
  return scenario;
}


Scenario ScenarioFromArrays(Mesh mesh, const std::vector<Index>& handle_vertices,
                            const Positions& targets, std::optional<Positions> initial,
                            std::optional<bool> planar, const std::string& source) {
  mesh.planar = false;
  ValidateMesh(mesh, source);
  Scenario scenario;
  scenario.mesh_source = source;
  // Rest tetrahedra's corner order carries no meaning; the energies need positive volumes, as
  // for tetrahedra read from files (BuildTetrahedralMesh).
  const TetrahedronOrientation orientation = OrientTetrahedra(mesh);
  if (!orientation.degenerate.empty()) {
    const Index t = orientation.degenerate.front();
    throw InputError(fmt::format(
        "{}: tetrahedron {} (corners {}) is flat (zero volume){}; flat tetrahedra have no "
        "orientation and no finite cotangent weights",
        source, t, fmt::join(mesh.elements.row(t), " "),
        orientation.degenerate.size() > 1
            ? fmt::format(", one of {} flat tetrahedra", orientation.degenerate.size())
            : std::string()));
  }
  if (orientation.reoriented > 0) {
    scenario.notes.push_back(fmt::format("{}: {} of {} tetrahedra had negative signed volume "
                                         "and were reoriented (last two corners swapped)",
                                         source, orientation.reoriented, mesh.num_elements()));
  }
  const Index n = mesh.num_vertices();
  if (targets.rows() != static_cast<Index>(handle_vertices.size())) {
    throw InputError(fmt::format("{}: {} handle vertices but {} target rows (one target per "
                                 "handle vertex)",
                                 source, handle_vertices.size(), targets.rows()));
  }
  std::vector<Index> first_row(n, -1);
  for (size_t k = 0; k < handle_vertices.size(); ++k) {
    const Index v = handle_vertices[k];
    if (v < 0 || v >= n) {
      throw InputError(fmt::format("{}: handle vertex {} (row {}) is out of range; the mesh has "
                                   "{} vertices (valid: 0..{})",
                                   source, v, k, n, n - 1));
    }
    if (first_row[v] >= 0) {
      throw InputError(fmt::format("{}: handle vertex {} appears twice (rows {} and {})", source,
                                   v, first_row[v], k));
    }
    first_row[v] = static_cast<Index>(k);
    if (!targets.row(static_cast<Index>(k)).allFinite()) {
      throw InputError(fmt::format("{}: the target of handle vertex {} (row {}) is not finite "
                                   "({}, {}, {})",
                                   source, v, k, targets(k, 0), targets(k, 1), targets(k, 2)));
    }
  }
  if (initial) {
    if (initial->rows() != n) {
      throw InputError(fmt::format("{}: the initial positions have {} rows, the mesh {} vertices",
                                   source, initial->rows(), n));
    }
    for (Index v = 0; v < n; ++v) {
      if (!initial->row(v).allFinite()) {
        throw InputError(fmt::format("{}: initial position of vertex {} is not finite ({}, {}, {})",
                                     source, v, (*initial)(v, 0), (*initial)(v, 1),
                                     (*initial)(v, 2)));
      }
    }
  }
  scenario.mesh = std::move(mesh);
  ScenarioHandle handle;
  handle.name = "handles";
  // ScenarioHandle keeps its vertices ascending (the selections' order).
  std::vector<Index> order(handle_vertices.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = static_cast<Index>(k);
  std::sort(order.begin(), order.end(),
            [&](Index a, Index b) { return handle_vertices[a] < handle_vertices[b]; });
  handle.targets.resize(static_cast<Index>(order.size()), 3);
  for (size_t k = 0; k < order.size(); ++k) {
    handle.vertices.push_back(handle_vertices[order[k]]);
    handle.targets.row(static_cast<Index>(k)) = targets.row(order[k]);
  }
  if (!handle.vertices.empty()) scenario.handles.push_back(std::move(handle));
  scenario.initial = std::move(initial);
  DecidePlanar(scenario, planar, source);
  return scenario;
}

}  // namespace harap
