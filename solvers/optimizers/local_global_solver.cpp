// SPDX-License-Identifier: MIT
#include "solvers/optimizers/local_global_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "framework/config.h"
#include "framework/error.h"
#include "framework/stiffness.h"
#include "solvers/optimizers/coarse_constraints.h"

namespace harap {

namespace {

// Why Newton steps (LocalGlobalOptions::newton) cannot run with `energy` on a level that masks
// its handles (`handle_edits`, an interactive session) or not; "" if they can.
std::string NewtonProblem(const Energy& energy, bool handle_edits) {
  if (handle_edits) {
    return "optimizer.newton works on the eliminated global system of a one-shot run; an "
           "interactive session masks its handles instead: set newton = 0 (anderson works in a "
           "session)";
  }
  if (!energy.has_rotation_derivative()) {
    return "optimizer.newton needs an energy whose local step minimizes it (with a rotation "
           "derivative); this energy has none, or fits its rotations to a part of the energy: "
           "set newton = 0 or choose another energy";
  }
  return {};
}

}  // namespace

void LocalGlobalSolver::CheckCompatible(const Energy& energy, bool handle_edits) const {
  if (options_.newton == 0) return;
  const std::string problem = NewtonProblem(energy, handle_edits);
  if (!problem.empty()) throw ConfigError(problem);
}

std::unique_ptr<LevelSolver> LocalGlobalSolver::CreateAnother() const {
  return std::make_unique<LocalGlobalSolver>(options_);
}

LocalGlobalSolver::LocalGlobalSolver(const Mesh& mesh, const ComponentFactory& factory, int level,
                                     const Context& context, const Mesh* input_mesh) {
  Precompute(LevelSetup{&mesh, input_mesh, level, false}, factory, context);
}

LocalGlobalSolver::LocalGlobalSolver(const Mesh& mesh, const std::vector<Index>& constrained,
                                     const ComponentFactory& factory, int level,
                                     const Context& context, const Mesh* input_mesh)
    : LocalGlobalSolver(mesh, factory, level, context, input_mesh) {
  // Targets are not needed: Run() keeps the constrained rows of the state it is given.
  LevelConstraints constraints;
  constraints.vertices = constrained;
  constraints.mean_target = Positions::Zero(static_cast<Index>(constrained.size()), 3);
  Constrain(constraints, factory, context);
}

void LocalGlobalSolver::Precompute(const LevelSetup& setup, const ComponentFactory& factory,
                                   const Context& context) {
  Stopwatch clock;
  setup_ = setup;
  level_ = setup.level;
  context.ReportPhase(fmt::format("precomputing level {}", level_));
  energy_ = factory.MakeEnergy();
  data_term_ = nullptr;
  CheckCompatible(*energy_, setup.handle_edits);  // the run's check, for callers without one
  if (setup.stiffness != nullptr && !setup.stiffness->empty()) {
    energy_->SetStiffness(*setup.stiffness);
  }
  if (setup.input_mesh) energy_->SetInputMesh(*setup.input_mesh, context);
  energy_->Precompute(*setup.mesh, context);
  precompute_seconds_ = clock.Seconds();
  rhs_.resize(setup.mesh->num_vertices(), 3);
}

namespace {

// Every index of `vertices` is a vertex of a mesh of `n` vertices.
void CheckVertices(const std::vector<Index>& vertices, Index n) {
  for (Index v : vertices) HARAP_CHECK(v >= 0 && v < n, "constrained vertex {} out of range", v);
}

}  // namespace

ConstrainSummary LocalGlobalSolver::Constrain(const LevelConstraints& constraints,
                                              const ComponentFactory& factory,
                                              const Context& context) {
  HARAP_CHECK(energy_ != nullptr, "level {} constrained before its precomputation", level_);
  HARAP_CHECK(static_cast<Index>(constraints.vertices.size()) == constraints.mean_target.rows(),
              "{} constrained vertices but {} targets", constraints.vertices.size(),
              constraints.mean_target.rows());
  LevelConstraints mapped = constraints;
  CheckVertices(mapped.vertices, setup_.mesh->num_vertices());
  CheckVertices(mapped.soft.vertices, setup_.mesh->num_vertices());
  if (mapped.targets_follow_rotations() && energy_->rotation_site() == RotationSite::kElement) {
    FindIncidentElements(*setup_.mesh, mapped);
  }
  const bool data_term_changed = SetDataTerm(mapped.soft);
  const std::vector<Index> anchored =
      data_term_ ? data_term_->soft_targets().vertices : std::vector<Index>{};
  const ConstrainSummary summary =
      setup_.handle_edits
          ? ConstrainMasked(mapped.vertices, anchored, data_term_changed, factory, context)
          : ConstrainEliminated(mapped.vertices, anchored, factory, context);
  constraints_ = std::move(mapped);
  return summary;
}

void LocalGlobalSolver::MoveTargets(const Positions& mean_target) {
  MoveMeanTargets(constraints_, mean_target);
}

void LocalGlobalSolver::MoveSoftTargets(const Positions& targets) {
  HARAP_CHECK(data_term_ != nullptr, "level {}: soft targets moved before they were set", level_);
  data_term_->MoveSoftTargets(targets);
  constraints_.soft.targets = targets;
}

bool LocalGlobalSolver::SetDataTerm(const SoftTargets& soft) {
  if (soft.empty() && data_term_ == nullptr) return false;
  if (options_.newton > 0) {
    // The Hessian products apply B to rotation derivatives; B' = B + W T is affine in R.
    throw ConfigError(
        "soft handles (a handle with a `weight`) and Newton steps exclude each other: set "
        "newton = 0 (anderson works with soft handles)");
  }
  if (data_term_ == nullptr) {
    // The energy gains the data term in place: everything downstream sees A + W and B + W T.
    auto wrapped = std::make_unique<EnergyWithDataTerm>(std::move(energy_));
    data_term_ = wrapped.get();
    energy_ = std::move(wrapped);
  }
  return data_term_->SetSoftTargets(soft);
}

ConstrainSummary LocalGlobalSolver::ConstrainEliminated(const std::vector<Index>& constrained,
                                                        const std::vector<Index>& anchored,
                                                        const ComponentFactory& factory,
                                                        const Context& context) {
  Stopwatch clock;
  context.ReportPhase(fmt::format("factoring level {}", level_));
  masked_ = nullptr;
  auto system =
      std::make_unique<ConstrainedSystem>(energy_->system_matrix(), constrained, anchored);
  const ConstrainSummary summary =
      FactorGlobalStep(*system, level_, factory, context, clock, solver_, reduced_rhs_, reduced_x_);
  system_ = std::move(system);
  constrain_seconds_ = summary.seconds;
  return summary;
}

ConstrainSummary LocalGlobalSolver::ConstrainMasked(const std::vector<Index>& constrained,
                                                    const std::vector<Index>& anchored,
                                                    bool matrix_changed,
                                                    const ComponentFactory& factory,
                                                    const Context& context) {
  Stopwatch clock;
  // Other soft weights change A + W itself, on the diagonal of the soft vertices: those rows
  // are refactored with the ones whose fixedness changes (a matrix that does not fit the
  // masked system's pattern and components starts over).
  std::vector<Index> changed_values;
  if (matrix_changed && masked_ != nullptr &&
      !masked_->SetMatrix(energy_->system_matrix(), changed_values)) {
    masked_ = nullptr;
  }
  context.ReportPhase(fmt::format("{} level {}", masked_ ? "refactoring" : "factoring", level_));
  ConstrainSummary summary;
  if (masked_ == nullptr) {
    auto system = std::make_unique<MaskedSystem>(energy_->system_matrix());
    system->SetConstrained(constrained, anchored);
    masked_ = system.get();
    system_ = std::move(system);
    solver_ = factory.MakeLinearSolver(level_, masked_->num_unknowns());
    // Handle edits refactor this level: the solver may keep what makes that cheaper.
    solver_->PrepareForRefactor();
    needs_factorization_ = true;
    reduced_rhs_.resize(system_->num_unknowns(), 3);
    reduced_x_.resize(system_->num_unknowns(), 3);
    summary.changed_rows = masked_->num_unknowns();
  } else {
    std::vector<Index> changed = masked_->SetConstrained(constrained, anchored);
    if (!changed_values.empty()) {
      changed.insert(changed.end(), changed_values.begin(), changed_values.end());
      std::sort(changed.begin(), changed.end());
      changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
    }
    summary.changed_rows = static_cast<Index>(changed.size());
    if (!needs_factorization_ && !changed.empty()) {
      // Until the refactorization succeeds the factor is out of date: a throw leaves it so.
      needs_factorization_ = true;
      const LinearSolver::RefactorSummary refactor =
          solver_->Refactor(masked_->system_matrix(), changed, context);
      needs_factorization_ = false;
      summary.factored = true;
      summary.route = refactor.route;
    }
  }
  if (needs_factorization_) {
    solver_->Factorize(masked_->system_matrix(), context);
    needs_factorization_ = false;
    summary.factored = true;
    summary.route = LinearSolver::RefactorRoute::kFull;
  }
  summary.seconds = clock.Seconds();
  constrain_seconds_ = summary.seconds;
  if (summary.factored && context.system_callback) {
    context.system_callback(level_, system_->system_matrix());
  }
  return summary;
}

LocalGlobalSolver::RunResult LocalGlobalSolver::Run(
    LevelState& state, bool start_with_global_step, const LocalGlobalOptions& options,
    double diagonal, const Context& context,
    const TargetsFollowRotations& targets_follow_rotations) {
  HARAP_CHECK(system_ != nullptr, "level {} run before it was constrained", level_);
  HARAP_CHECK(state.positions.rows() == system_->num_vertices(), "{} positions for {} vertices",
              state.positions.rows(), system_->num_vertices());
  return Iterate(state, start_with_global_step, options, diagonal, context,
                 targets_follow_rotations);
}

double LocalGlobalSolver::FitRotations(LevelState& state, const Context& context) {
  HARAP_CHECK(state.positions.rows() == setup_.mesh->num_vertices(), "{} positions for {} vertices",
              state.positions.rows(), setup_.mesh->num_vertices());
  if (static_cast<Index>(state.rotations.size()) != energy_->num_rotations()) {
    state.rotations.assign(energy_->num_rotations(), Rotation::Identity());
  }
  return energy_->FitRotations(state.positions, state.rotations, context);
}

LevelSolveResult LocalGlobalSolver::Solve(LevelState& state, const LevelSolveRequest& request,
                                          const Context& context) {
  LocalGlobalOptions options = options_;
  options.tolerance = request.Tolerance(options.tolerance);
  if (request.energy_tolerance >= 0.0) options.energy_tolerance = request.energy_tolerance;
  if (request.max_iterations > 0) options.max_iterations = request.max_iterations;
  options.freeze_targets_after = request.freeze_targets_after;
  const RotationSite site = energy_->rotation_site();
  const bool have_rotations =
      static_cast<Index>(state.rotations.size()) == energy_->num_rotations();
  PlaceConstrainedVertices(constraints_, site, have_rotations ? &state.rotations : nullptr,
                           state.positions);
  LevelSolveResult result;
  if (request.global_step_only && have_rotations) {
    // The paper's approximation: one global solve from the given rotations, no local step (the
    // energy would cost one).
    result.linear_solves.Add(GlobalStep(state, context));
    result.iterations = 1;
    result.energy = std::numeric_limits<double>::quiet_NaN();
    return result;
  }
  TargetsFollowRotations follow;
  if (request.targets_follow_rotations && constraints_.targets_follow_rotations()) {
    // Before every global step.
    follow = [this, site](const Rotations& rotations, Positions& positions) {
      PlaceConstrainedVertices(constraints_, site, &rotations, positions);
    };
  }
  const RunResult run =
      Run(state, request.start_from_rotations, options, request.diagonal, context, follow);
  result.iterations = run.iterations;
  result.energy = run.energy;
  result.converged = run.converged;
  result.stopped_by_callback = run.stopped_by_callback;
  result.linear_solves = run.linear_solves;
  result.weights = energy_->weights();
  if (options.anderson > 0) result.measures["accelerated_iterations"] = run.accelerated_iterations;
  if (options.newton > 0) {
    result.measures["newton_steps"] = run.newton_steps;
    result.measures["hessian_products"] = static_cast<double>(run.hessian_products);
  }
  if (run.targets_frozen_at > 0) {
    result.notes.push_back(fmt::format(
        "level {}: coarse constraint targets stopped following the rotations after iteration "
        "{} (the energy kept rising)",
        level_, run.targets_frozen_at));
  }
  return result;
}

SolveSummary LocalGlobalSolver::GlobalStep(LevelState& state, const Context& context) {
  HARAP_CHECK(system_ != nullptr, "level {} run before it was constrained", level_);
  HARAP_CHECK(static_cast<Index>(state.rotations.size()) == energy_->num_rotations(),
              "{} rotations for {} sites", state.rotations.size(), energy_->num_rotations());
  Positions& u = state.positions;
  system_->SetFixedPositions(u);
  if (system_->num_free() == 0) return SolveSummary{};
  energy_->AssembleRhs(state.rotations, rhs_, context);
  system_->ReducedRhs(rhs_, reduced_rhs_);
  if (!solver_->is_direct()) system_->GatherFree(u, reduced_x_);
  const SolveSummary summary = solver_->Solve(reduced_rhs_, reduced_x_, context);
  if (!summary.success()) {
    throw NumericalError(
        fmt::format("linear solve failed on level {}: {}", level_, summary.message));
  }
  system_->ScatterFree(reduced_x_, u);
  return summary;
}

GatheredPreviewStep::Level LocalGlobalSolver::GatheredLevel() {
  HARAP_CHECK(system_ != nullptr, "level {} run before it was constrained", level_);
  return GatheredPreviewStep::Level{*energy_, *system_, *solver_, level_};
}

SolveSummary LocalGlobalSolver::GatheredGlobalStep(const std::vector<Index>& source,
                                                   const Rotations& coarse,
                                                   const std::vector<Index>& handles,
                                                   const Positions& targets, Positions& positions,
                                                   const Context& context) {
  return gathered_step_.Run(GatheredLevel(), source, coarse, handles, targets, positions, context);
}

LevelSolveResult LocalGlobalSolver::GlobalStepFromGathered(LevelState& state,
                                                           const std::vector<Index>& source,
                                                           const Rotations& coarse,
                                                           const Context& context) {
  HARAP_CHECK(accepts_gathered_rotations(),
              "level {}: gathered rotations for a level that cannot take them", level_);
  PlaceConstrainedVertices(constraints_, energy_->rotation_site(), nullptr, state.positions);
  // The state's rotations are left as they are.
  LevelSolveResult result;
  result.linear_solves.Add(gathered_step_.Run(GatheredLevel(), source, coarse,
                                              constraints_.vertices, constraints_.mean_target,
                                              state.positions, context));
  result.iterations = 1;
  result.energy = std::numeric_limits<double>::quiet_NaN();
  return result;
}

bool LocalGlobalSolver::accepts_gathered_rotations() const {
  // GatheredGlobalStep's conditions: one rotation per vertex, exact (input-level) targets.
  // Soft targets are terms of the energy, which the gathered step does not assemble.
  return energy_ != nullptr && setup_.mesh != nullptr && constraints_.soft.empty() &&
         energy_->rotation_site() == RotationSite::kVertex &&
         energy_->num_rotations() == setup_.mesh->num_vertices() &&
         !constraints_.targets_follow_rotations();
}

std::map<std::string, double> LocalGlobalSolver::AuxiliaryMeasures(const LevelState& state,
                                                                   const Context& context) const {
  HARAP_CHECK(static_cast<Index>(state.rotations.size()) == energy_->num_rotations(),
              "{} rotations for {} sites", state.rotations.size(), energy_->num_rotations());
  return energy_->AuxiliaryMeasures(state.positions, state.rotations, context);
}

LocalGlobalSolver::RunResult LocalGlobalSolver::Iterate(
    LevelState& state, bool start_with_global_step, const LocalGlobalOptions& options,
    double diagonal, const Context& context,
    const TargetsFollowRotations& targets_follow_rotations) {
  if (static_cast<Index>(state.rotations.size()) != energy_->num_rotations()) {
    state.rotations.assign(energy_->num_rotations(), Rotation::Identity());
  }
  system_->SetFixedPositions(state.positions);
  RunResult result;
  const double squared_diagonal = diagonal * diagonal;
  double energy = start_with_global_step
                      ? 0.0
                      : energy_->FitRotations(state.positions, state.rotations, context);
  if (system_->num_free() == 0) {
    result.energy = start_with_global_step
                        ? energy_->FitRotations(state.positions, state.rotations, context)
                        : energy;
    result.converged = true;
    return result;
  }
  // Moving constraint targets make an iteration no longer a descent step and the energy can cycle
  // (see LocalGlobalOptions::freeze_targets_after); after that many increases the remaining
  // iterations are plain local/global steps: monotone and convergent.
  int energy_increases = 0;
  bool targets_frozen = false;
  double previous_energy = energy;
  double energy_scale = std::abs(energy);  // the largest energy seen on the level
  // Whether `energy` is E(u, R(u)) of the current positions (not so before a first global step
  // from handed-down rotations): the safeguard of Anderson acceleration compares against it.
  bool energy_is_fitted = !start_with_global_step;
  if (options.anderson > 0) {
    // The unknowns of a masked system include the fixed rows; they hold the targets in every
    // iterate, so the extrapolation keeps them (its weights sum to one) and ScatterFree skips them.
    anderson_.Reset(system_->num_unknowns(), options.anderson);
    current_free_.resize(system_->num_unknowns(), 3);
    accelerated_free_.resize(system_->num_unknowns(), 3);
    trial_positions_ = state.positions;
  }
  if (options.newton > 0) {
    // Run()'s options may differ from the level's (CheckCompatible checked those).
    const std::string problem = NewtonProblem(*energy_, masked_ != nullptr);
    if (!problem.empty()) throw ConfigError(problem);
    newton_.Reset(system_->num_vertices(), system_->num_free(), options.newton_exact_hessian);
  }
  while (result.iterations < options.max_iterations) {
    const bool targets_move = targets_follow_rotations && !targets_frozen;
    if (targets_move) {
      targets_follow_rotations(state.rotations, state.positions);
      system_->SetFixedPositions(state.positions);
    }
    // Global step: A_ff U_f = B_f(R) − A_fc U_c, all three coordinates at once.
    energy_->AssembleRhs(state.rotations, rhs_, context);
    system_->ReducedRhs(rhs_, reduced_rhs_);
    // Iterative solvers start from the current positions; direct ones ignore the warm start.
    if (!solver_->is_direct()) system_->GatherFree(state.positions, reduced_x_);
    const SolveSummary summary = solver_->Solve(reduced_rhs_, reduced_x_, context);
    result.linear_solves.Add(summary);
    if (!summary.success()) {
      throw NumericalError(
          fmt::format("linear solve failed on level {}: {}", level_, summary.message));
    }
    // Newton steps and Anderson's extrapolation need the same map G(u) = global(local(u)) from
    // one iteration to the next (fixed targets) and rotations fitted to u.
    double displacement = 0.0;
    const bool previous_energy_known = energy_is_fitted;
    if (options.newton > 0 && !targets_move && energy_is_fitted) {
      displacement = NewtonIteration(state, energy, options, squared_diagonal, context, result);
    } else {
      displacement = LocalGlobalIteration(state, energy, options, targets_move, energy_is_fitted,
                                          squared_diagonal, context, result);
    }
    energy_is_fitted = true;
    ++result.iterations;
    if (!std::isfinite(energy)) {
      throw NumericalError(fmt::format("the energy became {} on level {} at iteration {}", energy,
                                       level_, result.iterations));
    }
    if (targets_follow_rotations && !targets_frozen && result.iterations > 1 &&
        energy > previous_energy * (1.0 + 1e-12) &&
        ++energy_increases == options.freeze_targets_after) {
      targets_frozen = true;
      result.targets_frozen_at = result.iterations;
    }
    // The last iteration's relative energy change, for energy_tolerance (unknown after a first
    // global step from handed-down rotations: no energy before it). An increase (moving coarse
    // targets) counts by its size. Relative to E, but at least to a millionth of the level's
    // largest energy, so that a minimum of 0 (targets a rigid motion reaches) still stops.
    energy_scale = std::max(energy_scale, std::abs(energy));
    const double energy_change =
        previous_energy_known
            ? std::abs(previous_energy - energy) / std::max({std::abs(energy), 1e-6 * energy_scale,
                                                             std::numeric_limits<double>::min()})
            : std::numeric_limits<double>::infinity();
    previous_energy = energy;
    if (context.iteration_callback) {
      IterationSummary summary_for_callback{level_, result.iterations, energy, displacement,
                                            context.run_clock.Seconds()};
      if (context.iteration_callback(summary_for_callback) == CallbackAction::kStop) {
        result.stopped_by_callback = true;
        break;
      }
    }
    if (displacement < options.tolerance &&
        (options.energy_tolerance <= 0.0 || energy_change < options.energy_tolerance)) {
      result.converged = true;
      break;
    }
  }
  result.energy = energy;
  return result;
}

double LocalGlobalSolver::NewtonIteration(LevelState& state, double& energy,
                                          const LocalGlobalOptions& options,
                                          double squared_diagonal, const Context& context,
                                          RunResult& result) {
  const NewtonCgStep::Outcome step = newton_.Step(
      *energy_, static_cast<const ConstrainedSystem&>(*system_), *solver_, options.newton,
      state.positions, state.rotations, energy, reduced_rhs_, reduced_x_, context);
  result.newton_steps += step.newton ? 1 : 0;
  result.hessian_products += step.cg_iterations;
  energy = step.energy;
  // The convergence test measures the plain step A_ff⁻¹ rhs − u_f, as without Newton steps.
  return step.plain_step_displacement / squared_diagonal;
}

double LocalGlobalSolver::LocalGlobalIteration(LevelState& state, double& energy,
                                               const LocalGlobalOptions& options, bool targets_move,
                                               bool energy_is_fitted, double squared_diagonal,
                                               const Context& context, RunResult& result) {
  // The map G(u) = global(local(u)) may be accelerated only while it stays the same map
  // (fixed targets) and the pairs (u, G(u)) are true ones (rotations fitted to u).
  const bool accelerate = options.anderson > 0 && !targets_move && energy_is_fitted;
  bool extrapolated = false;
  if (accelerate) {
    system_->GatherFree(state.positions, current_free_);
    extrapolated = anderson_.Step(current_free_, reduced_x_, accelerated_free_, context);
  } else if (options.anderson > 0) {
    anderson_.Clear();
    // The fixed rows of the trial positions: they stay put while the acceleration runs (the
    // targets no longer move), so only the free rows are written from here on.
    trial_positions_ = state.positions;
  }
  // The displacement of the plain step, G(u) − u: the convergence test is the same with and
  // without acceleration.
  const double displacement = system_->ScatterFree(reduced_x_, state.positions) / squared_diagonal;
  bool accepted = false;
  if (extrapolated) {
    // Safeguard [Peng et al. 2018]: keep the accelerated iterate only if its energy (rotations
    // fitted) is below the current iterate's; the plain step never raises it, so the iteration
    // stays monotone.
    // The rotations are fitted in place: if the extrapolation is rejected, the plain step's
    // fit below starts from them, as good a warm start as the old ones (G(u) is near both).
    system_->ScatterFree(accelerated_free_, trial_positions_);
    const double trial_energy = energy_->FitRotations(trial_positions_, state.rotations, context);
    if (trial_energy < energy) {
      std::swap(state.positions, trial_positions_);
      energy = trial_energy;
      accepted = true;
      ++result.accelerated_iterations;
    }
  }
  // Local step: best-fit rotations for the new positions; also yields E(U, R).
  if (!accepted) energy = energy_->FitRotations(state.positions, state.rotations, context);
  return displacement;
}

Positions InitialPositions(const DeformationProblem& problem) {
  HARAP_CHECK(problem.mesh != nullptr, "deformation problem without a mesh");
  const Mesh& mesh = *problem.mesh;
  const Constraints& constraints = problem.constraints;
  ValidateStiffness(problem.stiffness, mesh, "the deformation problem");
  Positions u = problem.initial ? *problem.initial : mesh.vertices;
  if (u.rows() != mesh.num_vertices()) {
    throw InputError(fmt::format("the initial configuration has {} vertices, the mesh {}", u.rows(),
                                 mesh.num_vertices()));
  }
  if (!u.allFinite()) throw InputError("the initial configuration has non-finite coordinates");
  if (static_cast<Index>(constraints.indices.size()) != constraints.targets.rows()) {
    throw InputError(fmt::format("{} constrained vertices but {} targets",
                                 constraints.indices.size(), constraints.targets.rows()));
  }
  if (!constraints.weights.empty() && constraints.weights.size() != constraints.indices.size()) {
    throw InputError(fmt::format("{} constrained vertices but {} weights",
                                 constraints.indices.size(), constraints.weights.size()));
  }
  for (size_t k = 0; k < constraints.indices.size(); ++k) {
    const Index v = constraints.indices[k];
    if (v < 0 || v >= mesh.num_vertices()) {
      throw InputError(
          fmt::format("constrained vertex {} is out of range (the mesh has {} "
                      "vertices)",
                      v, mesh.num_vertices()));
    }
    if (!constraints.targets.row(k).allFinite()) {
      throw InputError(fmt::format("the target of constrained vertex {} is not finite", v));
    }
    if (!constraints.weights.empty()) {
      const double w = constraints.weights[k];
      if (!(w > 0.0)) {
        throw InputError(fmt::format(
            "the weight of constrained vertex {} is {}; a soft handle's weight must be > 0", v, w));
      }
      // A soft target pulls the vertex from where it starts.
      if (!constraints.is_hard(k)) continue;
    }
    u.row(v) = constraints.targets.row(k);
  }
  if (mesh.planar) {
    // Planar energies rotate in the plane only; a position off the plane would be pulled back
    // by nothing but the Laplacian of z, which is not the energy the user asked for.
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      if (u(v, 2) != 0.0) {
        throw InputError(
            fmt::format("the mesh is planar (z = 0) but the {} of vertex {} has "
                        "z = {}; targets and initial positions of a planar mesh "
                        "must lie in the plane",
                        std::find(constraints.indices.begin(), constraints.indices.end(), v) !=
                                constraints.indices.end()
                            ? "target"
                            : "initial position",
                        v, u(v, 2)));
      }
    }
  }
  return u;
}

LocalGlobalOptions ReadLocalGlobalOptions(OptionReader node) {
  LocalGlobalOptions options;
  options.tolerance = node.Get("tolerance", options.tolerance,
                               "stop when max squared vertex displacement of a global step / "
                               "squared bounding-box diagonal falls below this (0: never)",
                               Range::AtLeast(0.0));
  options.energy_tolerance =
      node.Get("energy_tolerance", options.energy_tolerance,
               "also require the last iteration to have changed the energy by less than this "
               "fraction, |E_prev − E| / E, before the displacement test stops a level (0: the "
               "displacement test alone, the paper's)",
               Range::AtLeast(0.0));
  options.max_iterations =
      node.Get("max_iterations", options.max_iterations,
               "cap on local/global iterations (per level)", Range::AtLeast(1));
  options.anderson = node.Get("anderson", options.anderson,
                              "Anderson acceleration with this many previous iterates, "
                              "safeguarded by the energy (0: off; 5 is typical)",
                              Range::AtLeast(0));
  options.newton = node.Get("newton", options.newton,
                            "truncated Newton steps with at most this many preconditioned "
                            "conjugate-gradient iterations each, instead of local/global steps "
                            "(0: off; 20 is typical)",
                            Range::AtLeast(0));
  options.newton_exact_hessian =
      node.GetChoice("newton_hessian", "exact", {"exact", "projected"},
                     "Hessian model of the Newton steps: exact (indefinite, trust region) or "
                     "projected per rotation site (positive semi-definite, line search)") ==
      "exact";
  if (options.newton > 0 && options.anderson > 0) {
    node.Fail("newton",
              "Newton steps and Anderson acceleration exclude each other: set one of "
              "`newton` and `anderson` to 0");
  }
  return options;
}

}  // namespace harap
