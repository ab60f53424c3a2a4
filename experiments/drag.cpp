// SPDX-License-Identifier: MIT
#include "experiments/drag.h"

#include <fmt/format.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "experiments/component_factory.h"
#include "experiments/session.h"
#include "framework/error.h"
#include "framework/io/mesh_io.h"

namespace harap {

namespace {

// The rigid motion x -> rotation (x - center) + center + translation closest to the handle's
// rest -> target map (Kabsch), and the per-vertex remainder.
struct HandleMotion {
  Eigen::AngleAxisd rotation{0.0, Eigen::Vector3d::UnitZ()};
  Eigen::RowVector3d center = Eigen::RowVector3d::Zero();
  Eigen::RowVector3d translation = Eigen::RowVector3d::Zero();
  Positions remainder;
};

HandleMotion FitMotion(const Mesh& mesh, const ScenarioHandle& handle) {
  HandleMotion motion;
  const Index count = static_cast<Index>(handle.vertices.size());
  Positions rest(count, 3);
  for (Index k = 0; k < count; ++k) rest.row(k) = mesh.vertices.row(handle.vertices[k]);
  motion.center = rest.colwise().mean();
  const Eigen::RowVector3d target_center = handle.targets.colwise().mean();
  const Eigen::Matrix3d covariance = (handle.targets.rowwise() - target_center).transpose() *
                                     (rest.rowwise() - motion.center);
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) d(2, 2) = -1.0;
  const Eigen::Matrix3d r = svd.matrixU() * d * svd.matrixV().transpose();
  motion.rotation = Eigen::AngleAxisd(r);
  motion.translation = target_center - motion.center;
  motion.remainder = handle.targets;
  for (Index k = 0; k < count; ++k) {
    const Eigen::RowVector3d moved =
        (r * (rest.row(k) - motion.center).transpose()).transpose() + target_center;
    motion.remainder.row(k) -= moved;
  }
  return motion;
}

}  // namespace

Constraints FrameConstraints(const Scenario& scenario, double t) {
  std::vector<ScenarioHandle> handles = scenario.handles;
  for (ScenarioHandle& handle : handles) {
    const HandleMotion motion = FitMotion(scenario.mesh, handle);
    const Eigen::Matrix3d r =
        Eigen::AngleAxisd(motion.rotation.angle() * t, motion.rotation.axis()).toRotationMatrix();
    for (Index k = 0; k < static_cast<Index>(handle.vertices.size()); ++k) {
      const Eigen::RowVector3d rest = scenario.mesh.vertices.row(handle.vertices[k]);
      handle.targets.row(k) = (r * (rest - motion.center).transpose()).transpose() +
                              motion.center + t * motion.translation +
                              t * motion.remainder.row(k);
    }
  }
  // Merge as the scenario does (first handle wins), without copying the mesh.
  const Index n = scenario.mesh.num_vertices();
  std::vector<std::pair<int, Index>> owner(n, {-1, 0});
  for (size_t h = 0; h < handles.size(); ++h) {
    for (size_t i = 0; i < handles[h].vertices.size(); ++i) {
      const Index v = handles[h].vertices[i];
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

DragOutcome RunDrag(const Registries& registries, const Scenario& scenario,
                    const ConfigNode& config, const DragOptions& options) {
  if (options.frames < 1) {
    throw InputError(fmt::format("--frames must be >= 1, got {}", options.frames));
  }
  if (options.preview && options.from_scratch) {
    throw InputError("--preview and --from-scratch exclude each other");
  }
  if (!(options.frame_budget_ms >= 0.0)) {
    throw InputError(fmt::format("--frame-budget-ms must be >= 0, got {}",
                                 options.frame_budget_ms));
  }
  DragOutcome outcome;
  outcome.mode = options.from_scratch ? "from_scratch" : options.preview ? "preview" : "session";
  const auto write_frame = [&](int frame, const Positions& positions) {
    if (options.out_frames.empty()) return;
    std::filesystem::create_directories(options.out_frames);
    WritePly(std::filesystem::path(options.out_frames) / fmt::format("frame_{:03}.ply", frame),
             positions, scenario.mesh.elements);
  };
  const auto record = [&](int frame, double seconds, const OptimizeResult& result) {
    outcome.frames.push_back(DragFrame{frame, seconds, result.energy, result.iterations,
                                       result.total_iterations, result.converged, result.levels,
                                       result.notes});
    outcome.frames_seconds += seconds;
    write_frame(frame, result.positions);
  };

  if (options.from_scratch) {
    DefaultComponents defaults;
    if (!registries.linear_solvers.Contains(defaults.solver)) defaults.solver = "eigen_ldlt";
    if (scenario.mesh.kind() == ElementKind::kTetrahedron || scenario.mesh.planar) {
      defaults.energy = "elements";
    }
    ValidateRunConfig(config);
    auto optimizer = MakeOptimizer(registries, config, defaults);
    RegistryComponentFactory factory(registries, config, defaults);
    outcome.optimizer = config.Child("optimizer").Get("type", defaults.optimizer, "which optimizer");
    for (int frame = 1; frame <= options.frames; ++frame) {
      DeformationProblem problem;
      problem.mesh = &scenario.mesh;
      problem.constraints = FrameConstraints(scenario, static_cast<double>(frame) / options.frames);
      Context context = Context::WithThreads(options.threads);
      if (options.progress) context.iteration_callback = options.progress;
      Stopwatch clock;
      const OptimizeResult result =
          context.Run([&] { return optimizer->Optimize(problem, factory, context); });
      record(frame, clock.Seconds(), result);
    }
    outcome.resolved_config = config.ToToml();
    return outcome;
  }

  Stopwatch setup_clock;
  auto configured = MakeSession(registries, scenario.mesh, config, options.threads,
                                options.frame_start);
  outcome.setup_seconds = setup_clock.Seconds();
  outcome.optimizer = configured->optimizer();
  DeformationSession& session = configured->session();
  if (options.progress) session.set_iteration_callback(options.progress);
  const Constraints first = FrameConstraints(scenario, 1.0 / options.frames);
  const HandleEditResult constrained = session.SetHandles(first.indices, first.targets);
  outcome.constrain_seconds = constrained.seconds;
  outcome.notes = constrained.notes;
  SessionSolveOptions solve;
  solve.time_budget_seconds = options.frame_budget_ms / 1000.0;
  for (int frame = 1; frame <= options.frames; ++frame) {
    Stopwatch clock;
    if (frame > 1) {
      session.SetTargets(
          FrameConstraints(scenario, static_cast<double>(frame) / options.frames).targets);
    }
    const OptimizeResult result = options.preview ? session.Preview() : session.Solve(solve);
    record(frame, clock.Seconds(), result);
  }
  outcome.resolved_config = configured->resolved_config();
  return outcome;
}

std::string DragReportJson(const Scenario& scenario, const DragOutcome& outcome) {
  using nlohmann::json;
  json frames = json::array();
  for (const DragFrame& frame : outcome.frames) {
    json levels = json::array();
    for (const LevelResult& level : frame.levels) {
      levels.push_back({{"level", level.level},
                        {"iterations", level.iterations},
                        {"energy", level.energy},
                        {"seconds", level.seconds}});
    }
    frames.push_back({{"frame", frame.frame},
                      {"levels", levels},
                      {"notes", frame.notes},
                      {"seconds", frame.seconds},
                      {"energy", frame.energy},
                      {"iterations", frame.iterations},
                      {"total_iterations", frame.total_iterations},
                      {"converged", frame.converged}});
  }
  json report = {{"scenario", scenario.file.string()},
                 {"vertices", scenario.mesh.num_vertices()},
                 {"mode", outcome.mode},
                 {"optimizer", outcome.optimizer},
                 {"setup_seconds", outcome.setup_seconds},
                 {"constrain_seconds", outcome.constrain_seconds},
                 {"frames_seconds", outcome.frames_seconds},
                 {"frames", frames},
                 {"notes", outcome.notes},
                 {"config", outcome.resolved_config}};
  return report.dump(2);
}

std::string DragTable(const DragOutcome& outcome) {
  std::string table = fmt::format("mode {}  optimizer {}  setup {:.3f} s  constrain {:.3f} s\n",
                                  outcome.mode, outcome.optimizer, outcome.setup_seconds,
                                  outcome.constrain_seconds);
  table += fmt::format("{:>5} {:>10} {:>16} {:>10} {:>8} {:>9}\n", "frame", "seconds", "energy",
                       "iterations", "total", "converged");
  for (const DragFrame& frame : outcome.frames) {
    table += fmt::format("{:>5} {:>10.4f} {:>16.9e} {:>10} {:>8} {:>9}\n", frame.frame,
                         frame.seconds, frame.energy, frame.iterations, frame.total_iterations,
                         frame.converged ? "yes" : "no");
  }
  table += fmt::format("frames: {:.3f} s in all\n", outcome.frames_seconds);
  for (const auto& note : outcome.notes) table += fmt::format("note  {}\n", note);
  return table;
}

}  // namespace harap
