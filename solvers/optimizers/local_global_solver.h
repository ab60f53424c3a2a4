// SPDX-License-Identifier: MIT
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>

#include "framework/config.h"
#include "framework/constrained_system.h"
#include "framework/data_term.h"
#include "framework/level_solver.h"
#include "framework/optimizer.h"
#include "solvers/optimizers/anderson_acceleration.h"
#include "solvers/optimizers/gathered_preview_step.h"
#include "solvers/optimizers/newton_cg.h"

namespace harap {

/// Options of the local/global iteration on one level (shared by every optimizer that runs it).
struct LocalGlobalOptions {
  /// Stop when max_i ‖Δu_i‖² / diag² of a global step falls below this (the paper's criterion,
  /// Section 5.1; 1e-6 in its experiments). 0 runs to max_iterations.
  double tolerance = 1e-6;
  /// With a value > 0, the displacement test alone does not stop the level: the last iteration
  /// must also have changed the energy by less than this fraction, |E_prev − E| / E (E at least a
  /// millionth of the level's largest energy, so that a minimum of 0 still stops). The
  /// displacement test stops where a step moves little, which on a slowly converging level can be
  /// while the energy still falls by a fraction of a percent per iteration (docs/results.md,
  /// Fig. 11). 0 (the default): the displacement test alone, the paper's.
  double energy_tolerance = 0.0;
  int max_iterations = 1000;  ///< Cap on local/global iterations on the level.
  /// With moving constraint targets (Run's `targets_follow_rotations`): after this many iterations
  /// that raised the energy, the targets stay where they are for the rest of the run (0: never).
  /// Moving targets make an iteration no longer a descent step; a few increases are a normal
  /// transient while they swing into place, but some levels cycle forever (tetrahedral meshes,
  /// edge-collapse hierarchies, smooth_arap). Set by hierarchical's `freeze_targets_after`.
  int freeze_targets_after = 3;
  /// Anderson acceleration of the local/global map with this many previous iterates (0: off),
  /// safeguarded by the energy so the iteration stays monotone [Peng et al. 2018]; see
  /// anderson_acceleration.h. Inactive while moving constraint targets change the map.
  int anderson = 0;
  /// Truncated Newton steps (newton_cg.h) instead of plain local/global steps, with at most this
  /// many preconditioned conjugate-gradient iterations each (0: off). Needs an energy with
  /// Energy::has_rotation_derivative(); excludes `anderson`. Inactive while moving constraint
  /// targets change the energy.
  int newton = 0;
  /// The Hessian model of the Newton steps: true = exact, in a trust region; false = projected
  /// per rotation site, with a line search (newton_cg.h). Exact by default: it leaves saddle
  /// points the projected model crawls past (measured in docs/results.md).
  bool newton_exact_hessian = true;
};

/// Local/global ARAP iterations on one mesh level, the paper's level solver (registry name
/// `local_global`): owns the level's energy, constrained system and factored linear solver.
/// Precompute() (or the first constructors) does the precomputation (energy weights: the paper's
/// P phase), Constrain() the constraint handling and factorization (the C phase); Solve() and
/// Run() do the S phase. Per-iteration work allocates nothing.
///
/// Two ways to constrain (LevelSetup::handle_edits): eliminating the fixed vertices
/// (ConstrainedSystem: the smallest system, for a run with one constraint set) or masking them
/// (MaskedSystem: a system of one size and pattern for every constraint set, so a later call
/// with another set brings the factorization up to date with LinearSolver::Refactor on the rows
/// that changed instead of factoring anew: interactive sessions). Newton steps need the
/// eliminated system.
///
/// Everything is in the numbering of the level's mesh: the energy, the system, states and
/// constraints, with no copies in another order. The level cascade hands it meshes already
/// renumbered for memory locality (level_cascade.h, vertex_ordering.h).
class LocalGlobalSolver final : public LevelSolver {
 public:
  static constexpr std::string_view kName = "local_global";

  explicit LocalGlobalSolver(const LocalGlobalOptions& options = {}) : options_(options) {}

  /// The P phase only (Precompute()); Constrain() must follow before Run(). `input_mesh`: see
  /// LevelSetup.
  LocalGlobalSolver(const Mesh& mesh, const ComponentFactory& factory, int level,
                    const Context& context, const Mesh* input_mesh = nullptr);
  /// P and C at once (eliminated): `constrained` are vertex indices whose positions are
  /// prescribed (their rows of the state at Run()).
  LocalGlobalSolver(const Mesh& mesh, const std::vector<Index>& constrained,
                    const ComponentFactory& factory, int level, const Context& context,
                    const Mesh* input_mesh = nullptr);

  // LevelSolver.
  std::unique_ptr<LevelSolver> CreateAnother() const override;
  /// Newton steps need an energy with a rotation derivative and the eliminated system (no
  /// session).
  void CheckCompatible(const Energy& energy, bool handle_edits) const override;
  void Precompute(const LevelSetup& setup, const ComponentFactory& factory,
                  const Context& context) override;
  /// Eliminated: a new solver from `factory` factors the reduced system. Masked
  /// (LevelSetup::handle_edits): the first call builds the masked system and factors it (a
  /// solver asked for num_vertices() unknowns); later calls refactor only the changed rows
  /// (LinearSolver::Refactor). On a throw from the linear solver the next call factors anew.
  ConstrainSummary Constrain(const LevelConstraints& constraints, const ComponentFactory& factory,
                             const Context& context) override;
  void MoveTargets(const Positions& mean_target) override;
  /// Soft constraints (LevelConstraints::soft) become a data term of the level's energy
  /// (EnergyWithDataTerm): A + W factored once per weight set, moved targets change only B.
  void MoveSoftTargets(const Positions& targets) override;
  bool accepts_soft_targets() const override { return true; }
  /// Run() with the level's options (the request's limits), the constrained vertices placed
  /// first and, with request.targets_follow_rotations on a coarse level, before every global
  /// step. Measures: "accelerated_iterations" (with `anderson`), "newton_steps" and
  /// "hessian_products" (with `newton`).
  LevelSolveResult Solve(LevelState& state, const LevelSolveRequest& request,
                         const Context& context) override;
  /// The local step on `state`: fits its rotations to its positions and returns the energy.
  double FitRotations(LevelState& state, const Context& context) override;
  /// Energy::AuxiliaryMeasures of `state` (rotations fitted).
  std::map<std::string, double> AuxiliaryMeasures(const LevelState& state,
                                                  const Context& context) const override;
  RotationSite rotation_site() const override { return energy_->rotation_site(); }
  /// Per-vertex rotations on a level with exact targets (the input level): the preview's global
  /// step takes them gathered (GatheredPreviewStep).
  bool accepts_gathered_rotations() const override;
  LevelSolveResult GlobalStepFromGathered(LevelState& state, const std::vector<Index>& source,
                                          const Rotations& coarse, const Context& context) override;
  Index num_unknowns() const override { return system_->num_free(); }
  ConstraintReport constraint_report() const override { return system_->report(); }

  /// What the level's run did.
  struct RunResult {
    int iterations = 0;
    double energy = 0.0;  ///< E(u, R) with R fitted to the final u.
    bool converged = false;
    bool stopped_by_callback = false;
    /// With moving constraint targets: the iteration after which they were frozen because the
    /// energy kept rising (0: never).
    int targets_frozen_at = 0;
    /// With `anderson`: iterations whose accelerated iterate was kept (lower energy than the plain
    /// local/global step's starting point).
    int accelerated_iterations = 0;
    /// With `newton`: iterations that took a Newton step (the others the plain local/global
    /// step), and the Hessian-vector products (CG iterations) they used.
    int newton_steps = 0;
    long long hessian_products = 0;
    SolveStatistics linear_solves;  ///< The global steps' solves (iterations, residuals, time).
  };

  /// The iteration Solve() runs, with explicit options and no placement of the constrained
  /// vertices (drivers call Solve(); this is for tests of the iteration itself).
  /// Iterates from `state`. If `start_with_global_step`, the rotations in `state` are used for
  /// the first global step (rotation up-sampling, Eq. 7); otherwise the first step is a local step
  /// from state.positions. Fixed vertices keep their rows of state.positions. `diagonal` scales the
  /// convergence test. On return `state` holds the final positions and fitted rotations.
  ///
  /// `targets_follow_rotations`, if set, is called before every global step with the current
  /// rotations and may move constrained vertices in the positions (Solve(): coarse constraint
  /// targets that follow the cluster rotations, Section 4); the reduced right-hand side then uses
  /// the new positions. Moving targets
  /// make the iteration non-monotone in principle: after the first iteration that increases the
  /// energy, the targets stay where they are and the run continues as a plain, monotone
  /// local/global iteration.
  using TargetsFollowRotations = std::function<void(const Rotations&, Positions&)>;
  RunResult Run(LevelState& state, bool start_with_global_step, const LocalGlobalOptions& options,
                double diagonal, const Context& context,
                const TargetsFollowRotations& targets_follow_rotations = {});

  /// One global step alone (the paper's coarse approximation, Fig. 15): the free positions of
  /// `state` from its rotations, the fixed ones kept; rotations unchanged.
  SolveSummary GlobalStep(LevelState& state, const Context& context);
  /// The gathered preview step (GatheredPreviewStep::Run) on this level.
  SolveSummary GatheredGlobalStep(const std::vector<Index>& source, const Rotations& coarse,
                                  const std::vector<Index>& handles, const Positions& targets,
                                  Positions& positions, const Context& context);
  /// Whether GatheredGlobalStep() evaluates its right-hand side from the probed linear map.
  bool gathered_rhs_is_linear() const { return gathered_step_.rhs_is_linear(); }

  /// The level's energy.
  const Energy& energy() const { return *energy_; }

 private:
  RunResult Iterate(LevelState& state, bool start_with_global_step,
                    const LocalGlobalOptions& options, double diagonal, const Context& context,
                    const TargetsFollowRotations& targets_follow_rotations);
  // One iteration from `state` (rotations fitted unless !energy_is_fitted) after the global
  // step's solve into reduced_x_; updates `energy` and returns the plain step's displacement
  // for the convergence test.
  double NewtonIteration(LevelState& state, double& energy, const LocalGlobalOptions& options,
                         double squared_diagonal, const Context& context, RunResult& result);
  double LocalGlobalIteration(LevelState& state, double& energy, const LocalGlobalOptions& options,
                              bool targets_move, bool energy_is_fitted, double squared_diagonal,
                              const Context& context, RunResult& result);

  ConstrainSummary ConstrainEliminated(const std::vector<Index>& constrained,
                                       const std::vector<Index>& anchored,
                                       const ComponentFactory& factory, const Context& context);
  ConstrainSummary ConstrainMasked(const std::vector<Index>& constrained,
                                   const std::vector<Index>& anchored, bool matrix_changed,
                                   const ComponentFactory& factory, const Context& context);
  // Gives the energy the data term of `soft` (the mesh's numbering), wrapping it the first
  // time; returns whether the system matrix changed.
  bool SetDataTerm(const SoftTargets& soft);

  LocalGlobalOptions options_;
  LevelSetup setup_;
  int level_ = 0;
  LevelConstraints constraints_;
  std::unique_ptr<Energy> energy_;
  EnergyWithDataTerm* data_term_ = nullptr;  ///< energy_ once it has soft targets
  std::unique_ptr<GlobalStepSystem> system_;
  MaskedSystem* masked_ = nullptr;    ///< system_ when masked
  bool needs_factorization_ = false;  ///< masked: a Refactor threw, factor anew next time
  std::unique_ptr<LinearSolver> solver_;
  // Per-iteration buffers, allocated once.
  Positions rhs_;
  Eigen::MatrixXd reduced_rhs_;
  Eigen::MatrixXd reduced_x_;
  // Anderson acceleration (options.anderson > 0): the current free positions, the accelerated
  // ones, and the positions they are evaluated at.
  AndersonAcceleration anderson_;
  Eigen::MatrixXd current_free_, accelerated_free_;
  Positions trial_positions_;
  NewtonCgStep newton_;
  // The preview's global step from gathered rotations (GlobalStepFromGathered()).
  GatheredPreviewStep::Level GatheredLevel();
  GatheredPreviewStep gathered_step_;
};

/// Initial positions of a problem: `problem.initial` or the rest positions, with constrained
/// vertices at their targets. Validates the constraints (index range, finite targets).
Positions InitialPositions(const DeformationProblem& problem);

/// Reads the options shared by all local/global optimizers from their config table.
LocalGlobalOptions ReadLocalGlobalOptions(OptionReader node);

}  // namespace harap
