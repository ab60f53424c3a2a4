// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "framework/config.h"
#include "framework/level_solver.h"
#include "framework/optimizer.h"
#include "framework/registry.h"
#include "solvers/optimizers/coarse_constraints.h"
#include "solvers/optimizers/hierarchical_optimizer.h"
#include "solvers/optimizers/level_cascade.h"

namespace harap {

/// How a session is solved: the optimizer (classic = one level, or hierarchical with its
/// hierarchy levels) and its options, read from the same `[optimizer]` table as `harap deform`.
struct SessionOptions {
  bool hierarchical = false;
  /// The optimizer's options and its level solver (classic: a one-level run of local_global).
  /// `overlap_setup` (a session sets up once) does not apply; the level solver must support
  /// handle edits (local_global with `newton` 0: Newton steps need the eliminated system;
  /// Anderson acceleration works).
  HierarchicalOptimizer::Options optimizer;

  /// Where the finer levels of a hierarchical session start a frame (the coarsest level always
  /// starts from its own previous solution, and a level whose last solution is for the current
  /// handles and targets starts from it). Measured on 30-frame drags (docs/session.md):
  /// kCorrected gave the lowest energies (no frame above the one-shot run's) at about the
  /// kUpsampled time; kPrevious the fewest iterations but energies up to 60% above.
  enum class FrameStart {
    /// Every level solved from the coarsest down, each finer one from the up-sampled solution of
    /// the coarser one, as in a one-shot run (the paper's cascade).
    kUpsampled,
    /// Only the finest level is solved, from its own previous solution (the first frame runs
    /// the cascade). The convergence test stops while the slow, smooth modes still lag behind
    /// the handles, and the lag accumulates over frames.
    kPrevious,
    /// The cascade, but a finer level with a previous solution starts from it moved by the
    /// up-sampled change of the coarser level's solution since then (a coarse-grid correction:
    /// the old fine detail plus the new smooth motion), with a local step.
    kCorrected,
  };
  FrameStart frame_start = FrameStart::kCorrected;
  /// "corrected", "upsampled", "previous" (ConfigError listing them for anything else).
  static FrameStart ParseFrameStart(std::string_view name);
  static std::string_view FrameStartName(FrameStart start);

  /// Reads `type` (classic or hierarchical) and that optimizer's options from an `[optimizer]`
  /// table, `inner` from `level_solvers`; other optimizers are rejected (ConfigError), and level
  /// solver options a session cannot run when the session is built.
  static SessionOptions FromConfig(OptionReader optimizer_node,
                                   const Registry<LevelSolver>& level_solvers);
};

/// Per-solve limits; negative values take the optimizer's configured ones.
struct SessionSolveOptions {
  /// Convergence tolerance of every level (the coarse levels' `coarse_tolerance`, if configured,
  /// still applies to them; else `coarse_tolerance_factor` times this one).
  double tolerance = -1.0;
  int max_iterations = -1;  ///< Per level.
  /// Wall-time budget of the whole solve in seconds (0: none). When it runs out on a coarse level
  /// the solution is up-sampled to the finest level, the handles placed, and one local/global
  /// iteration done there; on the finest level the iteration stops.
  double time_budget_seconds = 0.0;
};

/// What a handle edit did, per solved level.
struct HandleEditResult {
  struct Level {
    int level = 0;
    Index constrained_vertices = 0;  ///< constrained vertices of the level (coarse: clusters)
    Index changed_rows = 0;          ///< rows of the level's masked matrix that changed
    bool factored = false;           ///< false: nothing changed on the level
    LinearSolver::RefactorRoute route = LinearSolver::RefactorRoute::kFull;
    double seconds = 0.0;
  };
  std::vector<Level> levels;       ///< finest first
  double seconds = 0.0;            ///< the whole edit
  ConstraintReport constraints;    ///< on the finest level
  std::vector<std::string> notes;  ///< pinned components, isolated vertices
};

/// An interactive deformation session: the paper's phases split by what an interaction repeats.
/// Built once from a mesh (hierarchy H and per-level precomputation P); SetHandles() chooses the
/// constrained vertices (C: every level's masked system factored); SetTargets() moves them (no
/// refactoring); AddHandles()/RemoveHandles() edit the handle set by updating every level's
/// factorization on the rows that changed (LinearSolver::Refactor); Solve() runs the S phase,
/// warm-started from the previous solution; Preview() is the paper's coarse approximation.
///
/// A session is level solvers (framework/level_solver.h) that keep their state between solves:
/// set up with LevelSetup::handle_edits (local_global: MaskedSystem), so their matrices keep one
/// size and pattern whatever the handles. Coarse levels are constrained as in the hierarchical
/// optimizer (coarse_constraints.h): a coarse vertex is constrained when a handle maps to it, its
/// target follows its rotation (`targets_follow_rotations`).
///
/// Every public method validates its input first and throws InputError (naming the problem)
/// without changing anything, so the session stays usable after a bad call. `mesh` and `factory`
/// must outlive the session (api/session.h bundles them). Not thread-safe.
class DeformationSession {
 public:
  /// `stiffness`: per-element factors (framework/stiffness.h; empty: 1 everywhere), used while
  /// the levels are set up here.
  DeformationSession(const Mesh& mesh, const ComponentFactory& factory,
                     const SessionOptions& options, const Context& context,
                     const std::vector<double>& stiffness = {});
  ~DeformationSession();
  DeformationSession(const DeformationSession&) = delete;
  DeformationSession& operator=(const DeformationSession&) = delete;

  /// Makes `indices` the handles (unique, in range, not empty), their targets their current
  /// positions (the last solution, or the start positions), or `targets` (#indices×3, finite).
  HandleEditResult SetHandles(const std::vector<Index>& indices,
                              const std::vector<double>& weights = {});
  HandleEditResult SetHandles(const std::vector<Index>& indices, const Positions& targets);
  /// With a weight per handle vertex (Constraints::weights): +inf (kHardWeight) pins the
  /// vertex, a finite w > 0 makes it a soft handle adding w ‖u − t‖² to the energy (every level:
  /// MapConstraints). Empty: all hard. Other soft vertices or weights change the diagonal of a
  /// level's matrix A + W: those rows are refactored with the ones whose handles changed
  /// (LinearSolver::Refactor), as for AddHandles().
  HandleEditResult SetHandles(const std::vector<Index>& indices, const Positions& targets,
                              const std::vector<double>& weights);
  /// Moves the handles, hard and soft: `targets` has one row per handle, in the order of
  /// handles(). Nothing is refactored (soft targets change only the right-hand side).
  void SetTargets(const Positions& targets);
  /// Adds handles (not handles yet) with their targets; refactors the changed rows of each level.
  /// The added handles are hard.
  HandleEditResult AddHandles(const std::vector<Index>& indices, const Positions& targets);
  /// Removes handles (each must be one; at least one must stay).
  HandleEditResult RemoveHandles(const std::vector<Index>& indices);
  /// Sets the positions the next solve starts from (#V×3, finite) and forgets the previous
  /// solutions: the next Solve() starts like a one-shot run from `positions`.
  void SetPositions(const Positions& positions);

  /// Minimizes the energy for the current handles and targets, warm-started from the previous
  /// solution. The result is as detailed as a one-shot run's (per level iterations, energy,
  /// seconds; timings.solve and .total; the constraint report and notes).
  OptimizeResult Solve(const SessionSolveOptions& options = {});
  /// The paper's coarse approximation (Figs. 15–16): the coarsest level solved (warm-started),
  /// its solution up-sampled level by level to the finest, and one global solve there from the
  /// up-sampled rotations (with an upsampler that hands down positions: one local/global
  /// iteration). The finest level's energy is not evaluated (NaN; it would cost a local step:
  /// CurrentEnergy() gives it).
  OptimizeResult Preview();
  /// E(U, R) of the current finest positions (positions()), rotations fitted to them.
  double CurrentEnergy();

  /// Called after every iteration; returning kStop ends the solve (the result says so) as in a
  /// one-shot run. Empty: none.
  void set_iteration_callback(IterationCallback callback) { callback_ = std::move(callback); }

  const Mesh& mesh() const { return mesh_; }
  int num_levels() const;
  /// The hierarchy the session solves on (classic: no levels); level l < num_levels(). In the
  /// level numbering (level_cascade.h): its level 0 is the mesh renumbered; CoarseVertex() maps
  /// a vertex of the mesh.
  const MeshHierarchy& hierarchy() const { return cascade_.hierarchy(); }
  /// The vertex of level `level` that mesh vertex `vertex` (the mesh's numbering) maps to, or
  /// kNoVertex (MeshHierarchy::MapFinestVertex).
  Index CoarseVertex(Index vertex, int level) const {
    return cascade_.hierarchy().MapFinestVertex(cascade_.finest_ordering().new_vertex[vertex],
                                                level);
  }
  /// Levels that are solved (coarsest first); classic: {0}.
  const std::vector<int>& solved_levels() const { return solved_levels_; }
  const std::vector<Index>& handles() const { return handles_; }
  const Positions& targets() const { return targets_; }
  /// One weight per handle (kHardWeight: hard), or empty: every handle is hard.
  const std::vector<double>& weights() const { return weights_; }
  /// The current handles as constraints (indices, targets, weights).
  Constraints constraints() const { return Constraints{handles_, targets_, weights_}; }
  /// The current finest-level positions (the last solution, or the start), in the mesh's
  /// numbering.
  const Positions& positions() const;
  /// Timings of the construction: hierarchy and precompute (constrain and solve are 0).
  const PhaseTimings& setup_timings() const { return setup_timings_; }
  /// Whether Preview() gathers the coarsest level's rotations straight into the finest level
  /// when the upsampler allows it (Upsampler::RotationsFollowCoarseVertex; the default, the same
  /// result with a direct solver) or up-samples through every level (experiments, tests).
  void set_preview_straight(bool straight) { preview_straight_ = straight; }

 private:
  struct Level;
  class Frame;
  void ValidateIndices(const std::vector<Index>& indices, const char* what) const;
  void ValidateTargets(const Positions& targets, size_t count, const char* what) const;
  void ValidateWeights(const std::vector<double>& weights, size_t count, const char* what) const;
  /// Applies a new handle set on every level (refactoring); restores the old one on a throw.
  /// `weights`: empty (all hard) or one per index.
  HandleEditResult ApplyHandles(std::vector<Index> indices, Positions targets,
                                std::vector<double> weights);
  HandleEditResult ConstrainLevels();
  // level_handles_ from handles_.
  void MapHandles();
  // The handles as constraints in the level numbering.
  Constraints LevelHandles() const;
  // The finest positions in the level numbering (positions() maps them out).
  const Positions& level_positions() const;
  /// Moves the finest level's targets after SetTargets() (same handles); the coarse levels'
  /// follow when a solve uses them (UpdateCoarseTargets).
  void UpdateTargets();
  /// Level `l`'s coarse constraint targets for the current finest targets, if SetTargets()
  /// changed them since (they are mapped only for the levels a solve uses).
  void UpdateCoarseTargets(int l);
  /// The finest rotations a preview left pending (see preview_coarse_rotations_) into
  /// levels_[0]->state.
  void MaterializePreviewRotations();
  /// The S phase of Solve() and Preview(): the cascade from the coarsest level down (or, with
  /// FrameStart::kPrevious, the finest level alone).
  OptimizeResult Run(const SessionSolveOptions& options, bool preview);
  /// Where level `l` starts this solve, into work_[l] (`cur`: the state of the level above, the
  /// cascade's `top` level has none); returns whether it starts with a global step. `gather`:
  /// a straight preview's finest level that takes the coarse rotations gathered (kept in
  /// preview_coarse_rotations_, not written out). `coarser_previous_matches`: work_[l + 1]
  /// holds level l + 1's previous solution, made by the solve that made level l's.
  bool StartLevel(int l, int top, bool preview, bool straight, bool gather, const LevelState* cur,
                  bool coarser_previous_matches, const Context& context);
  /// Whether a preview goes straight from level `top` to the finest (see Run()); builds the
  /// composed vertex map on first use.
  bool StraightPreview(bool preview, int top);
  /// The request for level `l`: the optimizer's, with the solve's limits.
  LevelSolveRequest LevelRequest(int l, const SessionSolveOptions& solve_options, bool preview,
                                 bool out_of_time, bool start_with_global_step) const;
  /// Run()'s result from the final state: measures, constraint report, notes, positions
  /// (`out_of_time_level`: -1 when the time budget did not run out).
  void FinishResult(const LevelState& final_state, bool preview, double time_budget_seconds,
                    int out_of_time_level, const std::vector<std::string>& level_notes,
                    const Context& context, OptimizeResult& result) const;

  const Mesh& mesh_;
  const ComponentFactory& factory_;
  SessionOptions options_;
  Context context_;
  IterationCallback callback_;
  LevelCascade cascade_;  ///< the hierarchy (classic: the mesh alone), level solvers, the loop
  std::vector<std::unique_ptr<Level>> levels_;  ///< per hierarchy level; null if not solved
  std::vector<int> solved_levels_;              ///< coarsest first
  double diagonal_ = 0.0;
  std::vector<Index> handles_;        ///< the input's numbering
  std::vector<Index> level_handles_;  ///< the same vertices in the level numbering
  Positions targets_;
  std::vector<double> weights_;  ///< empty (all hard) or one per handle, with a soft one
  Positions start_positions_;    ///< finest positions without a solution (SetPositions; level
                                 ///< numbering)
  // positions()' copy in the input's numbering; stale once the finest state changed.
  mutable Positions output_positions_;
  mutable bool output_stale_ = true;
  long long version_ = 0;  ///< bumped by every change of handles, targets or positions
  long long solves_ = 0;   ///< Solve() and Preview() calls so far
  /// Solve()'s per-level states, kept between solves (see Run()).
  std::vector<LevelState> work_, scratch_;
  /// Preview() with an upsampler whose rotations follow the coarse vertex: each finest vertex's
  /// coarsest-level vertex (the composed maps; kNoVertex: identity), built on first use.
  std::vector<Index> preview_map_;
  /// After a gathered preview (LevelSolver::GlobalStepFromGathered) the finest level's rotations
  /// are these coarse ones gathered along preview_map_; they are written into levels_[0]->state
  /// only when something reads them (MaterializePreviewRotations): a preview frame never does.
  Rotations preview_coarse_rotations_;
  bool preview_rotations_pending_ = false;
  LevelState energy_state_;  ///< CurrentEnergy()'s buffers
  bool preview_straight_ = true;
  PhaseTimings setup_timings_;
};

}  // namespace harap
