// SPDX-License-Identifier: MIT
#include "solvers/optimizers/deformation_session.h"

#include <fmt/format.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>

#include "framework/error.h"
#include "framework/stiffness.h"
#include "solvers/optimizers/level_setup_pipeline.h"
#include "solvers/optimizers/local_global_solver.h"

namespace harap {

SessionOptions SessionOptions::FromConfig(OptionReader node,
                                          const Registry<LevelSolver>& level_solvers) {
  SessionOptions options;
  const std::string type =
      node.GetChoice("type", "classic", {"classic", "hierarchical"},
                     "which optimizer (a session runs classic or hierarchical)");
  options.hierarchical = type == "hierarchical";
  // The level solvers say themselves what they cannot do in a session (handle edits).
  options.optimizer =
      options.hierarchical
          ? HierarchicalOptimizer::Options::FromConfig(node, level_solvers)
          : HierarchicalOptimizer::Options::OneLevel(node, level_solvers, LocalGlobalSolver::kName);
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
  LevelState state;  ///< the last solution, in the level numbering (level_cascade.h)
  bool has_solution = false;
  /// Coarse levels: the solver's mean targets are not yet mapped from the current targets.
  bool targets_stale = false;
  /// The session's problem version `state` solves (DeformationSession::version_).
  long long version = -1;
  /// The solve (Solve() or Preview(), counted by DeformationSession::solves_) that made `state`:
  /// a coarse-grid correction needs the coarser level's state of that same solve.
  long long made_by_solve = -1;
  /// `state` is a preview's one global step: its positions come from its rotations, which are
  /// not fitted to them, so a global step from it would return the same positions and the
  /// displacement test would stop at once. A full solve starts from its positions instead.
  bool global_step_only = false;
};

DeformationSession::DeformationSession(const Mesh& mesh, const ComponentFactory& factory,
                                       const SessionOptions& options, const Context& context,
                                       const std::vector<double>& stiffness)
    : mesh_(mesh),
      factory_(factory),
      options_(options),
      context_(context),
      cascade_(mesh, context_) {
  ValidateStiffness(stiffness, mesh_, "the session's stiffness");
  Stopwatch clock;
  context_.Run([&] {
    diagonal_ = BoundingBoxDiagonal(mesh_);
    start_positions_ = cascade_.LevelMesh(0).vertices;
    Stopwatch phase;
    if (options_.hierarchical) {
      context_.ReportPhase("building the hierarchy");
      cascade_.SetHierarchy(factory_.MakeHierarchy()->Build(mesh_, context_),
                            factory_.MakeUpsampler());
    } else {
      cascade_.SetSingleLevel();
    }
    setup_timings_.hierarchy = phase.Seconds();
    const int levels = num_levels();
    solved_levels_ = options_.optimizer.SolvedLevels(levels);
    levels_.resize(levels);
    for (int l : solved_levels_) {
      levels_[l] = std::make_unique<Level>();
      cascade_.set_solver(l, options_.optimizer.level_solver->CreateAnother());
      // Coarse levels' energies are normalized like the input mesh's (Energy::SetInputMesh);
      // every level keeps one system for all handle sets (handle edits).
      const std::vector<double> level_stiffness = cascade_.LevelStiffness(l, stiffness);
      cascade_.solver(l).Precompute(LevelSetup{&cascade_.LevelMesh(l), l > 0 ? &mesh_ : nullptr, l,
                                               /*handle_edits=*/true, &level_stiffness},
                                    factory_, context_);
      setup_timings_.precompute += cascade_.solver(l).precompute_seconds();
    }
    cascade_.TakeRotationSite(solved_levels_.front());
  });
  setup_timings_.total = clock.Seconds();
}

DeformationSession::~DeformationSession() = default;

int DeformationSession::num_levels() const { return cascade_.num_levels(); }

const Positions& DeformationSession::level_positions() const {
  return levels_[0]->has_solution ? levels_[0]->state.positions : start_positions_;
}

const Positions& DeformationSession::positions() const {
  // Mapped out once per change of the finest state (a solve, SetPositions).
  if (output_stale_) {
    cascade_.ToInput(level_positions(), output_positions_, context_);
    output_stale_ = false;
  }
  return output_positions_;
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

void DeformationSession::ValidateWeights(const std::vector<double>& weights, size_t count,
                                         const char* what) const {
  if (weights.empty()) return;
  if (weights.size() != count) {
    throw InputError(
        fmt::format("{}: {} weights for {} handle vertices", what, weights.size(), count));
  }
  for (size_t k = 0; k < weights.size(); ++k) {
    const double w = weights[k];
    // +inf pins (Constraints::kHardWeight); a soft handle's weight is finite and > 0.
    if (!(w > 0.0)) {
      throw InputError(fmt::format(
          "{}: weight {} is {}; a handle's weight must be > 0 (+inf: hard, finite: soft)", what, k,
          w));
    }
  }
}

HandleEditResult DeformationSession::SetHandles(const std::vector<Index>& indices,
                                                const std::vector<double>& weights) {
  ValidateIndices(indices, "SetHandles");
  ValidateWeights(weights, indices.size(), "SetHandles");
  const Positions& current = level_positions();
  const std::vector<Index>& to_level = cascade_.finest_ordering().new_vertex;
  Positions targets(indices.size(), 3);
  for (size_t k = 0; k < indices.size(); ++k) targets.row(k) = current.row(to_level[indices[k]]);
  return ApplyHandles(indices, std::move(targets), weights);
}

HandleEditResult DeformationSession::SetHandles(const std::vector<Index>& indices,
                                                const Positions& targets) {
  return SetHandles(indices, targets, {});
}

HandleEditResult DeformationSession::SetHandles(const std::vector<Index>& indices,
                                                const Positions& targets,
                                                const std::vector<double>& weights) {
  ValidateIndices(indices, "SetHandles");
  ValidateTargets(targets, indices.size(), "SetHandles");
  ValidateWeights(weights, indices.size(), "SetHandles");
  return ApplyHandles(indices, targets, weights);
}

void DeformationSession::SetTargets(const Positions& targets) {
  if (handles_.empty()) throw InputError("SetTargets: the session has no handles yet (SetHandles)");
  ValidateTargets(targets, handles_.size(), "SetTargets");
  targets_ = targets;
  ++version_;
  UpdateTargets();
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
  std::vector<double> weights = weights_;
  if (!weights.empty()) weights.resize(handles.size(), Constraints::kHardWeight);
  return ApplyHandles(std::move(handles), std::move(all), std::move(weights));
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
  std::vector<double> weights;
  Positions targets(handles_.size() - removed.size(), 3);
  for (size_t k = 0; k < handles_.size(); ++k) {
    if (removed.count(handles_[k])) continue;
    targets.row(static_cast<Index>(handles.size())) = targets_.row(k);
    handles.push_back(handles_[k]);
    if (!weights_.empty()) weights.push_back(weights_[k]);
  }
  return ApplyHandles(std::move(handles), std::move(targets), std::move(weights));
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
  cascade_.ToLevel(positions, context_).swap(start_positions_);
  output_stale_ = true;
  ++version_;
  preview_rotations_pending_ = false;
  for (const auto& level : levels_) {
    if (level) {
      level->has_solution = false;
      level->state = LevelState();
    }
  }
}

HandleEditResult DeformationSession::ApplyHandles(std::vector<Index> indices, Positions targets,
                                                  std::vector<double> weights) {
  // Only a set with a soft handle keeps its weights: all hard is the empty list, as before.
  if (std::all_of(weights.begin(), weights.end(),
                  [](double w) { return w == Constraints::kHardWeight; })) {
    weights.clear();
  }
  std::vector<Index> old_handles = std::move(handles_);
  Positions old_targets = std::move(targets_);
  std::vector<double> old_weights = std::move(weights_);
  handles_ = std::move(indices);
  targets_ = std::move(targets);
  weights_ = std::move(weights);
  MapHandles();
  ++version_;
  try {
    return ConstrainLevels();
  } catch (...) {
    // A failed factorization (out of memory): go back to the previous handles, so the session
    // stays usable with them.
    handles_ = std::move(old_handles);
    targets_ = std::move(old_targets);
    weights_ = std::move(old_weights);
    MapHandles();
    if (!handles_.empty()) ConstrainLevels();
    throw;
  }
}

void DeformationSession::MapHandles() {
  const std::vector<Index>& to_level = cascade_.finest_ordering().new_vertex;
  level_handles_.resize(handles_.size());
  for (size_t k = 0; k < handles_.size(); ++k) level_handles_[k] = to_level[handles_[k]];
}

Constraints DeformationSession::LevelHandles() const {
  return Constraints{level_handles_, targets_, weights_};
}

HandleEditResult DeformationSession::ConstrainLevels() {
  Stopwatch clock;
  HandleEditResult result;
  const ComponentFactory& factory = factory_;  // thread-safe: levels are constrained in parallel
  std::vector<HandleEditResult::Level> done(levels_.size());
  const Constraints finest = LevelHandles();
  const auto constrain = [&](int l) {
    Level& level = *levels_[l];
    LevelSolver& solver = cascade_.solver(l);
    ConstrainSummary summary;
    Index constrained = static_cast<Index>(handles_.size());
    if (l == 0) {
      summary = solver.Constrain(LevelConstraints::Exact(finest, mesh_.planar), factory, context_);
    } else {
      // As the hierarchical optimizer's level setup: clusters holding a handle are constrained.
      const LevelConstraints mapped = cascade_.MapConstraints(l, finest);
      level.targets_stale = false;
      constrained = static_cast<Index>(mapped.vertices.size());
      summary = solver.Constrain(mapped, factory, context_);
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
  result.constraints = cascade_.solver(0).constraint_report();
  result.notes = DescribeConstraintHandling(result.constraints);
  result.seconds = clock.Seconds();
  return result;
}

void DeformationSession::UpdateTargets() {
  LevelSolver& finest = cascade_.solver(0);
  if (weights_.empty()) {
    finest.MoveTargets(targets_);
  } else {
    // The same split as LevelConstraints::Exact: hard targets pinned, soft ones in the data term.
    const Constraints all = constraints();
    finest.MoveTargets(all.HardPart().targets);
    finest.MoveSoftTargets(all.SoftPart().targets);
  }
  // The coarse levels' targets are mapped when a solve uses the level (a preview uses only the
  // coarsest one): UpdateCoarseTargets().
  for (int l : solved_levels_) {
    if (l != 0) levels_[l]->targets_stale = true;
  }
}

void DeformationSession::UpdateCoarseTargets(int l) {
  Level& level = *levels_[l];
  if (l == 0 || !level.targets_stale) return;
  // The constrained vertices are the same (same handles and weights): only the mean targets and
  // the soft clusters' weighted mean targets move.
  const LevelConstraints mapped = cascade_.MapConstraints(l, LevelHandles());
  cascade_.solver(l).MoveTargets(mapped.mean_target);
  if (!mapped.soft.empty()) cascade_.solver(l).MoveSoftTargets(mapped.soft.targets);
  level.targets_stale = false;
}

void DeformationSession::MaterializePreviewRotations() {
  if (!preview_rotations_pending_) return;
  GatherRotations(preview_map_, preview_coarse_rotations_, levels_[0]->state.rotations, context_);
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
  state.positions = level_positions();
  if (levels_[0]->has_solution) {
    state.rotations = levels_[0]->state.rotations;
  } else {
    state.rotations.clear();
  }
  return context_.Run([&] { return cascade_.solver(0).FitRotations(state, context_); });
}

bool DeformationSession::StraightPreview(bool preview, int top) {
  // A preview whose upsampler only copies each coarse vertex's rotation down: straight from the
  // coarsest level to the finest along the composed map (the paper's Fig. 15), one parallel
  // gather into the kept state instead of up-sampling positions and rotations through every
  // level (fresh arrays per level). The finest level's rotations are the same; its positions
  // are not up-sampled: the global step overwrites every free row and sets the handles' rows,
  // so with a direct solver the result is identical (an iterative one starts from the last
  // frame's positions instead of the up-sampled ones).
  const bool straight = preview && preview_straight_ && top > 0 &&
                        cascade_.upsampler().output() == UpsampleOutput::kRotations &&
                        cascade_.upsampler().RotationsFollowCoarseVertex(cascade_.rotation_site());
  if (straight && preview_map_.empty()) {
    // In the level numbering, like the finest level's rotation sites.
    preview_map_.resize(mesh_.num_vertices());
    for (Index v = 0; v < mesh_.num_vertices(); ++v) {
      preview_map_[v] = cascade_.hierarchy().MapFinestVertex(v, top);
    }
  }
  return straight;
}

LevelSolveRequest DeformationSession::LevelRequest(int l, const SessionSolveOptions& solve_options,
                                                   bool preview, bool out_of_time,
                                                   bool start_with_global_step) const {
  // The level solver places the handles (coarse levels: with the state's rotations, and again
  // before every global step with targets_follow_rotations).
  LevelSolveRequest request =
      options_.optimizer.Request(l, num_levels(), start_with_global_step, diagonal_);
  if (solve_options.tolerance >= 0.0 && request.tolerance < 0.0) {
    request.tolerance = solve_options.tolerance;
  }
  if (solve_options.max_iterations > 0 && request.max_iterations <= 0) {
    request.max_iterations = solve_options.max_iterations;
  }
  if (l == 0 && (preview || out_of_time)) request.max_iterations = 1;
  // The paper's approximation: one global solve from the up-sampled rotations, no local step
  // (the energy is left to CurrentEnergy()).
  request.global_step_only = l == 0 && preview && start_with_global_step;
  return request;
}

bool DeformationSession::StartLevel(int l, int top, bool preview, bool straight, bool gather,
                                    const LevelState* cur, bool coarser_previous_matches,
                                    const Context& context) {
  LevelState& work = work_[l];
  if (straight && l == 0 && gather) {
    // The finest level's global step gathers these (the coarsest level's solution) itself.
    if (work.positions.rows() != mesh_.num_vertices()) work.positions = start_positions_;
    preview_coarse_rotations_ = cur->rotations;
    return true;
  } else if (straight && l == 0) {
    if (work.positions.rows() != mesh_.num_vertices()) work.positions = start_positions_;
    GatherRotations(preview_map_, cur->rotations, work.rotations, context);
    return true;
  } else if (l == top) {
    Level* level = levels_[l].get();
    if (level->has_solution) {
      // Warm start: the previous solution's rotations drive the first global step, which
      // places the (moved) handles' influence smoothly over the mesh. After a preview's global
      // step a full solve fits the rotations to its positions first (a preview again takes one
      // more global step from the same rotations).
      work = level->state;
      return preview || !level->global_step_only;
    } else {
      work.positions = l == 0 ? start_positions_ : cascade_.hierarchy().levels[l].mesh.vertices;
      work.rotations.clear();
      return false;
    }
  } else if (levels_[l] && levels_[l]->has_solution && levels_[l]->version == version_ &&
             !preview) {
    // Nothing changed since this level's last solution: it is the best start there is (an
    // up-sampled one would start the level's iterations over).
    work = levels_[l]->state;
    return true;
  } else if (options_.frame_start == SessionOptions::FrameStart::kCorrected && !preview &&
             levels_[l] && levels_[l]->has_solution && coarser_previous_matches &&
             work_[l + 1].rotations.size() == cur->rotations.size()) {
    // Coarse-grid correction: the level's previous solution (its fine detail) moved by what
    // the coarser level's solution changed since then (the smooth motion), up-sampled. Only
    // when both previous solutions come from the same solve: a preview solves the coarsest
    // level but skips the levels between.
    LevelState& now = scratch_[l];
    cascade_.Upsample(l, *cur, now, context);
    cascade_.Upsample(l, work_[l + 1], work, context);
    work.positions = levels_[l]->state.positions + now.positions - work.positions;
    work.rotations = levels_[l]->state.rotations;
    return false;
  } else {
    return cascade_.Upsample(l, *cur, work, context);
  }
}

void DeformationSession::FinishResult(const LevelState& final_state, bool preview,
                                      double time_budget_seconds, int out_of_time_level,
                                      const std::vector<std::string>& level_notes,
                                      const Context& context, OptimizeResult& result) const {
  const LevelSolver& finest = cascade_.solver(0);
  // A preview's rotations are not fitted to its positions: no measures of that state.
  if (!preview) {
    result.measures = context.Run([&] { return finest.AuxiliaryMeasures(final_state, context); });
  }
  result.constraints = finest.constraint_report();
  std::vector<std::string> notes = DescribeConstraintHandling(result.constraints);
  result.notes.insert(result.notes.begin(), notes.begin(), notes.end());
  if (out_of_time_level >= 0) {
    result.notes.push_back(fmt::format(
        "the time budget of {} s ran out on level {}{}", time_budget_seconds, out_of_time_level,
        out_of_time_level > 0 ? "; the finest level did one iteration from the up-sampled state"
                              : ""));
  }
  result.notes.insert(result.notes.end(), level_notes.begin(), level_notes.end());
  cascade_.ToInput(final_state.positions, result.positions, context);
}

// One Solve() or Preview() down the cascade: where each level starts (StartLevel), its request
// (LevelRequest) and what a solved level keeps (its Level: the solution, its version).
class DeformationSession::Frame final : public LevelCascade::Pass {
 public:
  Frame(DeformationSession& session, const SessionSolveOptions& options, bool preview, int top,
        const Context& context)
      : s_(session), options_(options), preview_(preview), top_(top), context_(context) {
    straight_ = s_.StraightPreview(preview, top);
    // With per-vertex rotations the finest level's global step reads the coarse rotations
    // itself (no finest rotations written out at all).
    gathered_ = straight_ && s_.cascade_.solver(0).accepts_gathered_rotations();
  }

  /// A straight preview whose finest level cannot take the gathered rotations (soft targets: the
  /// gathered step does not assemble their data term): the rotations are written out first.
  bool gather_refused() const { return straight_ && !gathered_; }

  // Set by the session's iteration callback: which kind of stop ended a solve.
  bool user_stop = false;
  bool out_of_time = false;
  int out_of_time_level = -1;

  bool Visits(int l) const override {
    return !straight_ || l == top_ || l == 0;  // a straight preview skips the levels between
  }
  bool Solves(int l) const override {
    return s_.levels_[l] != nullptr && (!preview_ || l == top_ || l == 0);
  }
  LevelState& Start(int l, const LevelState* coarser, bool& from_rotations) override {
    // (A stop on a coarse level finishes from the up-sampled state: gathered into the finest
    // level's rotations.)
    gather_step_ = gathered_ && l == 0 && !user_stop;
    const bool coarser_previous_matches = coarse_before_level_ == l + 1 && s_.levels_[l] &&
                                          s_.levels_[l]->made_by_solve == coarse_before_solve_;
    from_rotations = s_.StartLevel(l, top_, preview_, straight_, gather_step_, coarser,
                                   coarser_previous_matches, context_);
    return s_.work_[l];
  }
  void Prepare(int l) override {
    s_.UpdateCoarseTargets(l);
    had_solution_ = s_.levels_[l]->has_solution;
    previous_made_by_ = s_.levels_[l]->made_by_solve;
  }
  LevelSolveRequest Request(int l, bool from_rotations, bool finishing) override {
    LevelSolveRequest request = s_.LevelRequest(l, options_, preview_, finishing, from_rotations);
    global_step_only_ = request.global_step_only;
    return request;
  }
  LevelSolveResult Solve(LevelSolver& solver, LevelState& state, const LevelSolveRequest& request,
                         const Context& context) override {
    // The coarsest rotations, gathered by the finest level's global step itself.
    if (gather_step_) {
      return solver.GlobalStepFromGathered(state, s_.preview_map_, s_.preview_coarse_rotations_,
                                           context);
    }
    return solver.Solve(state, request, context);
  }
  LevelState& Done(int l, LevelState& state, const LevelSolveResult* run) override {
    Level& level = *s_.levels_[l];
    if (l == 0) s_.output_stale_ = true;
    level.has_solution = true;
    level.made_by_solve = s_.solves_;
    level.global_step_only = run != nullptr && global_step_only_;
    if (run == nullptr) {
      // As a one-shot run stopped on a coarse level: the up-sampled state, rotations fitted.
      level.state = state;
      return level.state;
    }
    // The new solution into the Level; work_[l] keeps the previous one (the correction of the
    // next finer level needs it).
    std::swap(level.state, state);
    // After a gathered preview the finest rotations stay pending (MaterializePreviewRotations).
    if (l == 0) s_.preview_rotations_pending_ = gather_step_;
    coarse_before_level_ = had_solution_ ? l : -1;
    coarse_before_solve_ = previous_made_by_;
    // A stopped run or a preview is no finished solution: the next solve redoes the level.
    level.version = run->stopped_by_callback || preview_ ? s_.version_ - 1 : s_.version_;
    return level.state;
  }
  Finish OnStop(int /*l*/) override {
    return user_stop ? Finish::kFitRotations : Finish::kOneIteration;
  }

 private:
  DeformationSession& s_;
  const SessionSolveOptions& options_;
  const bool preview_;
  const int top_;
  const Context& context_;
  bool straight_ = false, gathered_ = false, gather_step_ = false, had_solution_ = false;
  bool global_step_only_ = false;
  // FrameStart::kCorrected: the level whose previous solution (before this solve) is in work_,
  // and the solve that made it.
  int coarse_before_level_ = -1;
  long long coarse_before_solve_ = -1, previous_made_by_ = -1;
};

OptimizeResult DeformationSession::Run(const SessionSolveOptions& solve_options, bool preview) {
  if (handles_.empty()) {
    throw InputError(fmt::format("{}: the session has no handles yet (SetHandles)",
                                 preview ? "Preview" : "Solve"));
  }
  Stopwatch total;
  OptimizeResult result;
  // The cascade from the coarsest level, or the finest level alone from its previous solution.
  const bool from_coarsest = preview ||
                             options_.frame_start != SessionOptions::FrameStart::kPrevious ||
                             !levels_[0]->has_solution;
  const int top = from_coarsest ? num_levels() - 1 : 0;
  // The states are kept between solves (work_[l], scratch_[l]: no allocation per frame on the
  // big levels). A solved level's result is swapped into its Level, so work_[l] then holds the
  // level's previous solution.
  if (work_.size() != static_cast<size_t>(num_levels())) {
    work_.assign(num_levels(), LevelState());
    scratch_.assign(num_levels(), LevelState());
  }
  ++solves_;
  Context context = context_;
  context.run_clock.Restart();
  Frame frame(*this, solve_options, preview, top, context);
  context.iteration_callback = [&](const IterationSummary& summary) {
    if (callback_ && callback_(summary) == CallbackAction::kStop) {
      frame.user_stop = true;
      return CallbackAction::kStop;
    }
    if (solve_options.time_budget_seconds > 0.0 &&
        context.run_clock.Seconds() > solve_options.time_budget_seconds) {
      if (!frame.out_of_time) frame.out_of_time_level = summary.level;
      frame.out_of_time = true;
      return CallbackAction::kStop;
    }
    return CallbackAction::kContinue;
  };
  // Whatever this solve reads of the finest level's last rotations must be there.
  if (!preview) MaterializePreviewRotations();
  std::vector<std::string> level_notes;
  const LevelState* final_state = nullptr;
  context.Run([&] { final_state = &cascade_.Run(top, frame, context, result, level_notes); });
  result.stopped_by_callback = frame.user_stop;
  if (frame.gather_refused() && !weights_.empty()) {
    level_notes.push_back(
        "preview with soft handles: the coarsest rotations were written out to the finest level "
        "before its global step (the gathered step has no soft targets)");
  }
  FinishResult(*final_state, preview, solve_options.time_budget_seconds,
               frame.out_of_time ? frame.out_of_time_level : -1, level_notes, context, result);
  result.timings.solve = total.Seconds();
  result.timings.total = result.timings.solve;
  return result;
}

}  // namespace harap
