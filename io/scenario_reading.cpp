// SPDX-License-Identifier: MIT
//
// Scenario text (shared/scenarios/FORMAT.md, harap's additions in docs/input.md). Decisions the
// format leaves open:
//   - Everything written in the scenario text (unknown keys, bad values, selections that match
//     nothing) is a ConfigError; problems with the files it names (missing, unreadable, bad
//     index files) are InputErrors. Every message starts with "file:line:column".
//   - The whole text is checked before the mesh is read, so a typo does not cost a mesh load
//     (the keys of a `mesh` table are the exception: they are checked when it is built).
//   - `units = "absolute"` (per handle, or at the top level for every handle) reads slab bounds,
//     ball centre and radius, rotate.center and translate in mesh coordinates instead of box
//     fractions and diagonals.
#include "io/scenario_reading.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include "framework/config.h"
#include "framework/error.h"
#include "framework/toml_reading.h"

namespace harap::io_internal {

namespace {

Eigen::Vector3d Vector3(const TomlReader& toml, const toml::node& node, std::string_view what) {
  const std::array<double, 3> v = toml.Vector3(node, what);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

// "builtin builtin=cylinder vertices=100": a built-in mesh table for reports.
std::string DescribeBuiltin(const toml::table& table) {
  std::string description = "builtin";
  for (const auto& [key, value] : table) {
    std::ostringstream text;
    value.visit([&](const auto& v) { text << v; });
    description += fmt::format(" {}={}", key.str(), text.str());
  }
  return description;
}

class ScenarioTextReader {
 public:
  ScenarioTextReader(std::string source, std::filesystem::path base, const ScenarioLimits& limits)
      : toml_(std::move(source)), base_(std::move(base)), limits_(limits) {}

  ScenarioDescription Read(std::string_view toml_text) const {
    const toml::table root = toml_.Parse(toml_text);
    toml_.CheckKeys(root,
                    {"mesh", "refine", "initial", "planar", "handle", "stiffness", "units",
                     "selection", "deformation"},
                    "the top level");
    ScenarioDescription description;
    const Units default_units = ParseUnits(toml_, root, Units::kFractions);
    // selection = "x.sel" with deformation = "x.def": the deformation benchmark's handles.
    std::optional<std::filesystem::path> selection_file, deformation_file;
    std::string selection_where, deformation_where;
    auto file_key = [&](std::string_view key, std::optional<std::filesystem::path>& file,
                        std::string& where) {
      if (const toml::node* node = root.get(key)) {
        if (!node->is_string()) toml_.Fail(*node, fmt::format("'{}' must be a file name", key));
        file = Resolve(node->as_string()->get());
        where = toml_.Where(*node);
      }
    };
    file_key("selection", selection_file, selection_where);
    file_key("deformation", deformation_file, deformation_where);
    if (selection_file.has_value() != deformation_file.has_value()) {
      toml_.Fail(selection_file ? selection_where : deformation_where,
                 "selection = \"x.sel\" and deformation = \"x.def\" come together (the "
                 "deformation benchmark's per-vertex labels and the handle's 4x4 transform)");
    }
    if (selection_file) {
      description.benchmark = BenchmarkHandlesSpec{*selection_file, selection_where,
                                                   *deformation_file, deformation_where};
    }
    description.mesh = ReadMeshSpec(root, toml_text);
    if (const toml::node* node = root.get("planar")) {
      if (!node->is_boolean()) toml_.Fail(*node, "'planar' must be true or false");
      description.planar = node->as_boolean()->get();
      description.planar_where = toml_.Where(*node);
    }
    ForEachTable(root, "handle", [&](const toml::table& table, int number) {
      description.handles.push_back(ParseHandle(table, number, default_units));
      if (description.handles.back().target == TargetKind::kInitial && !description.mesh.initial) {
        toml_.In(description.handles.back().label)
            .Fail(*table.get("target"),
                  "target = \"initial\" needs a top-level initial = \"file\"");
      }
    });
    ForEachTable(root, "stiffness", [&](const toml::table& table, int number) {
      description.stiffness.push_back(ParseStiffness(table, number, default_units));
    });
    return description;
  }

  // Calls parse(table, number) for each table of the array of tables `key` ([[key]]), numbered
  // from 1; anything else under `key` is an error naming it.
  template <class Parse>
  void ForEachTable(const toml::table& root, std::string_view key, Parse&& parse) const {
    const toml::node* node = root.get(key);
    if (!node) return;
    const toml::array* entries = node->as_array();
    if (!entries) {
      toml_.Fail(*node, fmt::format("'{}' must be an array of tables ([[{}]])", key, key));
    }
    int number = 0;
    for (const toml::node& entry : *entries) {
      ++number;
      const toml::table* table = entry.as_table();
      if (!table) toml_.In(fmt::format("{} {}", key, number)).Fail(entry, "must be a table");
      parse(*table, number);
    }
  }

  // A [[stiffness]] region: name, a selection as a handle's (select, units) and factor > 0.
  StiffnessSpec ParseStiffness(const toml::table& table, int number, Units default_units) const {
    StiffnessSpec spec;
    HandleSpec& region = spec.region;
    region.label = fmt::format("stiffness {}", number);
    region.name = region.label;
    if (const toml::node* name = table.get("name")) {
      if (!name->is_string()) toml_.In(region.label).Fail(*name, "'name' must be a string");
      region.name = name->as_string()->get();
      region.label = fmt::format("stiffness '{}'", region.name);
    }
    const TomlReader toml = toml_.In(region.label);
    toml.CheckKeys(table, {"name", "select", "units", "factor", "attribute"}, "a [[stiffness]]");
    if (const toml::node* attribute = table.get("attribute")) {
      if (!attribute->is_string() || attribute->as_string()->get().empty()) {
        toml.Fail(*attribute, "'attribute' must name a vertex or face property of the mesh file");
      }
      for (const char* key : {"select", "units", "factor"}) {
        if (const toml::node* other = table.get(key)) {
          toml.Fail(*other, fmt::format("'{}' does not go with 'attribute' (the property's values "
                                        "are the factors, per vertex or per face)",
                                        key));
        }
      }
      spec.attribute = attribute->as_string()->get();
      spec.attribute_where = toml_.Where(*attribute);
      return spec;
    }
    region.units = ParseUnits(toml, table, default_units);
    const toml::node* factor = table.get("factor");
    if (!factor) {
      toml.Fail(toml_.Where(table),
                "needs factor = s, the finite number > 0 multiplying the region's energy terms");
    }
    spec.factor = toml.Number(*factor, "factor");
    if (!(spec.factor > 0.0) || !std::isfinite(spec.factor)) {
      toml.Fail(*factor, "'factor' must be a finite number > 0 (1 = as stiff as the rest)");
    }
    const toml::node* select = table.get("select");
    if (!select || !select->as_table()) {
      toml.Fail(select ? toml_.Where(*select) : toml_.Where(table),
                "needs select = a table with one of slab, ball, indices, index_file (as a "
                "[[handle]]'s)");
    }
    region.select_where = toml_.Where(*select);
    ParseSelection(toml, *select->as_table(), region);
    return spec;
  }

  // A handle-edit file: [[edit]] frame = N with add = { a [[handle]] table } or remove = "name".
  std::vector<HandleEditSpec> ReadEdits(std::string_view toml_text) const {
    const toml::table root = toml_.Parse(toml_text);
    toml_.CheckKeys(root, {"edit"}, "a handle-edit file (expected [[edit]] entries)");
    const toml::node* node = root.get("edit");
    const toml::array* entries = node ? node->as_array() : nullptr;
    if (!entries || entries->empty()) {
      toml_.Fail(node ? toml_.Where(*node) : toml_.source(),
                 "no [[edit]] entries (each: frame = N and add = { name = ..., select... } or "
                 "remove = \"name\")");
    }
    std::vector<HandleEditSpec> edits;
    int number = 0;
    for (const toml::node& entry : *entries) {
      ++number;
      const TomlReader toml = toml_.In(fmt::format("edit {}", number));
      const toml::table* table = entry.as_table();
      if (!table) toml.Fail(entry, "must be a table");
      toml.CheckKeys(*table, {"frame", "add", "remove"}, "an [[edit]]");
      HandleEditSpec edit;
      const toml::node* frame = table->get("frame");
      const auto* integer = frame ? frame->as_integer() : nullptr;
      if (!integer || integer->get() < 1 || integer->get() > std::numeric_limits<int>::max()) {
        toml.Fail(frame ? toml.Where(*frame) : toml.Where(*table),
                  "needs frame = N, an integer >= 1 (the frame the edit comes before)");
      }
      edit.frame = static_cast<int>(integer->get());
      const toml::node* add = table->get("add");
      const toml::node* remove = table->get("remove");
      if ((add != nullptr) == (remove != nullptr)) {
        toml.Fail(*table,
                  "needs exactly one of add = { name = ..., select... } and remove = "
                  "\"name\"");
      }
      if (remove) {
        if (!remove->is_string()) toml.Fail(*remove, "'remove' must be the name of a handle");
        edit.add = false;
        edit.name = remove->as_string()->get();
      } else {
        if (!add->is_table()) {
          toml.Fail(*add, "'add' must be a table written like a scenario's [[handle]]");
        }
        edit.handle = ParseHandle(*add->as_table(), number, Units::kFractions);
        edit.name = edit.handle.name;
      }
      edits.push_back(std::move(edit));
    }
    return edits;
  }

 private:
  std::filesystem::path Resolve(const std::string& relative) const {
    std::filesystem::path path(relative);
    if (path.is_relative()) path = base_ / path;
    return path.lexically_normal();
  }

  // `mesh`, `refine` and `initial`.
  MeshSpec ReadMeshSpec(const toml::table& root, std::string_view toml_text) const {
    MeshSpec spec;
    const toml::node* mesh_node = root.get("mesh");
    if (!mesh_node) {
      toml_.Fail(toml_.source(),
                 "no 'mesh' given (mesh = \"file.obj\" or mesh = { builtin = \"cylinder\", ... })");
    }
    spec.where = toml_.Where(*mesh_node);
    if (const toml::node* node = root.get("refine")) {
      const auto* integer = node->as_integer();
      if (!integer || integer->get() < 0 || integer->get() > 10) {
        toml_.Fail(*node, "'refine' must be an integer in 0..10 (Loop subdivision rounds)");
      }
      spec.refine = static_cast<int>(integer->get());
      spec.refine_where = toml_.Where(*node);
    }
    if (const toml::node* node = root.get("initial")) {
      if (!node->is_string()) toml_.Fail(*node, "'initial' must be a file name (string)");
      spec.initial = Resolve(node->as_string()->get());
      spec.initial_where = toml_.Where(*node);
    }
    if (const auto* name = mesh_node->as_string()) {
      spec.kind = MeshSpec::Kind::kFile;
      spec.file = Resolve(name->get());
      return spec;
    }
    const toml::table* table = mesh_node->as_table();
    if (!table) {
      toml_.Fail(*mesh_node,
                 "'mesh' must be a file name, a table { builtin = \"cylinder\", ... } or a table "
                 "{ tetrahedralize = \"surface file\" or { builtin = ... }, ... }");
    }
    if (const toml::node* vertices = table->get("vertices")) {
      const auto* count = vertices->as_integer();
      if (count && count->get() > limits_.max_builtin_vertices) {
        toml_.Fail(*vertices, fmt::format("mesh.vertices = {} exceeds the limit of {} vertices",
                                          count->get(), limits_.max_builtin_vertices));
      }
    }
    // ConfigNode carries the line numbers and the unknown-key check into MakeBuiltinMesh.
    spec.parameters = ConfigNode::Parse(toml_text, toml_.source()).Child("mesh");
    const toml::node* source = table->get("tetrahedralize");
    if (!source) {
      spec.kind = MeshSpec::Kind::kBuiltin;
      spec.builtin_description = DescribeBuiltin(*table);
      return spec;
    }
    spec.kind = MeshSpec::Kind::kTetrahedralize;
    spec.tetrahedralize_where = toml_.Where(*source);
    if (const auto* file = source->as_string()) {
      spec.file = Resolve(file->get());
    } else if (const toml::table* surface = source->as_table()) {
      spec.tetrahedralize_builtin = true;
      spec.builtin_description = DescribeBuiltin(*surface);
    } else {
      toml_.Fail(*source,
                 "mesh.tetrahedralize must be a surface file name or a built-in mesh "
                 "table { builtin = \"cylinder\", ... }");
    }
    return spec;
  }

  // `units = "fractions" | "absolute"` of `table` (a handle or the top level), else `fallback`.
  Units ParseUnits(const TomlReader& toml, const toml::table& table, Units fallback) const {
    const toml::node* node = table.get("units");
    if (!node) return fallback;
    const std::string value = node->value_or(std::string());
    if (value == "fractions") return Units::kFractions;
    if (value == "absolute") return Units::kAbsolute;
    toml.Fail(*node,
              "'units' must be \"fractions\" (slab/ball/center as fractions of the bounding box, "
              "radius and translate in box diagonals; the default) or \"absolute\" (mesh "
              "coordinates)");
  }

  // `units` belongs to the handle (it also applies to rotate.center and translate).
  static void UnitsInsideSelection(const TomlReader& toml, const toml::table& selection,
                                   std::string_view what) {
    if (const toml::node* units = selection.get("units")) {
      toml.Fail(*units,
                fmt::format("'units' is a key of the [[handle]] (or of the top level), not of {}: "
                            "write units = \"absolute\" on its own line in the handle; it applies "
                            "to the selection, rotate.center and translate",
                            what));
    }
  }

  HandleSpec ParseHandle(const toml::table& table, int number, Units default_units) const {
    HandleSpec spec;
    spec.label = fmt::format("handle {}", number);
    spec.name = spec.label;
    const std::string where = toml_.Where(table);
    if (const toml::node* name = table.get("name")) {
      if (!name->is_string()) toml_.In(spec.label).Fail(*name, "'name' must be a string");
      spec.name = name->as_string()->get();
      spec.label = fmt::format("handle '{}'", spec.name);
    }
    const TomlReader toml = toml_.In(spec.label);  // errors name the handle
    toml.CheckKeys(
        table,
        {"name", "select", "rotate", "translate", "target", "target_file", "units", "weight"},
        "a [[handle]]");
    spec.units = ParseUnits(toml, table, default_units);
    if (const toml::node* weight = table.get("weight")) {
      // A soft handle: its vertices are pulled with this weight instead of pinned.
      spec.weight = toml.Number(*weight, "weight");
      if (!(spec.weight > 0.0) || !std::isfinite(spec.weight)) {
        toml.Fail(*weight, "'weight' must be a finite number > 0 (leave it out for a hard handle)");
      }
    }

    // target_file = "moves.txt": the file's "index x y z" lines are the selection and the motion.
    if (const toml::node* file = table.get("target_file")) {
      if (!file->is_string()) toml.Fail(*file, "'target_file' must be a file name");
      for (const char* other : {"select", "rotate", "translate", "target"}) {
        if (table.contains(other)) {
          toml.Fail(
              *table.get(other),
              fmt::format("target_file gives both the vertices and their targets; remove '{}'",
                          other));
        }
      }
      spec.target = TargetKind::kFile;
      spec.target_file = Resolve(file->as_string()->get());
      spec.target_file_where = toml_.Where(*file);
      spec.select_where = spec.target_file_where;
      return spec;
    }

    // Selection: exactly one of slab, ball, indices, index_file.
    const toml::node* select = table.get("select");
    if (!select) {
      toml.Fail(where,
                "has no selection; give exactly one of select.slab, select.ball, select.indices, "
                "select.index_file (or target_file = \"file\" with \"index x y z\" lines)");
    }
    spec.select_where = toml_.Where(*select);
    const toml::table* selection = select->as_table();
    if (!selection) {
      toml.Fail(spec.select_where,
                "'select' must be a table (select.slab = {...}, select.ball = {...}, "
                "select.indices = [...] or select.index_file = \"...\")");
    }
    ParseSelection(toml, *selection, spec);
    ParseMotion(toml, table, spec);
    return spec;
  }

  // The one selection of a handle's `select` table (slab, ball, indices or index_file).
  void ParseSelection(const TomlReader& toml, const toml::table& selection,
                      HandleSpec& spec) const {
    toml.CheckKeys(selection, {"slab", "ball", "indices", "index_file"}, "'select'");
    // toml++ iterates keys in sorted order; report them in the order written.
    std::vector<std::pair<toml::source_position, std::string>> written;
    for (const auto& [key, value] : selection) {
      written.emplace_back(key.source().begin, std::string(key.str()));
    }
    std::sort(written.begin(), written.end(), [](const auto& x, const auto& y) {
      return std::pair(x.first.line, x.first.column) < std::pair(y.first.line, y.first.column);
    });
    std::vector<std::string> kinds;
    for (auto& entry : written) kinds.push_back(std::move(entry.second));
    if (kinds.size() != 1) {
      toml.Fail(spec.select_where,
                kinds.empty() ? std::string("'select' is empty; give exactly one selection")
                              : fmt::format("has {} selections ({}); give exactly one",
                                            kinds.size(), fmt::join(kinds, ", ")));
    }
    const std::string& kind = kinds.front();
    const toml::node& body = *selection.get(kind);
    if (kind == "slab") {
      ParseSlab(toml, body, spec);
    } else if (kind == "ball") {
      ParseBall(toml, body, spec);
    } else if (kind == "indices") {
      spec.kind = SelectionKind::kIndices;
      const toml::array* indices = body.as_array();
      if (!indices) toml.Fail(body, "select.indices must be an array of integers");
      for (const toml::node& index : *indices) {
        const auto* integer = index.as_integer();
        if (!integer) {
          toml.Fail(index, "select.indices must hold integers (0-based indices)");
        }
        spec.indices.push_back(integer->get());
        spec.index_where.push_back(toml_.Where(index));
      }
    } else {
      spec.kind = SelectionKind::kIndexFile;
      if (!body.is_string()) toml.Fail(body, "select.index_file must be a string");
      spec.index_file = Resolve(body.as_string()->get());
      spec.index_file_where = toml_.Where(body);
    }
  }

  static void ParseSlab(const TomlReader& toml, const toml::node& body, HandleSpec& spec) {
    spec.kind = SelectionKind::kSlab;
    const toml::table* slab = body.as_table();
    if (!slab) toml.Fail(body, "select.slab must be a table {axis, from, to}");
    UnitsInsideSelection(toml, *slab, "select.slab");
    toml.CheckKeys(*slab, {"axis", "from", "to"}, "select.slab");
    const toml::node& axis = toml.Required(*slab, "axis", "select.slab");
    const std::string axis_name = axis.value_or(std::string());
    if (axis_name != "x" && axis_name != "y" && axis_name != "z") {
      toml.Fail(axis, "select.slab axis must be \"x\", \"y\" or \"z\"");
    }
    spec.axis = axis_name[0] - 'x';
    spec.from = toml.Number(toml.Required(*slab, "from", "select.slab"), "select.slab from");
    spec.to = toml.Number(toml.Required(*slab, "to", "select.slab"), "select.slab to");
    if (spec.from > spec.to) {
      toml.Fail(body, fmt::format("select.slab has from = {} > to = {}", spec.from, spec.to));
    }
  }

  static void ParseBall(const TomlReader& toml, const toml::node& body, HandleSpec& spec) {
    spec.kind = SelectionKind::kBall;
    const toml::table* ball = body.as_table();
    if (!ball) toml.Fail(body, "select.ball must be a table {center, radius}");
    UnitsInsideSelection(toml, *ball, "select.ball");
    toml.CheckKeys(*ball, {"center", "radius"}, "select.ball");
    spec.ball_center =
        Vector3(toml, toml.Required(*ball, "center", "select.ball"), "select.ball center");
    spec.radius = toml.Number(toml.Required(*ball, "radius", "select.ball"), "select.ball radius");
    if (spec.radius < 0.0) {
      toml.Fail(*ball->get("radius"), "select.ball radius must be >= 0");
    }
  }

  // A handle's motion: target = "initial", rotate, translate.
  static void ParseMotion(const TomlReader& toml, const toml::table& table, HandleSpec& spec) {
    if (const toml::node* target = table.get("target")) {
      if (target->value_or(std::string()) != "initial") {
        toml.Fail(*target,
                  "'target' must be \"initial\" (per-vertex targets from a file are given as "
                  "target_file = \"moves.txt\")");
      }
      if (table.contains("rotate") || table.contains("translate")) {
        toml.Fail(*target, "target = \"initial\" cannot be combined with rotate or translate");
      }
      spec.target = TargetKind::kInitial;
    }
    if (const toml::node* rotate = table.get("rotate")) {
      const toml::table* rotation = rotate->as_table();
      if (!rotation) {
        toml.Fail(*rotate, "'rotate' must be a table {axis, degrees, center?}");
      }
      toml.CheckKeys(*rotation, {"axis", "degrees", "center"}, "'rotate'");
      spec.has_rotation = true;
      const toml::node& axis = toml.Required(*rotation, "axis", "'rotate'");
      spec.axis_vector = Vector3(toml, axis, "rotate axis");
      if (spec.axis_vector.norm() == 0.0) {
        toml.Fail(axis, "the rotation axis is zero (it cannot be normalized)");
      }
      spec.degrees = toml.Number(toml.Required(*rotation, "degrees", "'rotate'"), "rotate degrees");
      if (const toml::node* center = rotation->get("center")) {
        spec.center = Vector3(toml, *center, "rotate center");
      }
    }
    if (const toml::node* translate = table.get("translate")) {
      spec.has_translation = true;
      spec.translation = Vector3(toml, *translate, "translate");
    }
  }

  TomlReader toml_;
  std::filesystem::path base_;
  ScenarioLimits limits_;
};

}  // namespace

ScenarioDescription ReadScenarioText(std::string_view toml_text, const std::string& source,
                                     const std::filesystem::path& base_directory,
                                     const ScenarioLimits& limits) {
  return ScenarioTextReader(source, base_directory, limits).Read(toml_text);
}

std::vector<HandleEditSpec> ReadHandleEditsText(std::string_view toml_text,
                                                const std::string& source,
                                                const std::filesystem::path& base_directory) {
  return ScenarioTextReader(source, base_directory, {}).ReadEdits(toml_text);
}

}  // namespace harap::io_internal
