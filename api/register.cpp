// SPDX-License-Identifier: MIT
#include "api/register.h"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <unordered_set>

#include "api/component_factory.h"
#include "api/deform.h"
#include "api/huge_pages.h"
#include "framework/error.h"
#include "io/file_reading.h"
#include "io/mesh_io.h"
#include "io/point_cloud.h"
#include "io/tetrahedra.h"
#include "spatial/target_search.h"

namespace harap {

RegistrationTarget ReadRegistrationTarget(const std::filesystem::path& file) {
  RegistrationTarget target;
  target.name = file.string();
  if (!std::filesystem::exists(file)) {
    throw InputError(fmt::format("{}: the target file does not exist", file.string()));
  }
  if (HoldsPointCloud(file)) {
    PointCloud cloud = ReadPointCloud(file);
    target.points = std::move(cloud.points);
    target.normals = std::move(cloud.normals);
  } else {
    target.mesh = ReadMesh(file);
  }
  return target;
}

Constraints ReadLandmarks(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(fmt::format("{}: cannot open the landmarks file", file.string()));
  Constraints landmarks;
  std::vector<Eigen::RowVector3d> points;
  std::unordered_set<long long> seen;  // vertices with a landmark
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    std::istringstream fields(line);
    long long vertex = -1;
    Eigen::RowVector3d point;
    std::string extra;
    if (!(fields >> vertex >> point.x() >> point.y() >> point.z()) || (fields >> extra)) {
      throw InputError(fmt::format("{}:{}: a landmark is `vertex x y z`, got '{}'", file.string(),
                                   number, line));
    }
    if (vertex < 0 || vertex > std::numeric_limits<Index>::max() || !point.allFinite()) {
      throw InputError(fmt::format("{}:{}: the vertex must be >= 0 and the point finite, got '{}'",
                                   file.string(), number, line));
    }
    if (!seen.insert(vertex).second) {
      throw InputError(
          fmt::format("{}:{}: vertex {} has a landmark already", file.string(), number, vertex));
    }
    landmarks.indices.push_back(static_cast<Index>(vertex));
    points.push_back(point);
  }
  landmarks.targets.resize(static_cast<Index>(points.size()), 3);
  for (size_t k = 0; k < points.size(); ++k)
    landmarks.targets.row(static_cast<Index>(k)) = points[k];
  return landmarks;
}

namespace {

// `[optimizer]`: hierarchical (default) or classic (flat), and the level solver's options.
struct RegistrationDriver {
  bool hierarchical = true;
  std::unique_ptr<LevelSolver> level_solver;
};

RegistrationDriver ResolveDriver(const Registries& registries, OptionReader table) {
  RegistrationDriver driver;
  const std::string type =
      table.GetChoice("type", "hierarchical", {"hierarchical", "classic"},
                      "hierarchical: register the levels coarse to fine; classic: the input mesh "
                      "alone");
  driver.hierarchical = type == "hierarchical";
  driver.level_solver = registries.level_solvers.Create("local_global", table);
  table.RejectUnknownKeys();
  return driver;
}

std::unique_ptr<ClosestPointSearch> BuildSearch(const RegistrationTarget& target) {
  if (target.mesh && target.mesh->kind() == ElementKind::kTetrahedron) {
    // A volume's surface is its boundary.
    Mesh surface;
    surface.vertices = target.mesh->vertices;
    surface.elements = BoundaryTriangles(target.mesh->elements);
    return TargetSearch::FromMesh(surface);
  }
  if (target.mesh) return TargetSearch::FromMesh(*target.mesh);
  return TargetSearch::FromPoints(target.points, target.normals);
}

}  // namespace

void CheckRegisterConfig(const Registries& registries, const ConfigNode& config) {
  ValidateRunConfig(config, {"registration"});
  RegistrationOptions::FromConfig(OptionReader(config.Child("registration")));
  const RegistrationDriver driver =
      ResolveDriver(registries, OptionReader(config.Child("optimizer")));
  const RegistryComponentFactory factory(registries, config);
  driver.level_solver->CheckCompatible(*factory.MakeEnergy(), /*handle_edits=*/false);
}

RegisterOutcome RunRegister(const Registries& registries, const Mesh& source,
                            const RegistrationTarget& target, const ConfigNode& config,
                            const RegisterOptions& options) {
  ValidateRunConfig(config, {"registration"});
  RegisterOutcome outcome;
  outcome.options = RegistrationOptions::FromConfig(OptionReader(config.Child("registration")));
  RegistrationDriver driver = ResolveDriver(registries, OptionReader(config.Child("optimizer")));
  outcome.options.hierarchical = driver.hierarchical;
  outcome.mode = driver.hierarchical ? "hierarchical" : "flat";
  const RegistryComponentFactory factory(registries, config,
                                         DefaultComponentsFor(registries, source));
  driver.level_solver->CheckCompatible(*factory.MakeEnergy(), /*handle_edits=*/false);
  outcome.energy_type = factory.energy_name();
  outcome.solver = factory.solver_name();
  if (driver.hierarchical) {
    outcome.hierarchy = factory.hierarchy_name();
    outcome.upsampler = factory.upsampler_name();
  }
  outcome.resolved_config = config.ToToml();

  Context context = options.MakeContext();
  outcome.threads = context.threads();
  context.ReportPhase("building the target's search tree");
  Stopwatch clock;
  const std::unique_ptr<ClosestPointSearch> search =
      context.Run([&] { return BuildSearch(target); });
  outcome.target_seconds = clock.Seconds();

  RegistrationProblem problem;
  problem.source = &source;
  problem.target = search.get();
  problem.make_point_search = [](const Positions& points) -> std::unique_ptr<ClosestPointSearch> {
    return TargetSearch::FromPoints(points, Positions(0, 3));
  };
  problem.landmarks = options.landmarks;
  problem.stiffness = options.stiffness;
  outcome.result = Register(problem, outcome.options, *driver.level_solver, factory, context);
  return outcome;
}

AnswerErrors CompareWithAnswer(const Positions& registered, const Positions& answer,
                               double diagonal, const std::string& what) {
  if (registered.rows() != answer.rows()) {
    throw InputError(fmt::format("{}: the answer has {} vertices, the registered mesh {}", what,
                                 answer.rows(), registered.rows()));
  }
  AnswerErrors errors;
  errors.diagonal = diagonal;
  double sum = 0.0, squares = 0.0;
  for (Index v = 0; v < answer.rows(); ++v) {
    const double e = (registered.row(v) - answer.row(v)).norm();
    sum += e;
    squares += e * e;
    if (e > errors.max || errors.worst_vertex < 0) {
      errors.max = e;
      errors.worst_vertex = v;
    }
  }
  if (answer.rows() > 0) {
    errors.mean = sum / static_cast<double>(answer.rows());
    errors.rms = std::sqrt(squares / static_cast<double>(answer.rows()));
  }
  return errors;
}

std::string RegisterReportJson(const std::string& source_name, const Mesh& source,
                               const RegistrationTarget& target, const RegisterOutcome& outcome,
                               const AnswerComparison* answer) {
  using nlohmann::json;
  const RegistrationResult& result = outcome.result;
  const OptimizeResult& run = result.run;
  const double diagonal = BoundingBoxDiagonal(source);
  json levels = json::array();
  for (const LevelResult& level : run.levels) {
    json entry = {{"level", level.level},
                  {"vertices", level.vertices},
                  {"iterations", level.iterations},
                  {"objective", level.energy},
                  {"seconds", level.seconds}};
    for (const auto& [name, value] : level.measures) entry[name] = value;
    levels.push_back(entry);
  }
  double distance_sum = 0.0, distance_max = 0.0;
  for (double d : result.distance) {
    distance_sum += d;
    distance_max = std::max(distance_max, d);
  }
  const RegistrationOptions& o = outcome.options;
  json report = {{"command", "register"},
                 {"status", outcome.interrupted                ? "interrupted"
                            : result.correspondences.kept == 0 ? "no_correspondences"
                            : run.converged                    ? "converged"
                                                               : "max_updates"},
                 {"source",
                  {{"file", source_name},
                   {"vertices", source.num_vertices()},
                   {source.kind() == ElementKind::kTetrahedron ? "tetrahedra" : "triangles",
                    source.num_elements()},
                   {"bounding_box_diagonal", diagonal}}},
                 {"target",
                  {{"file", target.name},
                   {"kind", target.mesh ? "mesh" : "points"},
                   {"points", target.num_points()},
                   {"normals", target.mesh.has_value() || target.normals.rows() > 0}}},
                 {"mode", outcome.mode},
                 {"energy_type", outcome.energy_type},
                 {"solver", outcome.solver},
                 {"hierarchy", outcome.hierarchy},
                 {"upsampler", outcome.upsampler},
                 {"threads", outcome.threads},
                 {"registration",
                  {{"data_weight_start", o.data_weight_start},
                   {"data_weight_end", o.data_weight_end},
                   {"stages", o.stages},
                   {"refine_stages", o.refine_stages},
                   {"max_updates", o.max_updates},
                   {"tolerance", o.tolerance},
                   {"inner_iterations", o.inner_iterations},
                   {"refactor_fraction", o.refactor_fraction},
                   {"max_distance", o.max_distance},
                   {"max_normal_angle", o.max_normal_angle},
                   {"reject_boundary", o.reject_boundary},
                   {"landmark_weight", o.landmark_weight}}},
                 {"arap_energy", result.arap_energy},
                 {"objective", run.energy},
                 {"residual",
                  {{"rms", result.residual_rms},
                   {"max", result.residual_max},
                   {"rms_relative", result.residual_rms / diagonal},
                   {"max_relative", result.residual_max / diagonal}}},
                 {"distance",
                  {{"mean", result.distance.empty() ? 0.0 : distance_sum / result.distance.size()},
                   {"max", distance_max}}},
                 {"correspondences",
                  {{"kept", result.correspondences.kept},
                   {"too_far", result.correspondences.too_far},
                   {"normal_angle", result.correspondences.normal_angle},
                   {"boundary", result.correspondences.boundary}}},
                 {"correspondence_updates", result.correspondence_updates},
                 {"iterations", run.total_iterations},
                 {"levels", levels},
                 {"timings",
                  {{"target", outcome.target_seconds},
                   {"hierarchy", run.timings.hierarchy},
                   {"precompute", run.timings.precompute},
                   {"constrain", run.timings.constrain},
                   {"solve", run.timings.solve},
                   {"total", run.timings.total + outcome.target_seconds}}},
                 {"notes", run.notes},
                 {"peak_memory_bytes", PeakMemoryBytes()},
                 {"huge_pages", HugePageBacking()},
                 {"config", outcome.resolved_config}};
  if (answer != nullptr) {
    const AnswerErrors& e = answer->errors;
    report["answer"] = {{"file", answer->file},
                        {"mean_error", e.mean},
                        {"max_error", e.max},
                        {"rms_error", e.rms},
                        {"mean_error_relative", e.mean / e.diagonal},
                        {"max_error_relative", e.max / e.diagonal},
                        {"rms_error_relative", e.rms / e.diagonal},
                        {"worst_vertex", e.worst_vertex}};
  }
  return report.dump(2);
}

}  // namespace harap
