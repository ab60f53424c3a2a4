// SPDX-License-Identifier: MIT
#pragma once

#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "framework/context.h"
#include "framework/data_term.h"
#include "framework/linear_solver.h"
#include "framework/mesh.h"
#include "framework/optimizer.h"
#include "framework/upsampler.h"

namespace harap {

/// The constraints of one level, in the level mesh's numbering. On the input level they are the
/// problem's: `mean_target` holds the targets and `mean_offset` is empty. On a coarse level (the
/// paper's Section 4, "Constraints") a vertex is constrained when a constrained input vertex maps
/// to it, and its target follows its rotation R: target(R) = mean_target − R · mean_offset, the
/// mean over its input members m of (target_m − R (v̄_m − v̄_c)).
struct LevelConstraints {
  std::vector<Index> vertices;
  Positions mean_target;  ///< #vertices×3
  Positions mean_offset;  ///< #vertices×3, or empty: the targets are exact (input level)
  /// Per-element rotation sites: the elements around each constrained vertex, whose rotations
  /// average to the vertex's (Eq. 11). Filled by the level solver that needs them.
  std::vector<std::vector<Index>> incident_elements;
  /// The level is planar: per-element rotations average to a rotation of the plane.
  bool planar = false;
  /// Soft constraints (a pull with a weight, not a pin). On a coarse level each coarse vertex
  /// takes the summed weight of its soft input members and their weighted mean target
  /// (MapConstraints; docs/solvers.md, "Soft targets"); they do not follow rotations.
  SoftTargets soft;

  /// The input level's constraints: exact targets, soft ones as they are.
  static LevelConstraints Exact(const Constraints& constraints, bool planar) {
    LevelConstraints exact;
    const Constraints hard = constraints.HardPart();
    exact.vertices = hard.indices;
    exact.mean_target = hard.targets;
    exact.planar = planar;
    if (constraints.has_soft()) {
      Constraints soft = constraints.SoftPart();
      exact.soft.vertices = std::move(soft.indices);
      exact.soft.targets = std::move(soft.targets);
      exact.soft.weights = std::move(soft.weights);
    }
    return exact;
  }
  /// Whether the targets depend on the rotations (a coarse level's).
  bool targets_follow_rotations() const { return mean_offset.rows() > 0; }
};

/// Where a level solver works.
struct LevelSetup {
  const Mesh* mesh = nullptr;  ///< the level's mesh
  /// The problem's mesh when `mesh` is a coarse level of a hierarchy (energies are normalized
  /// like it: Energy::SetInputMesh), nullptr on the input level.
  const Mesh* input_mesh = nullptr;
  int level = 0;  ///< 0 = input mesh
  /// The constrained vertices will change between solves (an interactive session's handle
  /// edits): keep one system size and pattern and refactor only the rows that change, instead
  /// of eliminating the constrained vertices (the smallest system, for one constraint set).
  bool handle_edits = false;
  /// Per-element stiffness factors of `mesh` (framework/stiffness.h), or nullptr / empty: 1
  /// everywhere. Only read during Precompute().
  const std::vector<double>* stiffness = nullptr;
};

/// What a driver asks of one level solve. Negative limits take the solver's configured ones.
struct LevelSolveRequest {
  double tolerance = -1.0;
  /// Multiplies the tolerance in effect (`tolerance`, or the solver's own if that is negative):
  /// the coarse levels' `coarse_tolerance_factor`. Solvers read both through Tolerance().
  double tolerance_factor = 1.0;
  /// The level's second stopping test (LocalGlobalOptions::energy_tolerance); negative: the
  /// solver's own. Solvers without it ignore it.
  double energy_tolerance = -1.0;
  int max_iterations = -1;
  /// state.rotations were handed down by the coarser level (an upsampler with
  /// UpsampleOutput::kRotations): start with a global step from them (Eq. 7). Otherwise the
  /// state's positions are the start; rotations there, if any, are only a warm start.
  bool start_from_rotations = false;
  /// Coarse levels: the constrained vertices' targets follow their current rotations during
  /// the iterations, not only at the start (`targets_follow_rotations`, Fig. 16). Solvers that
  /// place the targets once ignore it.
  bool targets_follow_rotations = false;
  /// With moving targets: after this many iterations that raised the energy, the targets stay
  /// where they are (0: never; see LocalGlobalOptions::freeze_targets_after).
  int freeze_targets_after = 3;
  /// One global step from the given rotations and nothing else (the paper's coarse
  /// approximation of the finest level, Fig. 15); the result's energy is NaN. Solvers without a
  /// rotation-driven global step throw InputError.
  bool global_step_only = false;
  double diagonal = 1.0;  ///< bounding-box diagonal of the input mesh: scales convergence tests

  /// The tolerance this solve stops at, given the solver's own: `tolerance` if set, else `own`,
  /// times tolerance_factor.
  double Tolerance(double own) const {
    return (tolerance >= 0.0 ? tolerance : own) * tolerance_factor;
  }
};

/// Writes out gathered rotations (LevelSolver::GlobalStepFromGathered): out[v] =
/// gathered[source[v]], the identity where source[v] is kNoVertex; in parallel.
void GatherRotations(const std::vector<Index>& source, const Rotations& gathered, Rotations& out,
                     const Context& context);

/// What one level solve did: the measures every solver has, plus named solver-specific ones.
struct LevelSolveResult {
  int iterations = 0;
  double energy = 0.0;  ///< E of the final state (rotations fitted; the input level: the report's)
  bool converged = false;
  bool stopped_by_callback = false;
  SolveStatistics linear_solves;
  /// Solver-specific counts, by name (e.g. "inverted_elements", "accelerated_iterations",
  /// "newton_steps", "hessian_products"); copied into LevelResult::measures and the report.
  std::map<std::string, double> measures;
  std::vector<std::string> notes;  ///< remarks for the report ("level 2: ...")
  EnergyWeights weights;           ///< the level energy's weights (Energy::weights())
};

/// What Constrain() did to the level's factorization.
struct ConstrainSummary {
  bool factored = false;  ///< false: the constrained set did not change, nothing was refactored
  LinearSolver::RefactorRoute route = LinearSolver::RefactorRoute::kFull;
  Index changed_rows = 0;  ///< rows that changed (all on the first call)
  double seconds = 0.0;
};

/// The solver of one mesh level: local/global ARAP, ADMM-PD, WRAPD, ... The optimizers drive one
/// level solver per hierarchy level (classic and the flat ADMM optimizers: one level); an
/// interactive session keeps them between solves. A level solver owns everything of its level:
/// its energy, constrained system and factorization, and where its constrained vertices go (it
/// places them itself, as often as it needs). Meshes, constraints and states are in the level
/// mesh's numbering, which the level cascade has already made local (HierarchyLevel): a level
/// solver works in it directly, with no renumbering of its own.
///
/// Phases (the paper's Table 1): Precompute() is P, Constrain() is C (again for another
/// constraint set), Solve() is S. MoveTargets() moves the constrained vertices' targets without
/// refactoring. Implementations read their options at creation (from the optimizer's table) and
/// never print; every iteration goes to Context::iteration_callback.
class LevelSolver {
 public:
  virtual ~LevelSolver() = default;

  /// A solver of the same kind with the same options and no state (one per level).
  virtual std::unique_ptr<LevelSolver> CreateAnother() const = 0;

  /// Throws ConfigError naming the option when this solver, with its options, cannot work with
  /// `energy` (the run's, made by its factory and not yet precomputed) or, with `handle_edits`,
  /// in an interactive session. A run calls it once, when its configuration is resolved, so such
  /// combinations fail before any work. Default: every energy, sessions included.
  virtual void CheckCompatible(const Energy& /*energy*/, bool /*handle_edits*/) const {}

  virtual void Precompute(const LevelSetup& setup, const ComponentFactory& factory,
                          const Context& context) = 0;
  /// Constrains `constraints.vertices` and factors the level's system (a new linear solver from
  /// `factory` the first time).
  virtual ConstrainSummary Constrain(const LevelConstraints& constraints,
                                     const ComponentFactory& factory, const Context& context) = 0;
  /// New `mean_target` rows for the same constrained vertices (no refactoring).
  virtual void MoveTargets(const Positions& mean_target) = 0;
  /// New targets for the same soft constraints (LevelConstraints::soft; no refactoring). Level
  /// solvers without soft constraints refuse them in Constrain() (accepts_soft_targets()), so
  /// the default is never reached by a correct caller.
  virtual void MoveSoftTargets(const Positions& /*targets*/) {
    throw InternalError("soft targets moved on a level solver without soft targets");
  }
  /// Whether Constrain() takes LevelConstraints::soft (others throw InputError for them).
  virtual bool accepts_soft_targets() const { return false; }

  /// Places the constrained vertices (with the state's rotations where it has them for the
  /// level's sites) and iterates from `state`; on return `state` holds the final positions and
  /// rotations fitted to them, the input of an upsampler.
  virtual LevelSolveResult Solve(LevelState& state, const LevelSolveRequest& request,
                                 const Context& context) = 0;
  /// Fits the state's rotations to its positions and returns the energy (the report's energy on
  /// the input level).
  virtual double FitRotations(LevelState& state, const Context& context) = 0;
  /// Energy::AuxiliaryMeasures of a state whose rotations are fitted (e.g. "energy_wrapd").
  virtual std::map<std::string, double> AuxiliaryMeasures(const LevelState& state,
                                                          const Context& context) const = 0;

  /// Where the level's rotations live (the upsampler's input); valid after Precompute().
  virtual RotationSite rotation_site() const = 0;
  /// Whether GlobalStepFromGathered() works here; valid after Constrain().
  virtual bool accepts_gathered_rotations() const { return false; }
  /// Solve() with global_step_only, the rotations gathered instead of in state.rotations: site
  /// (vertex) v of the level mesh takes coarse[source[v]] (kNoVertex: the identity), a preview
  /// straight from the coarsest level whose finest rotations need never be written out.
  /// state.rotations is left as it is; the energy is NaN. Only where
  /// accepts_gathered_rotations(); otherwise throws InputError.
  virtual LevelSolveResult GlobalStepFromGathered(LevelState& state,
                                                  const std::vector<Index>& source,
                                                  const Rotations& coarse, const Context& context);
  virtual Index num_unknowns() const = 0;  ///< rows of the factored system
  virtual ConstraintReport constraint_report() const = 0;
  double precompute_seconds() const { return precompute_seconds_; }
  double constrain_seconds() const { return constrain_seconds_; }

 protected:
  LevelSolver() = default;
  LevelSolver(const LevelSolver&) = default;
  LevelSolver& operator=(const LevelSolver&) = default;
  double precompute_seconds_ = 0.0;
  double constrain_seconds_ = 0.0;
};

}  // namespace harap
