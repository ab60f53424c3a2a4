// SPDX-License-Identifier: MIT
#include "solvers/optimizers/hierarchical_optimizer.h"

#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "framework/error.h"
#include "solvers/optimizers/coarse_constraints.h"
#include "solvers/optimizers/level_cascade.h"
#include "solvers/optimizers/level_setup_pipeline.h"
#include "solvers/optimizers/local_global_solver.h"

namespace harap {

HierarchicalOptimizer::Options HierarchicalOptimizer::Options::FromConfig(
    OptionReader node, const Registry<LevelSolver>& level_solvers) {
  Options options;
  options.inner = node.GetChoice("inner", options.inner, level_solvers.Names(),
                                 "level solver on each level (`harap list inner`): local_global "
                                 "(the paper's), admm_pd or wrapd (energy `elements`; tolerance "
                                 "and max_iterations then take their meaning)");
  options.level_solver = level_solvers.Create(options.inner, node);
  options.coarse_tolerance =
      node.Get("coarse_tolerance", options.coarse_tolerance,
               "convergence tolerance on the coarse levels (negative: tolerance × "
               "coarse_tolerance_factor)");
  options.coarse_tolerance_factor =
      node.Get("coarse_tolerance_factor", options.coarse_tolerance_factor,
               "the coarse levels' tolerance as a multiple of the finest level's, unless "
               "coarse_tolerance is set (below 1: better converged starts for the finer levels)",
               Range::Above(0.0));
  options.coarse_energy_tolerance =
      node.Get("coarse_energy_tolerance", options.coarse_energy_tolerance,
               "energy_tolerance on the coarse levels (-1: the same as on the finest; 0: the "
               "displacement test alone; local_global levels only)",
               Range::AtLeast(-1.0));
  if (options.coarse_energy_tolerance >= 0.0 && options.inner != "local_global") {
    node.Fail("coarse_energy_tolerance",
              fmt::format("applies to the local_global level solver only, not to inner = \"{}\" "
                          "(whose tolerance is its own stopping test)",
                          options.inner));
  }
  options.level_step = node.Get("level_step", options.level_step,
                                "solve every k-th level (1: all; the finest and coarsest always)",
                                Range::AtLeast(1));
  options.coarsest_only = node.Get("coarsest_only", options.coarsest_only,
                                   "solve only the coarsest and the finest level (Fig. 14)");
  options.coarse_approximation =
      node.Get("coarse_approximation", options.coarse_approximation,
               "up-sample the coarsest solution straight to the finest level and solve once "
               "(Fig. 15)");
  if (node.Has("update_constraints")) {
    // The option's name before it became the same as LevelSolveRequest's.
    throw ConfigError(fmt::format(
        "{}: option '{}update_constraints' is now called 'targets_follow_rotations'",
        node.Where("update_constraints"), node.path().empty() ? "" : node.path() + "."));
  }
  options.targets_follow_rotations =
      node.Get("targets_follow_rotations", options.targets_follow_rotations,
               "re-evaluate coarse constraint targets with the current rotations (Fig. 16)");
  options.overlap_setup =
      node.Get("overlap_setup", options.overlap_setup,
               "set up (precompute, factor) finer levels on another thread while coarser levels "
               "are solved; phase times then overlap");
  options.freeze_targets_after =
      node.Get("freeze_targets_after", options.freeze_targets_after,
               "with targets_follow_rotations: keep a level's coarse targets fixed after this many "
               "iterations "
               "raised its energy (0: never; moving targets can make the energy cycle)",
               Range::AtLeast(0));
  node.RejectUnknownKeys();
  return options;
}

HierarchicalOptimizer::Options HierarchicalOptimizer::Options::OneLevel(
    OptionReader node, const Registry<LevelSolver>& level_solvers, std::string_view inner) {
  Options options;
  options.inner = std::string(inner);
  options.hierarchical = false;
  options.level_solver = level_solvers.Create(inner, node);
  node.RejectUnknownKeys();
  return options;
}

std::vector<int> HierarchicalOptimizer::Options::SolvedLevels(int num_levels) const {
  const int coarsest = num_levels - 1;
  std::vector<bool> solved(num_levels, false);
  solved[0] = solved[coarsest] = true;
  if (!coarsest_only && !coarse_approximation) {
    for (int l = coarsest; l >= 0; l -= level_step) solved[l] = true;
  }
  std::vector<int> levels;
  for (int l = coarsest; l >= 0; --l) {
    if (solved[l]) levels.push_back(l);
  }
  return levels;
}

LevelSolveRequest HierarchicalOptimizer::Options::Request(int level, int num_levels,
                                                          bool start_from_rotations,
                                                          double diagonal) const {
  LevelSolveRequest request;
  request.start_from_rotations = start_from_rotations;
  request.diagonal = diagonal;
  if (level > 0 && coarse_tolerance >= 0.0) request.tolerance = coarse_tolerance;
  if (level > 0 && coarse_tolerance < 0.0) request.tolerance_factor = coarse_tolerance_factor;
  if (level > 0 && coarse_energy_tolerance >= 0.0) {
    request.energy_tolerance = coarse_energy_tolerance;
  }
  if (level == 0 && coarse_approximation && num_levels > 1) request.max_iterations = 1;
  request.targets_follow_rotations = targets_follow_rotations;
  request.freeze_targets_after = freeze_targets_after;
  return request;
}

void HierarchicalOptimizer::CheckComponents(const ComponentFactory& factory) const {
  options_.level_solver->CheckCompatible(*factory.MakeEnergy(), /*handle_edits=*/false);
}

std::vector<std::string> DescribeConstraintHandling(const ConstraintReport& report) {
  std::vector<std::string> notes;
  if (report.isolated_vertices > 0) {
    notes.push_back(
        fmt::format("{} vertices are used by no (non-degenerate) element; they keep "
                    "their initial positions",
                    report.isolated_vertices));
  }
  if (report.free_components > 0) {
    notes.push_back(
        fmt::format("{} connected components ({} vertices) have no constrained "
                    "vertex; one vertex of each is pinned at its initial position "
                    "(the energy is invariant to translating them)",
                    report.free_components, report.vertices_in_free_components));
  }
  return notes;
}

namespace {

// What one level's setup (P and C) made.
struct LevelSetupResult {
  std::unique_ptr<LevelSolver> solver;
  double precompute_seconds = 0.0, constrain_seconds = 0.0, seconds = 0.0;
};

// P and C of level l (from whichever thread gets there first; see LevelSetupPipeline). Level 0
// is the input mesh (renumbered), so its setup needs no hierarchy. `constraints`: the problem's,
// in level 0's numbering.
LevelSetupResult SetUpLevel(int l, const HierarchicalOptimizer::Options& options,
                            const LevelCascade& cascade, const DeformationProblem& problem,
                            const Constraints& constraints, const ComponentFactory& factory,
                            const Context& context) {
  Stopwatch clock;
  const Mesh& mesh = *problem.mesh;
  const LevelConstraints level_constraints = l == 0
                                                 ? LevelConstraints::Exact(constraints, mesh.planar)
                                                 : cascade.MapConstraints(l, constraints);
  const std::vector<double> stiffness = cascade.LevelStiffness(l, problem.stiffness);
  LevelSetupResult setup;
  setup.solver = options.level_solver->CreateAnother();
  // Coarse levels' energies are normalized like the input mesh's (Energy::SetInputMesh).
  setup.solver->Precompute(
      LevelSetup{&cascade.LevelMesh(l), l > 0 ? &mesh : nullptr, l, false, &stiffness}, factory,
      context);
  setup.solver->Constrain(level_constraints, factory, context);
  setup.precompute_seconds = setup.solver->precompute_seconds();
  setup.constrain_seconds = setup.solver->constrain_seconds();
  setup.seconds = clock.Seconds();
  return setup;
}

// A one-shot run's pass down the cascade: every solved level from the up-sampled solution of the
// coarser one, each waiting for its setup, a coarse level's solver freed once it is solved.
class OneShotPass final : public LevelCascade::Pass {
 public:
  OneShotPass(const HierarchicalOptimizer::Options& options, LevelCascade& cascade,
              LevelSetupPipeline& setup, const std::function<void(int)>& wait_for,
              Positions initial, const Context& context)
      : options_(options),
        cascade_(cascade),
        setup_(setup),
        wait_for_(wait_for),
        initial_(std::move(initial)),
        context_(context),
        solved_(options.SolvedLevels(cascade.num_levels())),
        diagonal_(BoundingBoxDiagonal(cascade.input_mesh())) {}

  const std::vector<int>& solved_levels() const { return solved_; }

  bool Solves(int l) const override {
    return std::find(solved_.begin(), solved_.end(), l) != solved_.end();
  }
  LevelState& Start(int l, const LevelState* coarser, bool& from_rotations) override {
    if (coarser == nullptr) {
      state_.positions = l == 0 ? initial_ : cascade_.LevelMesh(l).vertices;
      return state_;
    }
    LevelState coarse_state = std::move(state_);
    state_ = LevelState();
    from_rotations = cascade_.Upsample(l, coarse_state, state_, context_);
    return state_;
  }
  void Prepare(int l) override { wait_for_(l); }
  LevelSolveRequest Request(int l, bool from_rotations, bool /*finishing*/) override {
    return options_.Request(l, cascade_.num_levels(), from_rotations, diagonal_);
  }
  LevelSolveResult Solve(LevelSolver& solver, LevelState& state, const LevelSolveRequest& request,
                         const Context& context) override {
    return setup_.Isolated(context, [&] { return solver.Solve(state, request, context); });
  }
  LevelState& Done(int l, LevelState& state, const LevelSolveResult* run) override {
    // The level's factor is no longer needed.
    if (l > 0 && run != nullptr && !run->stopped_by_callback) cascade_.release_solver(l);
    return state;
  }

 private:
  const HierarchicalOptimizer::Options& options_;
  LevelCascade& cascade_;
  LevelSetupPipeline& setup_;
  const std::function<void(int)>& wait_for_;
  Positions initial_;
  const Context& context_;
  std::vector<int> solved_;
  double diagonal_;
  LevelState state_;
};

}  // namespace

OptimizeResult HierarchicalOptimizer::Optimize(const DeformationProblem& problem,
                                               const ComponentFactory& factory,
                                               const Context& context) const {
  Stopwatch total;
  OptimizeResult result;
  Positions initial = InitialPositions(problem);  // validates the constraints
  // The one renumbering (level_cascade.h): the problem goes in here, the positions out at the end.
  LevelCascade cascade(*problem.mesh, context);
  initial = cascade.ToLevel(initial, context);
  const Constraints constraints = cascade.ToLevel(problem.constraints);

  // P and C of every solved level (Algorithm 2, first loop). With overlap_setup, a background
  // task sets the levels up from fine to coarse while the caller's thread sets up and solves the
  // coarse levels, from the coarsest down: the finest level's setup (sequential ordering and
  // factorization, about half of a run: docs/results.md) then runs from the start beside
  // everything else. It needs no hierarchy, so it starts before the hierarchy is built; the
  // coarse levels join once the hierarchy is there. Each level is set up by whichever thread
  // reaches it first (both use the factory, which is thread-safe). Level 0's setup is kept aside
  // until the caller waits for it: the cascade's levels exist only once the hierarchy is built.
  const bool overlap = options_.overlap_setup && context.arena->max_concurrency() >= 2;
  std::vector<double> precompute_seconds, constrain_seconds;
  LevelSetupResult finest_setup;
  const auto store = [&](int l, LevelSetupResult&& setup) {
    precompute_seconds[l] = setup.precompute_seconds;
    constrain_seconds[l] = setup.constrain_seconds;
    cascade.set_solver(l, std::move(setup.solver), setup.seconds);
  };
  LevelSetupPipeline setup(
      {0},
      [&](int l) {
        LevelSetupResult made =
            SetUpLevel(l, options_, cascade, problem, constraints, factory, context);
        if (l == 0) {
          finest_setup = std::move(made);
        } else {
          store(l, std::move(made));
        }
      },
      overlap, context, /*more_levels=*/true);

  // H: the hierarchy (isolated: the caller's thread must not pick up the background setup
  // while it waits for the hierarchy's parallel loops).
  Stopwatch clock;
  if (options_.hierarchical) {
    context.ReportPhase("building the hierarchy");
    // (The cascade renumbers the levels in parallel too.)
    setup.Isolated(context, [&] {
      cascade.SetHierarchy(factory.MakeHierarchy()->Build(*problem.mesh, context),
                           factory.MakeUpsampler());
    });
  } else {
    cascade.SetSingleLevel();
  }
  result.timings.hierarchy = clock.Seconds();
  const int coarsest = cascade.num_levels() - 1;
  precompute_seconds.assign(cascade.num_levels(), 0.0);
  constrain_seconds.assign(cascade.num_levels(), 0.0);

  // Waiting for a level's setup belongs to P and C, not to S.
  double waiting_seconds = 0.0;
  bool finest_stored = false;
  const std::function<void(int)> wait_for = [&](int l) {
    Stopwatch wait_clock;
    setup.WaitFor(l);
    if (l == 0 && !finest_stored) {
      store(0, std::move(finest_setup));
      finest_stored = true;
    }
    waiting_seconds += wait_clock.Seconds();
  };
  OneShotPass pass(options_, cascade, setup, wait_for, std::move(initial), context);
  const std::vector<int>& solved_levels = pass.solved_levels();
  setup.AddLevels(std::vector<int>(solved_levels.rbegin() + 1, solved_levels.rend()));

  // S: solve from the coarsest level down (Algorithm 2, second loop).
  Stopwatch solve_clock;
  wait_for(coarsest);
  cascade.TakeRotationSite(coarsest);
  std::vector<std::string> level_notes;
  LevelState& state = cascade.Run(coarsest, pass, context, result, level_notes);
  for (int l : solved_levels) wait_for(l);
  for (int l : solved_levels) {
    result.timings.precompute += precompute_seconds[l];
    result.timings.constrain += constrain_seconds[l];
  }
  result.timings.solve = solve_clock.Seconds() - waiting_seconds;

  const LevelSolver& finest = cascade.solver(0);
  result.measures = finest.AuxiliaryMeasures(state, context);
  result.constraints = finest.constraint_report();
  cascade.ToInput(state.positions, result.positions, context);
  result.notes = DescribeConstraintHandling(result.constraints);
  result.notes.insert(result.notes.end(), level_notes.begin(), level_notes.end());
  result.timings.total = total.Seconds();
  return result;
}

}  // namespace harap
