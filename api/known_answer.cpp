// SPDX-License-Identifier: MIT
#include "api/known_answer.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>

#include "api/deform.h"
#include "framework/error.h"
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
  if (scenario.mesh.kind() != ElementKind::kTriangle) {
    throw InputError(fmt::format("{}: a known-answer registration case needs a triangle mesh",
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
  const auto count = static_cast<Index>(
      std::llround(options.points_per_vertex * static_cast<double>(deformed.num_vertices())));
  SampledPoints sample = SampleSurface(deformed, count, options.seed);
  if (options.target == KnownAnswerTarget::kDamaged) {
    // A seed of its own, so the damaged points are the undamaged ones minus the hole.
    sample = DamagePoints(sample, options.damage, options.seed + 1);
  }
  known.target.points = std::move(sample.points);
  known.target.normals = std::move(sample.normals);
  return known;
}

KnownAnswerFiles KnownAnswerFiles::In(const std::filesystem::path& folder) {
  return {folder / "source.ply", folder / "target.ply", folder / "answer.ply"};
}

KnownAnswerFiles WriteKnownAnswerCase(const KnownAnswerCase& known,
                                      const std::filesystem::path& folder) {
  std::error_code error;
  std::filesystem::create_directories(folder, error);
  if (error) {
    throw InputError(
        fmt::format("{}: cannot create the folder: {}", folder.string(), error.message()));
  }
  const KnownAnswerFiles files = KnownAnswerFiles::In(folder);
  WritePly(files.source, known.source.vertices, known.source.elements);
  WritePly(files.answer, known.answer, known.source.elements);
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
