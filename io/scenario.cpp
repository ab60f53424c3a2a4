// SPDX-License-Identifier: MIT
//
// Scenarios: a scenario file is read in three steps, each in its own file: its text
// (scenario_reading: TOML → what it asks for, checked before any file is read), its mesh
// (mesh_sourcing: file, built-in, tetrahedralized, refined; initial positions) and its handles
// (handle_selection: select.* → vertex sets, motions → targets). Here: the assembly, the planar
// decision, merging handles, and scenarios from arrays.
//   - Planar (Mesh::planar) is `planar = true/false` if given, else automatic: a triangle mesh
//     whose vertices, handle targets and initial positions all have z = 0 exactly. A flat mesh
//     with a handle that leaves the plane is a surface problem (lifting a sheet), not an error.
#include "io/scenario.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <functional>
#include <limits>

#include "framework/error.h"
#include "framework/stiffness.h"
#include "io/file_reading.h"
#include "io/handle_selection.h"
#include "io/mesh_sourcing.h"
#include "io/scenario_reading.h"
#include "io/tetrahedra.h"

namespace harap {

namespace {

[[noreturn]] void FailAt(const std::string& where, std::string_view problem) {
  throw ConfigError(fmt::format("{}: {}", where, problem));
}

}  // namespace

// Sets scenario.mesh.planar: from `planar = true/false`, else automatically (see docs/input.md):
// a triangle mesh whose vertices, handle targets and initial positions all have z = 0.
void DecidePlanar(Scenario& scenario, std::optional<bool> setting, const std::string& where) {
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
    scenario.notes.push_back(
        "planar: every vertex, handle target and initial position has "
        "z = 0, so the mesh is deformed in the plane (planar = false "
        "deforms it as a surface)");
  } else if (off_plane.rfind("vertex", 0) != 0) {
    scenario.notes.push_back(
        fmt::format("not planar although the mesh is flat (z = 0): {}", off_plane));
  }
}

Constraints Scenario::MergedConstraints() const {
  return MergeHandles(mesh.num_vertices(), handles);
}

std::vector<double> Scenario::ElementStiffness() const {
  if (stiffness.empty()) return {};
  std::vector<double> at_vertex(mesh.num_vertices(), 1.0);
  for (const ScenarioStiffness& region : stiffness) {
    if (!region.element_factors.empty()) continue;  // applied per element below
    for (size_t k = 0; k < region.vertices.size(); ++k) {
      at_vertex[region.vertices[k]] *=
          region.vertex_factors.empty() ? region.factor : region.vertex_factors[k];
    }
  }
  std::vector<double> at_element = harap::ElementStiffness(mesh, at_vertex);
  for (const ScenarioStiffness& region : stiffness) {
    for (size_t e = 0; e < region.element_factors.size(); ++e) {
      at_element[e] *= region.element_factors[e];
    }
  }
  return at_element;
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
  const bool any_soft = std::any_of(handles.begin(), handles.end(), [](const ScenarioHandle& h) {
    return h.weight != Constraints::kHardWeight;
  });
  for (size_t k = 0; k < constraints.indices.size(); ++k) {
    const auto [h, row] = owner[constraints.indices[k]];
    constraints.targets.row(static_cast<Index>(k)) = handles[h].targets.row(row);
    if (any_soft) constraints.weights.push_back(handles[h].weight);
  }
  return constraints;
}

Scenario ParseScenario(std::string_view toml_text, const std::string& source_name,
                       const std::filesystem::path& base_directory, const ScenarioLimits& limits) {
  const io_internal::ScenarioDescription description =
      io_internal::ReadScenarioText(toml_text, source_name, base_directory, limits);
  Scenario scenario;
  io_internal::SourceMesh(description.mesh, limits, scenario);
  io_internal::AddHandles(description.benchmark, description.handles, scenario);
  io_internal::AddStiffness(description.stiffness, description.mesh, scenario);
  DecidePlanar(scenario, description.planar, description.planar_where);
  return scenario;
}

void CheckScenarioText(const std::filesystem::path& file) {
  std::error_code error;
  if (!std::filesystem::exists(file, error)) {
    throw InputError(fmt::format("{}: scenario file not found", file.string()));
  }
  (void)io_internal::ReadScenarioText(ReadFileMaybeXz(file), file.string(), file.parent_path(), {});
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

std::vector<HandleEdit> LoadHandleEdits(const std::filesystem::path& file,
                                        const Scenario& scenario) {
  std::error_code error;
  if (!std::filesystem::exists(file, error)) {
    throw InputError(fmt::format("{}: handle-edit file not found", file.string()));
  }
  const std::vector<io_internal::HandleEditSpec> specs =
      io_internal::ReadHandleEditsText(ReadFileMaybeXz(file), file.string(), file.parent_path());
  // The selections run on a scenario with the same mesh and no handles, so they see the same
  // selection box and rules as the scenario's own handles.
  Scenario selecting;
  selecting.mesh = scenario.mesh;
  selecting.initial = scenario.initial;
  std::vector<HandleEdit> edits;
  for (const io_internal::HandleEditSpec& spec : specs) {
    HandleEdit edit{spec.frame, spec.name, spec.add, {}, {}};
    if (spec.add) {
      selecting.handles.clear();
      io_internal::AddHandles(std::nullopt, {spec.handle}, selecting);
      edit.vertices = std::move(selecting.handles.back().vertices);
      edit.selection = std::move(selecting.handles.back().selection);
    }
    edits.push_back(std::move(edit));
  }
  return edits;
}

Scenario ScenarioFromArrays(Mesh mesh, const std::vector<Index>& handle_vertices,
                            const Positions& targets, std::optional<Positions> initial,
                            std::optional<bool> planar, const std::string& source,
                            const std::vector<double>& weights) {
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
    scenario.notes.push_back(
        fmt::format("{}: {} of {} tetrahedra had negative signed volume "
                    "and were reoriented (last two corners swapped)",
                    source, orientation.reoriented, mesh.num_elements()));
  }
  const Index n = mesh.num_vertices();
  if (targets.rows() != static_cast<Index>(handle_vertices.size())) {
    throw InputError(
        fmt::format("{}: {} handle vertices but {} target rows (one target per "
                    "handle vertex)",
                    source, handle_vertices.size(), targets.rows()));
  }
  std::vector<Index> first_row(n, -1);
  for (size_t k = 0; k < handle_vertices.size(); ++k) {
    const Index v = handle_vertices[k];
    if (v < 0 || v >= n) {
      throw InputError(
          fmt::format("{}: handle vertex {} (row {}) is out of range; the mesh has "
                      "{} vertices (valid: 0..{})",
                      source, v, k, n, n - 1));
    }
    if (first_row[v] >= 0) {
      throw InputError(fmt::format("{}: handle vertex {} appears twice (rows {} and {})", source, v,
                                   first_row[v], k));
    }
    first_row[v] = static_cast<Index>(k);
    if (!targets.row(static_cast<Index>(k)).allFinite()) {
      throw InputError(
          fmt::format("{}: the target of handle vertex {} (row {}) is not finite "
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
  if (!weights.empty() && weights.size() != handle_vertices.size()) {
    throw InputError(fmt::format("{}: {} handle vertices but {} weights (one per handle vertex)",
                                 source, handle_vertices.size(), weights.size()));
  }
  for (size_t k = 0; k < weights.size(); ++k) {
    if (!(weights[k] > 0.0)) {  // NaN too
      throw InputError(fmt::format(
          "{}: the weight of handle vertex {} (row {}) is {}; a weight is > 0 (inf: a hard "
          "handle)",
          source, handle_vertices[k], k, weights[k]));
    }
  }
  scenario.mesh = std::move(mesh);
  // One handle per distinct weight (hard first), each with its vertices ascending (the
  // selections' order).
  std::vector<double> distinct =
      weights.empty() ? std::vector<double>{Constraints::kHardWeight} : weights;
  std::sort(distinct.begin(), distinct.end(), std::greater<>());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  std::vector<Index> order(handle_vertices.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = static_cast<Index>(k);
  std::sort(order.begin(), order.end(),
            [&](Index a, Index b) { return handle_vertices[a] < handle_vertices[b]; });
  for (const double weight : distinct) {
    ScenarioHandle handle;
    handle.weight = weight;
    handle.name = weight == Constraints::kHardWeight
                      ? std::string("handles")
                      : fmt::format("soft handles (weight {})", weight);
    std::vector<Index> rows;
    for (const Index k : order) {
      if (weights.empty() || weights[k] == weight) rows.push_back(k);
    }
    handle.targets.resize(static_cast<Index>(rows.size()), 3);
    for (size_t i = 0; i < rows.size(); ++i) {
      handle.vertices.push_back(handle_vertices[rows[i]]);
      handle.targets.row(static_cast<Index>(i)) = targets.row(rows[i]);
    }
    if (!handle.vertices.empty()) scenario.handles.push_back(std::move(handle));
  }
  scenario.initial = std::move(initial);
  DecidePlanar(scenario, planar, source);
  return scenario;
}

}  // namespace harap
