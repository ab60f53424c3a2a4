// SPDX-License-Identifier: MIT
#pragma once

#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "framework/mesh.h"
#include "framework/optimizer.h"

namespace harap {

/// One [[handle]] of a scenario: the selected vertices and their targets.
struct ScenarioHandle {
  std::string name;             ///< `name`, or "handle N" (1-based) if absent.
  std::vector<Index> vertices;  ///< Selected vertices, ascending.
  Positions targets;            ///< #vertices×3 target positions.
  /// What selects the vertices, with its units ("slab y in [0, 0.05] (fractions of the bounding
  /// box)", "label 2 of x.sel", ...), for `harap handles` and messages.
  std::string selection;
  /// The target motion in words: "fixed", "rotate 90° about (0, 0, 1) through (..), translate
  /// (..)", "per-vertex targets from FILE", "4x4 transform from FILE", ...
  std::string motion;
  /// `weight = w`: a soft handle pulling its vertices with weight w (Constraints::weights);
  /// Constraints::kHardWeight (the default) pins them.
  double weight = Constraints::kHardWeight;
};

/// A `[[stiffness]]` region of a scenario: its vertices' factor (docs/input.md).
struct ScenarioStiffness {
  std::string name;             ///< `name`, or "stiffness N" (1-based) if absent.
  std::vector<Index> vertices;  ///< Selected vertices, ascending.
  double factor = 1.0;          ///< finite, > 0 (unused with an attribute)
  std::string selection;        ///< What selects the vertices, in words (as ScenarioHandle's).
  /// `attribute = "NAME"`: the PLY property the factors come from, and the factors, one per
  /// vertex (of `vertices`, every vertex) or one per element; empty for a selected region.
  std::string attribute;
  std::vector<double> vertex_factors, element_factors;
};

/// A deformation scenario (../shared/scenarios/FORMAT.md, harap's additions in docs/input.md):
/// the mesh and its handles.
struct Scenario {
  std::filesystem::path file;  ///< The scenario file ("" for in-memory scenarios).
  std::string mesh_source;     ///< Mesh file path or builtin description, for reports.
  Mesh mesh;                   ///< After `refine` / `tetrahedralize`; `planar` decided.
  std::vector<ScenarioHandle> handles;
  std::vector<ScenarioStiffness> stiffness;  ///< `[[stiffness]]` regions, as written
  /// The box selections refer to: of the vertices some element references (docs/input.md).
  Eigen::Vector3d box_min = Eigen::Vector3d::Zero(), box_max = Eigen::Vector3d::Zero();
  std::optional<Positions> initial;  ///< From `initial = "file"`.
  /// Remarks about the input for reports: reoriented tetrahedra, what tetrahedralization made,
  /// why the mesh is (not) treated as planar.
  std::vector<std::string> notes;

  /// All handles merged; a vertex selected by several handles takes the first handle's target.
  Constraints MergedConstraints() const;
  /// Per-element stiffness factors (framework/stiffness.h) from the `[[stiffness]]` regions: a
  /// vertex takes the product of the factors of the regions that select it (1 outside all), an
  /// element the mean of its vertices'. Empty without regions.
  std::vector<double> ElementStiffness() const;
};

/// The box that selections refer to, {min, max}: of the vertices some element references, so
/// that stray unreferenced vertices do not move it (docs/input.md). Infinite (min > max) for a
/// mesh without elements.
std::pair<Eigen::Vector3d, Eigen::Vector3d> SelectionBox(const Mesh& mesh);

/// `handles` (of a mesh with `num_vertices` vertices) merged into one set of constraints, sorted
/// by vertex; a vertex selected by several handles takes the first handle's target. For handles
/// whose targets differ from the scenario's (a frame of `harap drag`).
Constraints MergeHandles(Index num_vertices, const std::vector<ScenarioHandle>& handles);

/// Upper bounds on what a scenario may make the program build, for callers that parse untrusted
/// text (the fuzz harness). Exceeding one is a ConfigError naming the key. Default: no bound
/// beyond the index type.
struct ScenarioLimits {
  /// `vertices` of a built-in mesh.
  Index max_builtin_vertices = std::numeric_limits<Index>::max();
  /// Elements after `refine` (each Loop step multiplies them by 4).
  Index max_elements = std::numeric_limits<Index>::max();
};

/// Loads a scenario file. Mesh paths are relative to the scenario file. Throws ConfigError or
/// InputError naming the file, the handle and the problem.
Scenario LoadScenario(const std::filesystem::path& file);

/// One edit of a session's handle set (`harap drag --edits`, docs/session.md): before frame
/// `frame`, add the handle `name` (its vertices selected on the scenario's mesh exactly as a
/// scenario's [[handle]] selects them: slab, ball, indices, index_file, units) or remove it.
struct HandleEdit {
  int frame = 0;  ///< 1-based
  std::string name;
  bool add = true;
  std::vector<Index> vertices;  ///< add: the selected vertices (ascending)
  std::string selection;        ///< add: what selected them, in words
};

/// Reads a handle-edit file (TOML: [[edit]] frame = N, add = { name = ..., select... } or
/// remove = "name") for `scenario`'s mesh; paths in it are relative to the file. Throws
/// ConfigError naming file:line:column and the edit for a bad entry or an empty selection.
std::vector<HandleEdit> LoadHandleEdits(const std::filesystem::path& file,
                                        const Scenario& scenario);

/// Checks a scenario file's text (TOML syntax, keys, values, handles) without reading the mesh
/// or any other file it names, for callers that want typos found before long work starts
/// (`harap run` checks every scenario file of an experiment so). Throws like LoadScenario.
void CheckScenarioText(const std::filesystem::path& file);

/// Same from TOML text; relative paths are resolved against `base_directory`.
Scenario ParseScenario(std::string_view toml_text, const std::string& source_name,
                       const std::filesystem::path& base_directory,
                       const ScenarioLimits& limits = {});

/// Decides scenario.mesh.planar: `setting` if given (true fails with a ConfigError prefixed by
/// `where` when the mesh has tetrahedra or something leaves the plane z = 0), else automatically:
/// a triangle mesh whose vertices, handle targets and initial positions all have z = 0 (a note
/// says so). Scenario files and in-memory scenarios decide alike.
void DecidePlanar(Scenario& scenario, std::optional<bool> setting, const std::string& where);

/// A scenario from data held in memory (the Python module's arrays): `mesh` (triangles or
/// tetrahedra; not planar yet), one handle moving `handle_vertices[k]` to `targets.row(k)`, an
/// optional start configuration, and `planar` as in a scenario file (absent: automatic). Checks
/// everything a scenario file's loader checks and throws InputError naming `source` and the
/// offending row: the mesh (ValidateMesh; flat tetrahedra), handle vertices out of range or
/// repeated, a targets or initial array of the wrong size, non-finite targets or initial
/// positions. Tetrahedra are oriented positively as the file readers do (a note says so).
/// `weights`: empty (every handle vertex hard) or one per handle vertex, each > 0: a finite w makes
/// the vertex a soft handle with weight w, +inf keeps it hard (Constraints::kHardWeight); the
/// vertices become one handle per distinct weight ("handles", "soft handles (weight w)").
Scenario ScenarioFromArrays(Mesh mesh, const std::vector<Index>& handle_vertices,
                            const Positions& targets, std::optional<Positions> initial,
                            std::optional<bool> planar, const std::string& source,
                            const std::vector<double>& weights = {});

}  // namespace harap
