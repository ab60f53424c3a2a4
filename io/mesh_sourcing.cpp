// SPDX-License-Identifier: MIT
//
// Mesh sourcing. Decisions the format leaves open:
//   - `refine` of a non-manifold surface uses the crease variant of Loop subdivision, with a note.
//   - `refine` of a tetrahedralized surface subdivides the surface before TetGen fills it; `refine`
//     of a tetrahedral file is an error (Loop subdivision is for triangles).
//   - `initial` reads vertex positions only (ReadMeshVertices): a start configuration may have
//     inverted or flat tetrahedra, and for TetGen only its .node file is needed.
#include "io/mesh_sourcing.h"

#include <fmt/format.h>

#include <cmath>
#include <utility>

#include "framework/error.h"
#include "io/builtin_meshes.h"
#include "io/file_reading.h"
#include "io/mesh_io.h"
#include "io/subdivision.h"
#include "io/tetrahedralize.h"

namespace harap::io_internal {

namespace {

// A problem with a value of the scenario text, at `where`.
[[noreturn]] void Fail(const std::string& where, std::string_view problem) {
  throw ConfigError(fmt::format("{}: {}", where, problem));
}

Mesh LoadMeshFile(const std::filesystem::path& path, const std::string& where,
                  std::string_view what, std::vector<std::string>* notes) {
  return ReadNamedFile(path, where, what, [&](const auto& file) { return ReadMesh(file, notes); });
}

// `refine` rounds of Loop subdivision of the scenario's (triangle) mesh.
void Refine(Scenario& scenario, const MeshSpec& spec, const ScenarioLimits& limits) {
  const int refine = spec.refine;
  if (refine == 0) return;
  if (scenario.mesh.kind() == ElementKind::kTetrahedron) {
    Fail(spec.refine_where,
         fmt::format("refine (Loop subdivision) applies to triangle meshes, but {} has "
                     "tetrahedra (to refine a surface before filling it, use mesh = "
                     "{{ tetrahedralize = ... }})",
                     scenario.mesh_source));
  }
  const double growth = std::pow(4.0, refine);
  if (static_cast<double>(scenario.mesh.num_elements()) * growth >
      static_cast<double>(limits.max_elements)) {
    Fail(spec.refine_where, fmt::format("refine = {} would make more than {} triangles from {}",
                                        refine, limits.max_elements, scenario.mesh.num_elements()));
  }
  try {
    std::string note;
    scenario.mesh = LoopSubdivide(scenario.mesh, refine, &note);
    if (!note.empty()) scenario.notes.push_back(std::move(note));
  } catch (const InputError& error) {
    throw InputError(fmt::format("{}: refine = {} of mesh {}: {}", spec.refine_where, refine,
                                 scenario.mesh_source, error.what()));
  }
}

// mesh = { tetrahedralize = "surface file" | { builtin = ... }, max_volume = ..., ... }: the
// surface (after `refine`) filled with tetrahedra by TetGen, its vertices first and unchanged.
void TetrahedralizeSurface(const MeshSpec& spec, const ScenarioLimits& limits, Scenario& scenario) {
  const std::string& where = spec.tetrahedralize_where;
  OptionReader parameters(spec.parameters);
  const int refine = spec.refine;
  Scenario surface;
  if (!spec.tetrahedralize_builtin) {
    // Read as an option too, so that RejectUnknownKeys knows it (the path is spec.file).
    (void)parameters.Get(
        "tetrahedralize", std::string(),
        "surface to fill with tetrahedra: a mesh file, or a built-in table { builtin = ... }");
    surface.mesh_source = spec.file.string();
    surface.mesh = LoadMeshFile(spec.file, where, "mesh.tetrahedralize", nullptr);
  } else {
    surface.mesh = MakeBuiltinMesh(parameters.Child("tetrahedralize"));
    surface.mesh_source = spec.builtin_description;
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
    Fail(spec.where, problem);
  }
  if (surface.mesh.kind() == ElementKind::kTetrahedron) {
    throw InputError(
        fmt::format("{}: mesh.tetrahedralize: {} has tetrahedra already; give a "
                    "triangle surface (or name the tetrahedral file as mesh)",
                    where, surface.mesh_source));
  }
  Refine(surface, spec, limits);
  scenario.mesh = Tetrahedralize(surface.mesh, options,
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

}  // namespace

void SourceMesh(const MeshSpec& spec, const ScenarioLimits& limits, Scenario& scenario) {
  switch (spec.kind) {
    case MeshSpec::Kind::kFile:
      scenario.mesh_source = spec.file.string();
      scenario.mesh = LoadMeshFile(spec.file, spec.where, "mesh", &scenario.notes);
      Refine(scenario, spec, limits);
      break;
    case MeshSpec::Kind::kBuiltin:
      scenario.mesh = MakeBuiltinMesh(spec.parameters);
      scenario.mesh_source = spec.builtin_description;
      Refine(scenario, spec, limits);
      break;
    case MeshSpec::Kind::kTetrahedralize:
      TetrahedralizeSurface(spec, limits, scenario);
      break;
  }
  if (spec.initial) {
    Positions initial = ReadNamedFile(*spec.initial, spec.initial_where, "initial",
                                      [](const auto& path) { return ReadMeshVertices(path); });
    if (initial.rows() != scenario.mesh.num_vertices()) {
      throw InputError(
          fmt::format("{}: initial configuration {} has {} vertices, but the mesh "
                      "has {}{} (same count and order needed)",
                      spec.initial_where, spec.initial->string(), initial.rows(),
                      scenario.mesh.num_vertices(), spec.refine > 0 ? " after refine" : ""));
    }
    scenario.initial = std::move(initial);
  }
}

}  // namespace harap::io_internal
