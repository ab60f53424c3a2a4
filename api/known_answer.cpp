// SPDX-License-Identifier: MIT
#include "api/known_answer.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>

#include "api/deform.h"
#include "framework/error.h"
#include "framework/mesh_topology.h"
#include "io/mesh_writers.h"

namespace harap {

namespace {

constexpr std::pair<KnownAnswerTarget, std::string_view> kTargetNames[] = {
    {KnownAnswerTarget::kMesh, "mesh"},
    {KnownAnswerTarget::kPoints, "points"},
    {KnownAnswerTarget::kDamaged, "damaged"},
};

}  // namespace

std::string_view KnownAnswerTargetName(KnownAnswerTarget target) {
  for (const auto& [value, name] : kTargetNames) {
    if (value == target) return name;
  }
  return "?";
}

std::vector<std::string> KnownAnswerTargetNames() {
  std::vector<std::string> names;
  for (const auto& entry : kTargetNames) names.emplace_back(entry.second);
  return names;
}

KnownAnswerTarget ParseKnownAnswerTarget(std::string_view name) {
  for (const auto& [value, known] : kTargetNames) {
    if (known == name) return value;
  }
  throw ConfigError(fmt::format("unknown known-answer target '{}'; valid targets: {}", name,
                                fmt::join(KnownAnswerTargetNames(), ", ")));
}

void KnownAnswerOptions::Validate() const {
  if (!(points_per_vertex > 0.0 && points_per_vertex <= 1000.0)) {
    throw ConfigError(
        fmt::format("points_per_vertex = {} must lie in (0, 1000]", points_per_vertex));
  }
  for (const auto& [name, value] :
       {std::pair{"removed", damage.removed}, std::pair{"outliers", damage.outliers},
        std::pair{"outlier_margin", damage.outlier_margin}}) {
    if (!(value >= 0.0 && value < 1.0)) {
      throw ConfigError(fmt::format("{} = {} must lie in [0, 1)", name, value));
    }
  }
  if (threads < 0) throw ConfigError(fmt::format("threads = {} must be >= 0", threads));
}

KnownAnswerCase MakeKnownAnswerCase(const Registries& registries, const Scenario& scenario,
                                    const ConfigNode& answer_config,
                                    const KnownAnswerOptions& options) {
  options.Validate();
  if (scenario.mesh.planar) {
    throw InputError(fmt::format(
        "{}: a known-answer registration case needs a surface or a volume in space, not a "
        "planar mesh",
        scenario.mesh_source));
  }
  DeformOptions deform;
  deform.threads = options.threads;
  const DeformOutcome solved = RunDeform(registries, scenario, answer_config, deform);
  KnownAnswerCase known;
  known.source = scenario.mesh;
  known.answer = solved.result.positions;
  if (known.answer.rows() != known.source.num_vertices()) {
    throw InputError(fmt::format(
        "{}: the deformation solved {} vertices of the mesh's {} (the mesh was repaired); a "
        "known answer needs one position per vertex",
        scenario.mesh_source, known.answer.rows(), known.source.num_vertices()));
  }
  known.answer_description =
      fmt::format("{} with {} ({} energy), {} iterations",
                  scenario.file.empty() ? scenario.mesh_source : scenario.file.generic_string(),
                  solved.optimizer, solved.energy_type, solved.result.iterations);
  Mesh deformed{known.answer, known.source.elements, known.source.planar};
  known.target.name = std::string(KnownAnswerTargetName(options.target));
  if (options.target == KnownAnswerTarget::kMesh) {
    known.target.mesh = std::move(deformed);
    return known;
  }
  // Points on the deformed surface: a volume's boundary.
  Mesh surface{deformed.vertices,
               deformed.kind() == ElementKind::kTetrahedron ? BoundaryTriangles(deformed.elements)
                                                            : deformed.elements,
               false};
  const auto count = static_cast<Index>(
      std::llround(options.points_per_vertex * static_cast<double>(deformed.num_vertices())));
  SampledPoints sample = SampleSurface(surface, count, options.seed);
  if (options.target == KnownAnswerTarget::kDamaged) {
    // A seed of its own, so the damaged points are the undamaged ones minus the hole.
    sample = DamagePoints(sample, options.damage, options.seed + 1);
  }
  known.target.points = std::move(sample.points);
  known.target.normals = std::move(sample.normals);
  return known;
}

KnownAnswerFiles KnownAnswerFiles::In(const std::filesystem::path& folder, ElementKind kind) {
  const char* extension = kind == ElementKind::kTetrahedron ? ".mesh" : ".ply";
  return {folder / (std::string("source") + extension), folder / "target.ply",
          folder / (std::string("answer") + extension)};
}

std::optional<KnownAnswerFiles> KnownAnswerFiles::Find(const std::filesystem::path& folder) {
  for (const ElementKind kind : {ElementKind::kTriangle, ElementKind::kTetrahedron}) {
    KnownAnswerFiles files = In(folder, kind);
    std::error_code error;
    if (std::filesystem::exists(files.answer, error)) return files;
  }
  return std::nullopt;
}

KnownAnswerFiles WriteKnownAnswerCase(const KnownAnswerCase& known,
                                      const std::filesystem::path& folder) {
  std::error_code error;
  std::filesystem::create_directories(folder, error);
  if (error) {
    throw InputError(
        fmt::format("{}: cannot create the folder: {}", folder.string(), error.message()));
  }
  const KnownAnswerFiles files = KnownAnswerFiles::In(folder, known.source.kind());
  WriteMesh(files.source, known.source.vertices, known.source.elements);
  WriteMesh(files.answer, known.answer, known.source.elements);
  if (known.target.mesh) {
    WritePly(files.target, known.target.mesh->vertices, known.target.mesh->elements);
  } else {
    std::vector<VertexValues> normals(3);
    const char* names[] = {"nx", "ny", "nz"};
    for (int axis = 0; axis < 3; ++axis) {
      normals[axis].name = names[axis];
      const Eigen::VectorXd column = known.target.normals.col(axis);
      normals[axis].values.assign(column.data(), column.data() + column.size());
    }
    WritePly(files.target, known.target.points, Elements(0, 3), normals);
  }
  return files;
}

}  // namespace harap
