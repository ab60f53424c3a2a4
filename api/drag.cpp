// SPDX-License-Identifier: MIT
#include "api/drag.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>

#include "api/component_factory.h"
#include "api/session.h"
#include "framework/error.h"
#include "io/mesh_writers.h"

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
  const Eigen::Matrix3d covariance =
      (handle.targets.rowwise() - target_center).transpose() * (rest.rowwise() - motion.center);
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
      handle.targets.row(k) = (r * (rest - motion.center).transpose()).transpose() + motion.center +
                              t * motion.translation + t * motion.remainder.row(k);
    }
  }
  // Merged as the scenario does (first handle wins), without copying the mesh.
  return MergeHandles(scenario.mesh.num_vertices(), handles);
}

DragOutcome RunDrag(const Registries& registries, const Scenario& scenario,
                    const ConfigNode& config, const DragOptions& options) {
  if (options.frames < 1) {
    throw InputError(fmt::format("--frames must be >= 1, got {}", options.frames));
  }
  if (options.from_scratch && !options.edits.empty()) {
    throw InputError("--edits needs a session (not --from-scratch)");
  }
  if (options.preview && options.from_scratch) {
    throw InputError("--preview and --from-scratch exclude each other");
  }
  if (!(options.frame_budget_ms >= 0.0)) {
    throw InputError(
        fmt::format("--frame-budget-ms must be >= 0, got {}", options.frame_budget_ms));
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
                                       result.notes, std::nullopt, ""});
    outcome.frames_seconds += seconds;
    write_frame(frame, result.positions);
  };

  if (options.from_scratch) {
    const ResolvedRunConfig run(registries, config, scenario.mesh);
    const auto& optimizer = run.optimizer;
    const RegistryComponentFactory& factory = run.factory;
    outcome.optimizer = run.optimizer_name;
    // The mesh and its stiffness are the same for every frame; only the targets move.
    DeformationProblem problem;
    problem.mesh = &scenario.mesh;
    problem.stiffness = scenario.ElementStiffness();
    for (int frame = 1; frame <= options.frames; ++frame) {
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
                                options.frame_start, scenario.ElementStiffness());
  outcome.setup_seconds = setup_clock.Seconds();
  outcome.optimizer = configured->optimizer();
  DeformationSession& session = configured->session();
  if (options.progress) session.set_iteration_callback(options.progress);
  const Constraints first = FrameConstraints(scenario, 1.0 / options.frames);
  // Soft handles (a scenario handle's `weight`) stay soft in the session: SetTargets moves them.
  const HandleEditResult constrained =
      session.SetHandles(first.indices, first.targets, first.weights);
  outcome.constrain_seconds = constrained.seconds;
  outcome.notes = constrained.notes;
  SessionSolveOptions solve;
  solve.time_budget_seconds = options.frame_budget_ms / 1000.0;
  // Handles added by edits: name -> vertices that were no handles before (held in place).
  std::map<std::string, std::vector<Index>> added;
  std::vector<Index> added_vertices;  // all of them, in the order the session holds them
  Positions added_targets(0, 3);
  for (int frame = 1; frame <= options.frames; ++frame) {
    std::optional<HandleEditResult> edit;
    std::string description;
    for (const HandleEdit& request : options.edits) {
      if (request.frame != frame) continue;
      // Vertices that are handles already (the scenario's or an earlier edit's) stay as they are.
      std::vector<unsigned char> is_handle(scenario.mesh.num_vertices(), 0);
      for (Index v : session.handles()) is_handle[v] = 1;
      if (request.add) {
        if (added.count(request.name)) {
          throw InputError(fmt::format("edit at frame {}: a handle '{}' was added already", frame,
                                       request.name));
        }
        std::vector<Index> fresh;
        for (Index v : request.vertices) {
          if (!is_handle[v]) fresh.push_back(v);
        }
        if (fresh.empty()) {
          throw InputError(fmt::format("edit at frame {}: '{}' selects only handle vertices", frame,
                                       request.name));
        }
        Positions held(fresh.size(), 3);
        for (size_t k = 0; k < fresh.size(); ++k) {
          held.row(static_cast<Index>(k)) = session.positions().row(fresh[k]);
        }
        edit = session.AddHandles(fresh, held);
        description = fmt::format("add '{}' ({} vertices)", request.name, fresh.size());
        added[request.name] = fresh;
        added_vertices.insert(added_vertices.end(), fresh.begin(), fresh.end());
        added_targets.conservativeResize(added_targets.rows() + held.rows(), 3);
        added_targets.bottomRows(held.rows()) = held;
      } else {
        const auto it = added.find(request.name);
        if (it == added.end()) {
          throw InputError(fmt::format("edit at frame {}: no handle '{}' was added to remove",
                                       frame, request.name));
        }
        edit = session.RemoveHandles(it->second);
        description = fmt::format("remove '{}' ({} vertices)", request.name, it->second.size());
        std::vector<unsigned char> removed(scenario.mesh.num_vertices(), 0);
        for (Index v : it->second) removed[v] = 1;
        std::vector<Index> kept;
        Positions kept_targets(added_targets.rows() - static_cast<Index>(it->second.size()), 3);
        for (size_t k = 0; k < added_vertices.size(); ++k) {
          if (removed[added_vertices[k]]) continue;
          kept_targets.row(static_cast<Index>(kept.size())) =
              added_targets.row(static_cast<Index>(k));
          kept.push_back(added_vertices[k]);
        }
        added_vertices = std::move(kept);
        added_targets = std::move(kept_targets);
        added.erase(it);
      }
    }
    // The frame's time starts with handing the targets to the session (computing them is the
    // interaction's business, not the solver's).
    Positions targets;
    if (frame > 1) {
      const Constraints scenario_targets =
          FrameConstraints(scenario, static_cast<double>(frame) / options.frames);
      targets.resize(scenario_targets.targets.rows() + added_targets.rows(), 3);
      targets << scenario_targets.targets, added_targets;
    }
    Stopwatch clock;
    if (frame > 1) session.SetTargets(targets);
    OptimizeResult result = options.preview ? session.Preview() : session.Solve(solve);
    const double seconds = clock.Seconds();
    // A preview leaves the energy to the caller: evaluated here, outside the frame's time.
    if (options.preview) result.energy = session.CurrentEnergy();
    record(frame, seconds, result);
    outcome.frames.back().edit = edit;
    outcome.frames.back().edit_description = description;
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
    json entry = {{"frame", frame.frame},
                  {"levels", levels},
                  {"notes", frame.notes},
                  {"seconds", frame.seconds},
                  {"energy", frame.energy},
                  {"iterations", frame.iterations},
                  {"total_iterations", frame.total_iterations},
                  {"converged", frame.converged}};
    if (frame.edit) {
      json edit_levels = json::array();
      for (const auto& level : frame.edit->levels) {
        edit_levels.push_back({{"level", level.level},
                               {"constrained_vertices", level.constrained_vertices},
                               {"changed_rows", level.changed_rows},
                               {"factored", level.factored},
                               {"route", std::string(RefactorRouteName(level.route))},
                               {"seconds", level.seconds}});
      }
      entry["edit_seconds"] = frame.edit->seconds;
      entry["edit"] = {{"description", frame.edit_description}, {"levels", edit_levels}};
    }
    frames.push_back(entry);
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
  std::string table =
      fmt::format("mode {}  optimizer {}  setup {:.3f} s  constrain {:.3f} s\n", outcome.mode,
                  outcome.optimizer, outcome.setup_seconds, outcome.constrain_seconds);
  table += fmt::format("{:>5} {:>10} {:>16} {:>10} {:>8} {:>9}\n", "frame", "seconds", "energy",
                       "iterations", "total", "converged");
  for (const DragFrame& frame : outcome.frames) {
    table += fmt::format("{:>5} {:>10.4f} {:>16.9e} {:>10} {:>8} {:>9}\n", frame.frame,
                         frame.seconds, frame.energy, frame.iterations, frame.total_iterations,
                         frame.converged ? "yes" : "no");
    if (frame.edit) {
      table += fmt::format("      edit before frame {}: {} in {:.4f} s (", frame.frame,
                           frame.edit_description, frame.edit->seconds);
      for (size_t k = 0; k < frame.edit->levels.size(); ++k) {
        const auto& level = frame.edit->levels[k];
        table += fmt::format(
            "{}level {}: {} rows, {} {:.4f} s", k ? "; " : "", level.level, level.changed_rows,
            level.factored ? RefactorRouteName(level.route) : "none", level.seconds);
      }
      table += ")\n";
    }
  }
  table += fmt::format("frames: {:.3f} s in all\n", outcome.frames_seconds);
  for (const auto& note : outcome.notes) table += fmt::format("note  {}\n", note);
  return table;
}

}  // namespace harap
