// SPDX-License-Identifier: MIT
#include "solvers/optimizers/hierarchical_optimizer.h"

#include <fmt/format.h>

#include <algorithm>
#include <string>
#include <vector>

#include "framework/error.h"
#include "solvers/optimizers/coarse_constraints.h"
#include "solvers/optimizers/level_setup_pipeline.h"
#include "solvers/optimizers/local_global_solver.h"

namespace harap {

HierarchicalOptimizer::Options HierarchicalOptimizer::Options::FromConfig(
    const ConfigNode& node, const Registry<LevelSolver>& level_solvers) {
  Options options;
  options.inner = node.GetChoice("inner", options.inner, level_solvers.Names(),
                                 "level solver on each level (`harap list inner`): local_global "
                                 "(the paper's), admm_pd or wrapd (energy `elements`; tolerance "
                                 "and max_iterations then take their meaning)");
  options.level_solver = level_solvers.Create(options.inner, node);
  options.coarse_tolerance =
      node.Get("coarse_tolerance", options.coarse_tolerance,
               "convergence tolerance on the coarse levels (negative: same as tolerance)");
  options.level_step = node.Get("level_step", options.level_step,
                                "solve every k-th level (1: all; the finest and coarsest always)",
                                Range::AtLeast(1));
  options.coarsest_only = node.Get("coarsest_only", options.coarsest_only,
                                   "solve only the coarsest and the finest level (Fig. 14)");
  options.coarse_approximation =
      node.Get("coarse_approximation", options.coarse_approximation,
               "up-sample the coarsest solution straight to the finest level and solve once "
               "(Fig. 15)");
  options.update_constraints =
      node.Get("update_constraints", options.update_constraints,
               "re-evaluate coarse constraint targets with the current rotations (Fig. 16)");
  options.overlap_setup =
      node.Get("overlap_setup", options.overlap_setup,
               "set up (precompute, factor) finer levels on another thread while coarser levels "
               "are solved; phase times then overlap");
  options.freeze_targets_after = node.Get(
      "freeze_targets_after", options.freeze_targets_after,
      "with update_constraints: keep a level's coarse targets fixed after this many iterations "
      "raised its energy (0: never; moving targets can make the energy cycle)",
      Range::AtLeast(0));
  node.RejectUnknownKeys();
  return options;
}

HierarchicalOptimizer::Options HierarchicalOptimizer::Options::OneLevel(
    const ConfigNode& node, const Registry<LevelSolver>& level_solvers, std::string_view inner) {
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
  if (level == 0 && coarse_approximation && num_levels > 1) request.max_iterations = 1;
  request.targets_follow_rotations = update_constraints;
  request.freeze_targets_after = freeze_targets_after;
  return request;
}

Registry<Optimizer>::Factory HierarchicalOptimizer::Factory(
    std::shared_ptr<const Registry<LevelSolver>> level_solvers) {
  return [level_solvers](const ConfigNode& node) -> std::unique_ptr<Optimizer> {
    return std::make_unique<HierarchicalOptimizer>(Options::FromConfig(node, *level_solvers));
  };
}

Registry<Optimizer>::Factory HierarchicalOptimizer::OneLevelFactory(
    std::shared_ptr<const Registry<LevelSolver>> level_solvers, std::string inner) {
  return [level_solvers, inner](const ConfigNode& node) -> std::unique_ptr<Optimizer> {
    return std::make_unique<HierarchicalOptimizer>(Options::OneLevel(node, *level_solvers, inner));
  };
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

// What one Optimize() call shares between its phases: the levels (the hierarchy's, or the input
// mesh alone), their solvers and their times.
struct Cascade {
  Cascade(const HierarchicalOptimizer::Options& options, const DeformationProblem& problem,
          const Context& context)
      : options(options), problem(problem), context(context) {}

  // Level 0 is the input mesh itself (the hierarchy's levels[0] equals it), so that its setup
  // can start before the hierarchy is built.
  const Mesh& LevelMesh(int l) const {
    return options.hierarchical && l > 0 ? hierarchy.levels[l].mesh : *problem.mesh;
  }
  int num_levels() const { return options.hierarchical ? hierarchy.num_levels() : 1; }

  // What setting up one level made.
  struct Setup {
    std::unique_ptr<LevelSolver> solver;
    double precompute_seconds = 0.0, constrain_seconds = 0.0, seconds = 0.0;
  };

  // P and C of level l (from whichever thread gets there first; see LevelSetupPipeline).
  Setup MakeSetup(int l, const ComponentFactory& factory) const {
    Stopwatch clock;
    const Mesh& mesh = *problem.mesh;
    const LevelConstraints constraints =
        l == 0 ? LevelConstraints::Exact(problem.constraints, mesh.planar)
               : MapConstraints(hierarchy, l, problem.constraints);
    Setup setup;
    setup.solver = options.level_solver->CreateAnother();
    // Coarse levels' energies are normalized like the input mesh's (Energy::SetInputMesh).
    setup.solver->Precompute(LevelSetup{&LevelMesh(l), l > 0 ? &mesh : nullptr, l, false}, factory,
                             context);
    setup.solver->Constrain(constraints, factory, context);
    setup.precompute_seconds = setup.solver->precompute_seconds();
    setup.constrain_seconds = setup.solver->constrain_seconds();
    setup.seconds = clock.Seconds();
    return setup;
  }

  // Stores level l's setup (the caller's thread, or level > 0 after the vectors are sized).
  void Store(int l, Setup&& setup) {
    precompute_seconds[l] = setup.precompute_seconds;
    constrain_seconds[l] = setup.constrain_seconds;
    solvers[l] = std::move(setup.solver);
    level_seconds[l] = setup.seconds;
  }

  // The state of level l from the state of level l + 1 (Section 5.1).
  void Upsample(int l, LevelState& state) const {
    LevelState coarse_state = std::move(state);
    state = LevelState();
    upsampler->Upsample(hierarchy.levels[l], hierarchy.levels[l + 1], site, coarse_state, state,
                        context);
  }

  const HierarchicalOptimizer::Options& options;
  const DeformationProblem& problem;
  const Context& context;
  MeshHierarchy hierarchy;
  std::unique_ptr<Upsampler> upsampler;
  RotationSite site = RotationSite::kVertex;
  std::vector<std::unique_ptr<LevelSolver>> solvers;
  std::vector<double> level_seconds, precompute_seconds, constrain_seconds;
};

}  // namespace

OptimizeResult HierarchicalOptimizer::Optimize(const DeformationProblem& problem,
                                               const ComponentFactory& factory,
                                               const Context& context) const {
  Stopwatch total;
  OptimizeResult result;
  const Positions initial = InitialPositions(problem);  // validates the constraints
  Cascade cascade(options_, problem, context);

  // P and C of every solved level (Algorithm 2, first loop). With overlap_setup, a background
  // task sets the levels up from fine to coarse while the caller's thread sets up and solves the
  // coarse levels, from the coarsest down: the finest level's setup (its ordering and
  // factorization alone take about half of the run, and are sequential) then runs from the
  // start beside everything else (armadillo-bend, 1e-6: 0.9 s instead of 1.2 s,
  // docs/results.md). It needs no hierarchy, so it starts before the hierarchy is built
  // (dragon-lift: 0.17 s earlier); the coarse levels join once the hierarchy is there. Each level
  // is set up by whichever thread reaches it first; creating components reads config tables, so
  // the two threads take turns at the factory. Level 0's setup is kept aside until the caller
  // waits for it: the per-level vectors are sized only after the hierarchy is built.
  const SerializedFactory serialized_factory(factory);
  const bool overlap = options_.overlap_setup && context.arena->max_concurrency() >= 2;
  Cascade::Setup finest_setup;
  LevelSetupPipeline setup(
      {0},
      [&](int l) {
        if (l == 0) {
          finest_setup = cascade.MakeSetup(0, serialized_factory);
        } else {
          cascade.Store(l, cascade.MakeSetup(l, serialized_factory));
        }
      },
      overlap, context, /*more_levels=*/true);

  // H: the hierarchy (isolated: the caller's thread must not pick up the background setup
  // while it waits for the hierarchy's parallel loops).
  Stopwatch clock;
  if (options_.hierarchical) {
    context.ReportPhase("building the hierarchy");
    cascade.hierarchy = setup.Isolated(
        context, [&] { return factory.MakeHierarchy()->Build(*problem.mesh, context); });
    cascade.upsampler = factory.MakeUpsampler();
  }
  result.timings.hierarchy = clock.Seconds();
  const int levels = cascade.num_levels();
  const int coarsest = levels - 1;
  cascade.solvers.resize(levels);
  cascade.level_seconds.assign(levels, 0.0);
  cascade.precompute_seconds.assign(levels, 0.0);
  cascade.constrain_seconds.assign(levels, 0.0);
  const std::vector<int> solved_levels = options_.SolvedLevels(levels);
  std::vector<int> coarse_levels(solved_levels.rbegin() + 1, solved_levels.rend());
  setup.AddLevels(coarse_levels);  // fine to coarse, after level 0

  // S: solve from the coarsest level down.
  Stopwatch solve_clock;
  const double diagonal = BoundingBoxDiagonal(*problem.mesh);
  double waiting_seconds = 0.0;  // waiting for a level's setup belongs to P and C, not to S
  bool finest_stored = false;
  const auto wait_for = [&](int l) {
    Stopwatch wait_clock;
    setup.WaitFor(l);
    if (l == 0 && !finest_stored) {
      cascade.Store(0, std::move(finest_setup));
      finest_stored = true;
    }
    waiting_seconds += wait_clock.Seconds();
  };
  wait_for(coarsest);
  cascade.site = cascade.solvers[coarsest]->rotation_site();
  std::vector<std::string> level_notes;
  LevelState state;
  bool from_rotations = false;
  for (int l = coarsest; l >= 0; --l) {
    if (l < coarsest) {
      cascade.Upsample(l, state);
      from_rotations = cascade.upsampler->output() == UpsampleOutput::kRotations;
    } else {
      state.positions = l == 0 ? initial : cascade.LevelMesh(l).vertices;
    }
    if (std::find(solved_levels.begin(), solved_levels.end(), l) == solved_levels.end()) continue;

    wait_for(l);
    Stopwatch level_clock;
    LevelSolver& solver = *cascade.solvers[l];
    const LevelSolveRequest request = options_.Request(l, levels, from_rotations, diagonal);
    const LevelSolveResult run =
        setup.Isolated(context, [&] { return solver.Solve(state, request, context); });
    cascade.level_seconds[l] += level_clock.Seconds();
    level_notes.insert(level_notes.end(), run.notes.begin(), run.notes.end());
    result.total_iterations += run.iterations;
    const Mesh& level_mesh = cascade.LevelMesh(l);
    result.levels.push_back(LevelResult{l, level_mesh.num_vertices(), level_mesh.num_elements(),
                                        run.iterations, run.energy, cascade.level_seconds[l],
                                        run.converged, solver.num_unknowns(), run.linear_solves,
                                        run.measures, run.weights});
    if (l == 0) {
      result.energy = run.energy;
      result.iterations = run.iterations;
      result.converged = run.converged;
    }
    if (run.stopped_by_callback) {
      result.stopped_by_callback = true;
      if (l > 0) {
        // Finish on the finest level without iterating: up-sample what we have.
        for (int f = l - 1; f >= 0; --f) cascade.Upsample(f, state);
        wait_for(0);
        result.energy = cascade.solvers[0]->FitRotations(state, context);
      }
      break;
    }
    if (l > 0) cascade.solvers[l].reset();  // the level's factor is no longer needed
  }
  for (int l : solved_levels) wait_for(l);
  for (int l : solved_levels) {
    result.timings.precompute += cascade.precompute_seconds[l];
    result.timings.constrain += cascade.constrain_seconds[l];
  }
  result.timings.solve = solve_clock.Seconds() - waiting_seconds;
  std::reverse(result.levels.begin(), result.levels.end());

  const LevelSolver& finest = *cascade.solvers[0];
  result.measures = finest.AuxiliaryMeasures(state, context);
  result.constraints = finest.constraint_report();
  result.positions = std::move(state.positions);
  result.notes = DescribeConstraintHandling(result.constraints);
  result.notes.insert(result.notes.end(), level_notes.begin(), level_notes.end());
  result.timings.total = total.Seconds();
  return result;
}

}  // namespace harap
