// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <vector>

#include "framework/context.h"
#include "framework/hierarchy.h"
#include "framework/level_solver.h"
#include "framework/mesh.h"
#include "framework/optimizer.h"
#include "framework/upsampler.h"
#include "solvers/optimizers/vertex_ordering.h"

namespace harap {

/// The levels of one deformation and the paper's coarse-to-fine loop over them (Algorithm 2,
/// second loop): a mesh hierarchy (Section 4; none for a one-level run on the input mesh), the
/// upsampler between its levels (Section 5.1) and one level solver per solved level, solved from
/// the coarsest level down, each finer level starting from the up-sampled solution of the
/// coarser one.
///
/// The loop is the one of every optimizer and of the interactive session; what differs between
/// them (where a level's state comes from, the request, what a solved level keeps) is a Pass.
/// Stops (Context::iteration_callback returning kStop) are handled here: the coarser levels
/// still to come are not solved, the state is carried down to the finest level, and there the
/// pass chooses between fitting the rotations (the result as it stands) and one iteration.
///
/// Numbering: the cascade renumbers once, where its levels are made. Level 0 is the input mesh
/// renumbered for memory locality (LocalityOrdering, made at construction, so level 0's solver
/// can be set up before the hierarchy is built); SetHierarchy() renumbers every coarse level
/// and the vertex maps between the levels likewise (RenumberForLocality). Every level mesh,
/// the hierarchy, the upsampler's states, the level solvers' states and constraints are in that
/// level numbering; the caller maps the problem in (ToLevel()) and the finest positions out
/// (ToInput()) once, at its boundary.
/// Not thread-safe; set_solver() of different levels from different threads is.
class LevelCascade {
 public:
  /// `mesh` (the input mesh, in the caller's numbering) must outlive the cascade; level 0's
  /// renumbering runs in `context`.
  LevelCascade(const Mesh& mesh, const Context& context);

  /// A hierarchy built on the input mesh (Hierarchy::Build, the input's numbering) and its
  /// upsampler; without one the cascade is the input mesh alone. Renumbers the hierarchy's
  /// levels into the level numbering and sizes the per-level slots (solvers, setup times); call
  /// before set_solver() of a coarse level.
  void SetHierarchy(MeshHierarchy hierarchy, std::unique_ptr<Upsampler> upsampler);
  /// One level: the input mesh (a one-level run).
  void SetSingleLevel();
  /// The level solver of level l and what its setup (P and C) took, in seconds: `setup_seconds`
  /// is reported with the level's solve time (LevelResult::seconds).
  void set_solver(int l, std::unique_ptr<LevelSolver> solver, double setup_seconds = 0.0);
  /// Frees level l's solver (a one-shot run no longer needs a coarse level's factor).
  void release_solver(int l) { solvers_[l].reset(); }
  /// Takes the rotation site (the upsampler's input) from the coarsest solved level's solver.
  void TakeRotationSite(int coarsest_solved);

  int num_levels() const { return static_cast<int>(solvers_.size()); }
  bool hierarchical() const { return upsampler_ != nullptr; }
  /// The input mesh, in the caller's numbering.
  const Mesh& input_mesh() const { return input_mesh_; }
  /// Level l's mesh, in the level numbering (level 0: the input mesh renumbered).
  const Mesh& LevelMesh(int l) const { return l > 0 ? hierarchy_.levels[l].mesh : finest_.mesh; }
  /// The hierarchy in the level numbering (levels[0].mesh is LevelMesh(0)).
  const MeshHierarchy& hierarchy() const { return hierarchy_; }
  /// Level 0's numbering: new_vertex maps an input vertex to level 0, old_vertex back.
  const MeshOrdering& finest_ordering() const { return finest_; }

  /// The problem's constraints with their vertices in level 0's numbering (same order).
  Constraints ToLevel(const Constraints& input) const;
  /// Per-vertex rows of the input mesh in level 0's order.
  Positions ToLevel(const Positions& input, const Context& context) const {
    return context.Run([&] { return finest_.ToNew(input); });
  }
  /// The problem's constraints (`level0`: in level 0's numbering) on coarse level l > 0
  /// (MapConstraints, coarse_constraints.h), listed in the order of the level's vertices as the
  /// hierarchy built them: a level's system sums its constrained columns in list order, so the
  /// arithmetic does not depend on the renumbering.
  LevelConstraints MapConstraints(int l, const Constraints& level0) const;
  /// Level l's per-element stiffness (framework/stiffness.h) from the input mesh's (its
  /// numbering): level 0's renumbered, a coarse level's by LevelStiffness (coarse_constraints.h).
  std::vector<double> LevelStiffness(int l, const std::vector<double>& input_stiffness) const;
  /// Level 0's positions in the input's numbering (into `out`: no allocation when it has the
  /// size already).
  void ToInput(const Positions& level_positions, Positions& out, const Context& context) const {
    context.Run([&] { finest_.ToOld(level_positions, out); });
  }
  const Upsampler& upsampler() const { return *upsampler_; }
  RotationSite rotation_site() const { return site_; }
  bool has_solver(int l) const { return solvers_[l] != nullptr; }
  LevelSolver& solver(int l) const { return *solvers_[l]; }

  /// Level l's state from level l + 1's (Section 5.1); returns whether it starts with a global
  /// step (the upsampler hands down rotations).
  bool Upsample(int l, const LevelState& coarse, LevelState& fine, const Context& context) const;

  /// What a pass down the levels does at each of them, beyond the loop itself.
  class Pass {
   public:
    virtual ~Pass() = default;
    /// Whether level l gets a state at all (false: skipped, the next level starts from the last
    /// one that got a state).
    virtual bool Visits(int /*l*/) const { return true; }
    /// Whether a visited level is solved (false: its state is only handed down).
    virtual bool Solves(int l) const = 0;
    /// The state level l starts from, made from `coarser` (the last visited coarser level's
    /// state; null on the first level of the pass); `from_rotations` says whether the level
    /// starts with a global step from the state's rotations.
    virtual LevelState& Start(int l, const LevelState* coarser, bool& from_rotations) = 0;
    /// Called before level l is solved or, after a stop, its rotations fitted (e.g. to wait for
    /// its setup).
    virtual void Prepare(int /*l*/) {}
    /// The request for level l; `finishing`: after a stop on a coarser level.
    virtual LevelSolveRequest Request(int l, bool from_rotations, bool finishing) = 0;
    /// Solves level l (a pass may run it isolated from background work).
    virtual LevelSolveResult Solve(LevelSolver& solver, LevelState& state,
                                   const LevelSolveRequest& request, const Context& context) {
      return solver.Solve(state, request, context);
    }
    /// After level l is solved (or, finishing, its rotations fitted): where its state is now,
    /// the input of the next finer level. `run` is null after a fit.
    virtual LevelState& Done(int /*l*/, LevelState& state, const LevelSolveResult* /*run*/) {
      return state;
    }
    /// How a pass stopped on level l finishes: fit the finest level's rotations to the state
    /// handed down (the result as it stands) or iterate once there (a time budget).
    enum class Finish { kFitRotations, kOneIteration };
    virtual Finish OnStop(int /*l*/) { return Finish::kFitRotations; }
  };

  /// The loop from level `top` down to the finest: per level the pass's start, then, if solved,
  /// the solve and its LevelResult (finest first in `result.levels`), iterations and notes; on
  /// the finest level energy, iterations and convergence. Returns the finest level's state (the
  /// pass's, to take).
  LevelState& Run(int top, Pass& pass, const Context& context, OptimizeResult& result,
                  std::vector<std::string>& notes);

 private:
  const Mesh& input_mesh_;
  MeshOrdering finest_;  ///< level 0's numbering and mesh
  MeshHierarchy hierarchy_;
  std::vector<std::vector<Index>> as_built_;  ///< per level: vertex as built → level numbering
  std::unique_ptr<Upsampler> upsampler_;
  RotationSite site_ = RotationSite::kVertex;
  std::vector<std::unique_ptr<LevelSolver>> solvers_;
  std::vector<double> setup_seconds_;
};

}  // namespace harap
