// SPDX-License-Identifier: MIT
#include "solvers/optimizers/deformation_session.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>

#include "framework/error.h"
#include "solvers/optimizers/classic_optimizer.h"
#include "solvers/optimizers/level_setup_pipeline.h"

namespace harap {

SessionOptions SessionOptions::FromConfig(const ConfigNode& node) {
  SessionOptions options;
  const std::string type =
      node.GetChoice("type", "classic", {"classic", "hierarchical"},
                     "which optimizer (a session runs classic or hierarchical)");
  if (type == "classic") {
    options.optimizer.iterations = ClassicOptimizer::Options::FromConfig(node).iterations;
  } else {
    options.hierarchical = true;
    options.optimizer = HierarchicalOptimizer::Options::FromConfig(node);
    if (options.optimizer.inner != HierarchicalOptimizer::Inner::kLocalGlobal) {
      throw ConfigError(
          fmt::format("{}: a session runs the local/global iteration on every "
                      "level; the ADMM inner optimizers are for one-shot runs",
                      node.Where("inner")));
    }
  }
  if (options.optimizer.iterations.newton > 0) {
    throw ConfigError(fmt::format(
        "{}: Newton steps work on the eliminated global system of a one-shot run; a session "
        "masks its handles instead: set newton = 0 (anderson works in a session)",
        node.Where("newton")));
  }
  return options;
}

SessionOptions::FrameStart SessionOptions::ParseFrameStart(std::string_view name) {
  if (name == "corrected") return FrameStart::kCorrected;
  if (name == "upsampled") return FrameStart::kUpsampled;
  if (name == "previous") return FrameStart::kPrevious;
  throw ConfigError(
      fmt::format("unknown frame start '{}': valid are corrected, upsampled, previous", name));
}

std::string_view SessionOptions::FrameStartName(FrameStart start) {
  switch (start) {
    case FrameStart::kCorrected:
      return "corrected";
    case FrameStart::kUpsampled:
      return "upsampled";
    case FrameStart::kPrevious:
      return "previous";
  }
  return "?";
}

struct DeformationSession::Level {
  std::unique_ptr<LocalGlobalSolver> solver;
  LevelConstraints constraints;  ///< coarse levels: in the mesh's numbering
  LevelConstraints internal;     ///< the same in the solver's numbering (moving targets)
  LevelState state;              ///< the last solution, in the mesh's numbering
  bool has_solution = false;
  /// Coarse levels: `constraints.mean_target` is not yet mapped from the current targets.
  bool targets_stale = false;
  /// The session's problem version `state` solves (DeformationSession::version_).
  long long version = -1;
};

DeformationSession::DeformationSession(const Mesh& mesh, const ComponentFactory& factory,
                                       const SessionOptions& options, const Context& context)
    : mesh_(mesh), factory_(factory), options_(options), context_(context) {
  Stopwatch clock;
  context_.Run([&] {
    diagonal_ = BoundingBoxDiagonal(mesh_);
    start_positions_ = mesh_.vertices;
    Stopwatch phase;
    if (options_.hierarchical) {
      context_.ReportPhase("building the hierarchy");
      hierarchy_ = factory_.MakeHierarchy()->Build(mesh_, context_);
      upsampler_ = factory_.MakeUpsampler();
    }
    setup_timings_.hierarchy = phase.Seconds();
    const int levels = num_levels();
    const int coarsest = levels - 1;
    std::vector<bool> solved(levels, false);
    solved[0] = solved[coarsest] = true;
    const HierarchicalOptimizer::Options& o = options_.optimizer;
    if (options_.hierarchical && !o.coarsest_only && !o.coarse_approximation) {
      for (int l = coarsest; l >= 0; l -= o.level_step) solved[l] = true;
    }
    levels_.resize(levels);
    for (int l = coarsest; l >= 0; --l) {
      if (!solved[l]) continue;
      solved_levels_.push_back(l);
      levels_[l] = std::make_unique<Level>();
      // Coarse levels' energies are normalized like the input mesh's (Energy::SetInputMesh).
      levels_[l]->solver =
          std::make_unique<LocalGlobalSolver>(l == 0 ? mesh_ : hierarchy_.levels[l].mesh, factory_,
                                              l, context_, l > 0 ? &mesh_ : nullptr);
      setup_timings_.precompute += levels_[l]->solver->precompute_seconds();
    }
    site_ = levels_[coarsest]->solver->energy().rotation_site();
  });
  setup_timings_.total = clock.Seconds();
}

DeformationSession::~DeformationSession() = default;

int DeformationSession::num_levels() const {
  return options_.hierarchical ? hierarchy_.num_levels() : 1;
}

const Positions& DeformationSession::positions() const {
  return levels_[0]->has_solution ? levels_[0]->state.positions : start_positions_;
}

void DeformationSession::ValidateIndices(const std::vector<Index>& indices,
                                         const char* what) const {
  if (indices.empty()) throw InputError(fmt::format("{}: no vertex indices given", what));
  std::vector<unsigned char> seen(mesh_.num_vertices(), 0);
  for (size_t k = 0; k < indices.size(); ++k) {
    const Index v = indices[k];
    if (v < 0 || v >= mesh_.num_vertices()) {
      throw InputError(
          fmt::format("{}: vertex index {} (entry {}) is out of range (the mesh "
                      "has {} vertices)",
                      what, v, k, mesh_.num_vertices()));
    }
    if (seen[v]) {
      throw InputError(fmt::format("{}: vertex {} is given twice (entry {})", what, v, k));
    }
    seen[v] = 1;
  }
}

void DeformationSession::ValidateTargets(const Positions& targets, size_t count,
                                         const char* what) const {
  if (static_cast<size_t>(targets.rows()) != count) {
    throw InputError(
        fmt::format("{}: {} targets for {} handle vertices", what, targets.rows(), count));
  }
  for (Index k = 0; k < targets.rows(); ++k) {
    if (!targets.row(k).allFinite()) {
      throw InputError(fmt::format("{}: target {} is not finite ({}, {}, {})", what, k,
                                   targets(k, 0), targets(k, 1), targets(k, 2)));
    }
    if (mesh_.planar && targets(k, 2) != 0.0) {
      throw InputError(fmt::format("{}: the mesh is planar (z = 0) but target {} has z = {}", what,
                                   k, targets(k, 2)));
    }
  }
}

HandleEditResult DeformationSession::SetHandles(const std::vector<Index>& indices) {
  ValidateIndices(indices, "SetHandles");
  const Positions& current = positions();
  Positions targets(indices.size(), 3);
  for (size_t k = 0; k < indices.size(); ++k) targets.row(k) = current.row(indices[k]);
  return ApplyHandles(indices, std::move(targets));
}

HandleEditResult DeformationSession::SetHandles(const std::vector<Index>& indices,
                                                const Positions& targets) {
  ValidateIndices(indices, "SetHandles");
  ValidateTargets(targets, indices.size(), "SetHandles");
  return ApplyHandles(indices, targets);
}

void DeformationSession::SetTargets(const Positions& targets) {
  if (handles_.empty()) throw InputError("SetTargets: the session has no handles yet (SetHandles)");
  ValidateTargets(targets, handles_.size(), "SetTargets");
  targets_ = targets;
  ++version_;
  // Mapped when a solve uses the level (a preview uses only the coarsest one).
  for (int l : solved_levels_) {
    if (l != 0) levels_[l]->targets_stale = true;
  }
}

HandleEditResult DeformationSession::AddHandles(const std::vector<Index>& indices,
                                                const Positions& targets) {
  ValidateIndices(indices, "AddHandles");
  ValidateTargets(targets, indices.size(), "AddHandles");
  const std::unordered_set<Index> current(handles_.begin(), handles_.end());
  for (Index v : indices) {
    if (current.count(v)) {
      throw InputError(
          fmt::format("AddHandles: vertex {} is a handle already (move it with "
                      "SetTargets)",
                      v));
    }
  }
  std::vector<Index> handles = handles_;
  handles.insert(handles.end(), indices.begin(), indices.end());
  Positions all(handles.size(), 3);
  all.topRows(targets_.rows()) = targets_;
  all.bottomRows(targets.rows()) = targets;
  return ApplyHandles(std::move(handles), std::move(all));
}

HandleEditResult DeformationSession::RemoveHandles(const std::vector<Index>& indices) {
  ValidateIndices(indices, "RemoveHandles");
  std::unordered_set<Index> removed(indices.begin(), indices.end());
  const std::unordered_set<Index> current(handles_.begin(), handles_.end());
  for (Index v : indices) {
    if (!current.count(v)) {
      throw InputError(fmt::format("RemoveHandles: vertex {} is not a handle", v));
    }
  }
  if (removed.size() == handles_.size()) {
    throw InputError(
        "RemoveHandles: this would remove every handle; a session needs at least "
        "one (use SetHandles to replace them)");
  }
  std::vector<Index> handles;
  Positions targets(handles_.size() - removed.size(), 3);
  for (size_t k = 0; k < handles_.size(); ++k) {
    if (removed.count(handles_[k])) continue;
    targets.row(static_cast<Index>(handles.size())) = targets_.row(k);
    handles.push_back(handles_[k]);
  }
  return ApplyHandles(std::move(handles), std::move(targets));
}

void DeformationSession::SetPositions(const Positions& positions) {
  if (positions.rows() != mesh_.num_vertices()) {
    throw InputError(fmt::format("SetPositions: {} positions for a mesh of {} vertices",
                                 positions.rows(), mesh_.num_vertices()));
  }
  if (!positions.allFinite()) throw InputError("SetPositions: the positions are not all finite");
  if (mesh_.planar && positions.col(2).cwiseAbs().maxCoeff() != 0.0) {
    throw InputError("SetPositions: the mesh is planar (z = 0) but the positions are not");
  }
  start_positions_ = positions;
  ++version_;
  preview_rotations_pending_ = false;
  for (const auto& level : levels_) {
    if (level) {
      level->has_solution = false;
      level->state = LevelState();
    }
  }
}

HandleEditResult DeformationSession::ApplyHandles(std::vector<Index> indices, Positions targets) {
  std::vector<Index> old_handles = std::move(handles_);
  Positions old_targets = std::move(targets_);
  handles_ = std::move(indices);
  targets_ = std::move(targets);
  ++version_;
  try {
    return ConstrainLevels();
  } catch (...) {
    // A failed factorization (out of memory): go back to the previous handles, so the session
    // stays usable with them.
    handles_ = std::move(old_handles);
    targets_ = std::move(old_targets);
    if (!handles_.empty()) ConstrainLevels();
    throw;
  }
}

HandleEditResult DeformationSession::ConstrainLevels() {
  Stopwatch clock;
  HandleEditResult result;
  // Creating a level's linear solver reads config tables: two threads take turns.
  const SerializedFactory factory(factory_);
  std::vector<HandleEditResult::Level> done(levels_.size());
  const Constraints finest{handles_, targets_};
  const auto constrain = [&](int l) {
    Level& level = *levels_[l];
    LocalGlobalSolver& solver = *level.solver;
    LocalGlobalSolver::ConstrainSummary summary;
    Index constrained = static_cast<Index>(handles_.size());
    if (l == 0) {
      summary = solver.ConstrainMasked(handles_, factory, context_);
    } else {
      // As the hierarchical optimizer's level setup: clusters holding a handle are
      // constrained; per-element energies average the rotations of the incident elements.
      const Mesh& level_mesh = hierarchy_.levels[l].mesh;
      level.constraints = MapConstraints(hierarchy_, l, finest);
      level.targets_stale = false;
      if (site_ == RotationSite::kElement) {
        auto& incident = level.constraints.incident_elements;
        incident.assign(level.constraints.vertices.size(), {});
        std::vector<Index> slot(level_mesh.num_vertices(), kNoVertex);
        for (size_t k = 0; k < level.constraints.vertices.size(); ++k) {
          slot[level.constraints.vertices[k]] = static_cast<Index>(k);
        }
        for (Index e = 0; e < level_mesh.num_elements(); ++e) {
          for (int a = 0; a < level_mesh.simplex_size(); ++a) {
            if (slot[level_mesh.elements(e, a)] != kNoVertex) {
              incident[slot[level_mesh.elements(e, a)]].push_back(e);
            }
          }
        }
      }
      const MeshOrdering& ordering = solver.ordering();
      level.internal = level.constraints;
      for (Index& v : level.internal.vertices) v = ordering.new_vertex[v];
      for (auto& elements : level.internal.incident_elements) {
        for (Index& e : elements) e = ordering.new_element[e];
      }
      constrained = static_cast<Index>(level.constraints.vertices.size());
      summary = solver.ConstrainMasked(level.constraints.vertices, factory, context_);
    }
    done[l] = HandleEditResult::Level{
        l, constrained, summary.changed_rows, summary.factored, summary.route, summary.seconds};
  };
  context_.Run([&] {
    // The levels are independent: the finest level (most of the work) in this thread, the
    // coarse ones beside it in a task, as the hierarchical optimizer overlaps its level set-ups
    // (CHOLMOD factors on one thread by default, so two factorizations use both cores).
    std::vector<int> coarse;
    for (int l : solved_levels_) {
      if (l != 0) coarse.push_back(l);
    }
    const bool has_finest = levels_[0] != nullptr;
    if (coarse.empty() || !has_finest || tbb::this_task_arena::max_concurrency() < 2) {
      for (auto it = solved_levels_.rbegin(); it != solved_levels_.rend(); ++it) constrain(*it);
      return;
    }
    tbb::task_group group;
    group.run([&] {
      for (int l : coarse) constrain(l);
    });
    try {
      constrain(0);
    } catch (...) {
      try {
        group.wait();
      } catch (...) {
        // The finest level's error is the one reported.
      }
      throw;
    }
    group.wait();
  });
  // Finest first, as before.
  for (auto it = solved_levels_.rbegin(); it != solved_levels_.rend(); ++it) {
    result.levels.push_back(done[*it]);
  }
  result.constraints = levels_[0]->solver->system().report();
  result.notes = DescribeConstraintHandling(result.constraints);
  result.seconds = clock.Seconds();
  return result;
}

void DeformationSession::UpdateCoarseTargets(int l) {
  Level& level = *levels_[l];
  if (l == 0 || !level.targets_stale) return;
  // The constrained vertices are the same (same handles): only the mean targets move.
  const LevelConstraints mapped = MapConstraints(hierarchy_, l, Constraints{handles_, targets_});
  level.constraints.mean_target = mapped.mean_target;
  level.internal.mean_target = mapped.mean_target;
  level.targets_stale = false;
}

void DeformationSession::MaterializePreviewRotations() {
  if (!preview_rotations_pending_) return;
  Rotations& rotations = levels_[0]->state.rotations;
  rotations.resize(preview_map_.size());
  context_.Run([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, preview_map_.size(), 4096),
                      [&](const tbb::blocked_range<size_t>& range) {
                        for (size_t v = range.begin(); v != range.end(); ++v) {
                          const Index c = preview_map_[v];
                          rotations[v] = c == kNoVertex ? Rotation::Identity()
                                                        : preview_coarse_rotations_[c];
                        }
                      });
  });
  preview_rotations_pending_ = false;
}

OptimizeResult DeformationSession::Solve(const SessionSolveOptions& options) {
  if (options.time_budget_seconds < 0.0 || !std::isfinite(options.time_budget_seconds)) {
    throw InputError(fmt::format("Solve: the time budget must be >= 0 seconds, got {}",
                                 options.time_budget_seconds));
  }
  if (std::isnan(options.tolerance)) throw InputError("Solve: the tolerance is NaN");
  return Run(options, /*preview=*/false);
}

OptimizeResult DeformationSession::Preview() { return Run({}, /*preview=*/true); }

double DeformationSession::CurrentEnergy() {
  MaterializePreviewRotations();
  // Kept buffers: called after every preview frame of a drag, where fresh 10 MB arrays (page
  // faults, unmapping) slowed the next frames down.
  LevelState& state = energy_state_;
  state.positions = positions();
  if (levels_[0]->has_solution) {
    state.rotations = levels_[0]->state.rotations;
  } else {
    state.rotations.clear();
  }
  return context_.Run(
      [&] { return levels_[0]->solver->FitRotationsKeptBuffers(state, context_); });
}

OptimizeResult DeformationSession::Run(const SessionSolveOptions& solve_options, bool preview) {
  if (handles_.empty()) {
    throw InputError(fmt::format("{}: the session has no handles yet (SetHandles)",
                                 preview ? "Preview" : "Solve"));
  }
  Stopwatch total;
  OptimizeResult result;
  const int coarsest = num_levels() - 1;
  const HierarchicalOptimizer::Options& o = options_.optimizer;
  // The cascade from the coarsest level, or the finest level alone from its previous solution.
  const bool cascade = preview || options_.frame_start != SessionOptions::FrameStart::kPrevious ||
                       !levels_[0]->has_solution;
  const int top = cascade ? coarsest : 0;

  Context context = context_;
  context.run_clock.Restart();
  bool user_stop = false;
  bool out_of_time = false;
  int out_of_time_level = -1;
  context.iteration_callback = [&](const IterationSummary& summary) {
    if (callback_ && callback_(summary) == CallbackAction::kStop) {
      user_stop = true;
      return CallbackAction::kStop;
    }
    if (solve_options.time_budget_seconds > 0.0 &&
        context.run_clock.Seconds() > solve_options.time_budget_seconds) {
      if (!out_of_time) out_of_time_level = summary.level;
      out_of_time = true;
      return CallbackAction::kStop;
    }
    return CallbackAction::kContinue;
  };

  std::vector<std::string> frozen_target_notes;
  // The states are kept between solves (work_[l], scratch_[l]: no allocation per frame on the
  // big levels). `cur` is the state being solved or handed down; a solved level's result is
  // swapped into its Level, so work_[l] then holds the level's previous solution.
  if (work_.size() != static_cast<size_t>(num_levels())) {
    work_.assign(num_levels(), LevelState());
    scratch_.assign(num_levels(), LevelState());
  }
  LevelState* cur = nullptr;
  bool start_with_global_step = false;
  // FrameStart::kCorrected: the level whose previous solution (before this solve) is in work_.
  int coarse_before_level = -1;
  // A preview whose upsampler only copies each coarse vertex's rotation down: straight from the
  // coarsest level to the finest along the composed map (the paper's Fig. 15), one parallel
  // gather into the kept state instead of up-sampling positions and rotations through every
  // level (fresh arrays per level). The finest level's rotations are the same; its positions
  // are not up-sampled: the global step overwrites every free row and sets the handles' rows,
  // so with a direct solver the result is identical (an iterative one starts from the last
  // frame's positions instead of the up-sampled ones).
  const bool straight = preview && preview_straight_ && top > 0 &&
                        upsampler_->output() == UpsampleOutput::kRotations &&
                        upsampler_->RotationsFollowCoarseVertex(site_);
  if (straight && preview_map_.empty()) {
    preview_map_.resize(mesh_.num_vertices());
    for (Index v = 0; v < mesh_.num_vertices(); ++v) {
      preview_map_[v] = hierarchy_.MapFinestVertex(v, top);
    }
  }
  // With per-vertex rotations the finest level's global step reads the coarse rotations
  // straight into its own numbering (no finest rotations in the mesh's numbering at all).
  const bool gathered = straight && site_ == RotationSite::kVertex &&
                        levels_[0]->solver->energy().num_rotations() == mesh_.num_vertices();
  if (gathered && preview_source_.empty()) {
    const std::vector<Index>& old_vertex = levels_[0]->solver->ordering().old_vertex;
    preview_source_.resize(old_vertex.size());
    for (size_t s = 0; s < old_vertex.size(); ++s) preview_source_[s] = preview_map_[old_vertex[s]];
  }
  // Whatever this solve reads of the finest level's last rotations must be there.
  if (!preview) MaterializePreviewRotations();
  context.Run([&] {
    for (int l = top; l >= 0; --l) {
      LevelState& work = work_[l];
      if (straight && l != top && l != 0) continue;  // the levels in between: skipped
      // (A stop on a coarse level finishes from the up-sampled state: gathered in the mesh's
      // numbering below.)
      const bool gather_step = gathered && l == 0 && !user_stop;
      if (gather_step) {
        // GatheredGlobalStep below gathers these (the coarsest level's solution).
        preview_coarse_rotations_ = cur->rotations;
        if (work.positions.rows() != mesh_.num_vertices()) work.positions = start_positions_;
        start_with_global_step = true;
      } else if (straight && l == 0) {
        const Rotations& coarse = cur->rotations;
        if (work.positions.rows() != mesh_.num_vertices()) work.positions = start_positions_;
        work.rotations.resize(preview_map_.size());
        tbb::parallel_for(tbb::blocked_range<size_t>(0, preview_map_.size(), 4096),
                          [&](const tbb::blocked_range<size_t>& range) {
                            for (size_t v = range.begin(); v != range.end(); ++v) {
                              const Index c = preview_map_[v];
                              work.rotations[v] = c == kNoVertex ? Rotation::Identity() : coarse[c];
                            }
                          });
        start_with_global_step = true;
      } else if (l == top) {
        Level* level = levels_[l].get();
        if (level->has_solution) {
          // Warm start: the previous solution's rotations drive the first global step, which
          // places the (moved) handles' influence smoothly over the mesh.
          work = level->state;
          start_with_global_step = true;
        } else {
          work.positions = l == 0 ? start_positions_ : hierarchy_.levels[l].mesh.vertices;
          work.rotations.clear();
          start_with_global_step = false;
        }
      } else if (levels_[l] && levels_[l]->has_solution && levels_[l]->version == version_ &&
                 !preview) {
        // Nothing changed since this level's last solution: it is the best start there is (an
        // up-sampled one would start the level's iterations over).
        work = levels_[l]->state;
        start_with_global_step = true;
      } else if (options_.frame_start == SessionOptions::FrameStart::kCorrected && !preview &&
                 levels_[l] && levels_[l]->has_solution && coarse_before_level == l + 1 &&
                 work_[l + 1].rotations.size() == cur->rotations.size()) {
        // Coarse-grid correction: the level's previous solution (its fine detail) moved by what
        // the coarser level's solution changed since then (the smooth motion), up-sampled.
        LevelState& now = scratch_[l];
        upsampler_->Upsample(hierarchy_.levels[l], hierarchy_.levels[l + 1], site_, *cur, now,
                             context);
        upsampler_->Upsample(hierarchy_.levels[l], hierarchy_.levels[l + 1], site_, work_[l + 1],
                             work, context);
        work.positions = levels_[l]->state.positions + now.positions - work.positions;
        work.rotations = levels_[l]->state.rotations;
        start_with_global_step = false;
      } else {
        upsampler_->Upsample(hierarchy_.levels[l], hierarchy_.levels[l + 1], site_, *cur, work,
                             context);
        start_with_global_step = upsampler_->output() == UpsampleOutput::kRotations;
      }
      cur = &work;
      LevelState& state = work;
      Level* level = levels_[l].get();
      if (level == nullptr) continue;  // not a solved level: only up-sampled
      if (preview && l != top && l != 0) continue;
      if (l > 0 && (user_stop || out_of_time)) continue;  // finish on the finest level
      LocalGlobalSolver& solver = *level->solver;
      if (user_stop) {
        // As a one-shot run stopped on a coarse level: the up-sampled state, rotations fitted.
        result.energy = solver.FitRotations(state, context);
        level->state = state;
        level->has_solution = true;
        cur = &level->state;
        break;
      }
      Stopwatch level_clock;
      LocalGlobalOptions options = o.iterations;
      if (solve_options.tolerance >= 0.0) options.tolerance = solve_options.tolerance;
      if (solve_options.max_iterations > 0) options.max_iterations = solve_options.max_iterations;
      if (l > 0 && o.coarse_tolerance >= 0.0) options.tolerance = o.coarse_tolerance;
      const bool approximation = o.coarse_approximation && coarsest > 0;
      if (l == 0 && (preview || out_of_time || approximation)) options.max_iterations = 1;
      LocalGlobalSolver::FixedPositionUpdate update;
      if (l == 0) {
        for (size_t k = 0; k < handles_.size(); ++k) {
          state.positions.row(handles_[k]) = targets_.row(static_cast<Index>(k));
        }
      } else {
        UpdateCoarseTargets(l);
        const bool have_rotations =
            static_cast<Index>(state.rotations.size()) == solver.energy().num_rotations();
        PlaceConstrainedVertices(level->constraints, site_,
                                 have_rotations ? &state.rotations : nullptr, state.positions);
        if (o.update_constraints) {
          update = [&, level](const Rotations& rotations, Positions& positions) {
            PlaceConstrainedVertices(level->internal, site_, &rotations, positions);
          };
        }
      }
      const bool was_out_of_time = out_of_time;
      const bool had_solution = level->has_solution;
      LocalGlobalSolver::RunResult run;
      if (gather_step) {
        // The straight preview: the coarsest rotations gathered into the level's own
        // numbering by the global step; the finest rotations stay pending.
        run.linear_solves.Add(solver.GatheredGlobalStep(preview_source_, preview_coarse_rotations_,
                                                        handles_, targets_, state.positions,
                                                        context));
        run.iterations = 1;
        run.energy = std::numeric_limits<double>::quiet_NaN();
      } else if (l == 0 && preview && start_with_global_step &&
          static_cast<Index>(state.rotations.size()) == solver.energy().num_rotations()) {
        // The paper's approximation: one global solve from the up-sampled rotations, no local
        // step (the energy is left to CurrentEnergy()).
        run.linear_solves.Add(solver.GlobalStep(state, context));
        run.iterations = 1;
        run.energy = std::numeric_limits<double>::quiet_NaN();
      } else {
        run = solver.Run(state, start_with_global_step, options, diagonal_, context, update);
      }
      // The new solution into the Level; work_[l] keeps the previous one (the correction of
      // the next finer level needs it).
      std::swap(level->state, work);
      cur = &level->state;
      if (l == 0) preview_rotations_pending_ = gather_step;
      level->has_solution = true;
      coarse_before_level = had_solution ? l : -1;
      // A stopped run or a preview is no finished solution: the next solve redoes the level.
      level->version = run.stopped_by_callback || preview ? version_ - 1 : version_;
      if (run.targets_frozen_at > 0) {
        frozen_target_notes.push_back(
            fmt::format("level {}: coarse constraint targets stopped following the rotations after "
                        "iteration {} (the energy kept rising)",
                        l, run.targets_frozen_at));
      }
      result.total_iterations += run.iterations;
      result.levels.push_back(
          LevelResult{l, solver.system().num_vertices(),
                      l == 0 ? mesh_.num_elements() : hierarchy_.levels[l].mesh.num_elements(),
                      run.iterations, run.energy, level_clock.Seconds(), run.converged,
                      solver.system().num_free(), run.linear_solves});
      RecordAcceleration(options, run, result.levels.back());
      if (l == 0) {
        result.energy = run.energy;
        result.iterations = run.iterations;
        result.converged = run.converged && !was_out_of_time;
      }
    }
  });
  result.stopped_by_callback = user_stop;
  std::reverse(result.levels.begin(), result.levels.end());
  LocalGlobalSolver& finest = *levels_[0]->solver;
  // A preview's rotations are not fitted to its positions: no measures of that state.
  if (!preview) {
    result.measures = context.Run([&] { return finest.AuxiliaryMeasures(*cur, context); });
  }
  result.constraints = finest.system().report();
  std::vector<std::string> notes = DescribeConstraintHandling(result.constraints);
  result.notes.insert(result.notes.begin(), notes.begin(), notes.end());
  if (out_of_time) {
    result.notes.push_back(fmt::format(
        "the time budget of {} s ran out on level {}{}", solve_options.time_budget_seconds,
        out_of_time_level,
        out_of_time_level > 0 ? "; the finest level did one iteration from the up-sampled state"
                              : ""));
  }
  result.notes.insert(result.notes.end(), frozen_target_notes.begin(), frozen_target_notes.end());
  result.positions = cur->positions;
  result.timings.solve = total.Seconds();
  result.timings.total = result.timings.solve;
  return result;
}

}  // namespace harap
