// SPDX-License-Identifier: MIT
#include "solvers/optimizers/hierarchical_optimizer.h"

#include <fmt/format.h>

#include <algorithm>
#include <string>
#include <vector>

#include "framework/error.h"
#include "solvers/optimizers/classic_optimizer.h"
#include "solvers/optimizers/coarse_constraints.h"
#include "solvers/optimizers/level_setup_pipeline.h"

namespace harap {


HierarchicalOptimizer::Options HierarchicalOptimizer::Options::FromConfig(const ConfigNode& node) {
  Options options;
  const std::string inner =
      node.GetChoice("inner", "local_global", {"local_global", "admm_pd", "wrapd"},
                     "optimizer on each level: local_global (the paper's), admm_pd or wrapd "
                     "(energy `elements`; tolerance and max_iterations then take their meaning)");
  if (inner == "local_global") {
    options.iterations = ReadLocalGlobalOptions(node);
  } else {
    options.inner = inner == "admm_pd" ? Inner::kAdmmPd : Inner::kWrapd;
    options.admm = ReadAdmmOptions(node, options.inner == Inner::kAdmmPd
                                             ? AdmmVariant::kProjectiveDynamics
                                             : AdmmVariant::kRotationAware);
    options.iterations.tolerance = options.admm.tolerance;
    options.iterations.max_iterations = options.admm.max_iterations;
  }
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
  options.iterations.freeze_targets_after = node.Get(
      "freeze_targets_after", options.iterations.freeze_targets_after,
      "with update_constraints: keep a level's coarse targets fixed after this many iterations "
      "raised its energy (0: never; moving targets can make the energy cycle)",
      Range::AtLeast(0));
  node.RejectUnknownKeys();
  return options;
}

std::unique_ptr<Optimizer> HierarchicalOptimizer::Create(const ConfigNode& node) {
  return std::make_unique<HierarchicalOptimizer>(Options::FromConfig(node));
}

OptimizeResult HierarchicalOptimizer::Optimize(const DeformationProblem& problem,
                                               const ComponentFactory& factory,
                                               const Context& context) const {
  Stopwatch total;
  OptimizeResult result;
  const Mesh& mesh = *problem.mesh;
  const Positions initial = InitialPositions(problem);  // validates the constraints

  // H: the hierarchy.
  Stopwatch clock;
  context.ReportPhase("building the hierarchy");
  const MeshHierarchy hierarchy = factory.MakeHierarchy()->Build(mesh, context);
  const auto upsampler = factory.MakeUpsampler();
  result.timings.hierarchy = clock.Seconds();
  const int coarsest = hierarchy.num_levels() - 1;

  // Which levels are solved.
  std::vector<bool> solved(hierarchy.num_levels(), false);
  solved[0] = solved[coarsest] = true;
  if (!options_.coarsest_only && !options_.coarse_approximation) {
    for (int l = coarsest; l >= 0; l -= options_.level_step) solved[l] = true;
  }

  // P and C: precompute and factor every solved level (Algorithm 2, first loop).
  std::vector<LevelConstraints> constraints(hierarchy.num_levels());
  std::vector<LevelConstraints> internal_constraints(hierarchy.num_levels());  // solver numbering
  std::vector<std::unique_ptr<LocalGlobalSolver>> solvers(hierarchy.num_levels());
  // With an ADMM inner optimizer these take the solvers' place.
  const bool admm = options_.inner != Inner::kLocalGlobal;
  std::vector<std::unique_ptr<AdmmLevelSolver>> admm_solvers(hierarchy.num_levels());
  std::vector<double> level_seconds(hierarchy.num_levels(), 0.0);
  std::vector<double> precompute_seconds(hierarchy.num_levels(), 0.0);
  std::vector<double> constrain_seconds(hierarchy.num_levels(), 0.0);
  // Levels may be set up from two threads at once (see the pipeline below).
  const SerializedFactory serialized_factory(factory);
  const auto setup_level = [&](int l) {
    Stopwatch level_clock;
    const Mesh& level_mesh = hierarchy.levels[l].mesh;
    if (l == 0) {
      constraints[0].vertices = problem.constraints.indices;
    } else {
      constraints[l] = MapConstraints(hierarchy, l, problem.constraints);
    }
    if (admm) {
      // Only the input level needs the factory's energy (final energy and measures); coarse
      // levels drop their inverted elements (Section 7: "filtering all inverted elements").
      admm_solvers[l] = std::make_unique<AdmmLevelSolver>(
          level_mesh, constraints[l].vertices, serialized_factory, l, context,
          /*with_energy=*/l == 0, /*drop_misoriented=*/l > 0, options_.admm.beta);
    } else {
      // Coarse levels' energies are normalized like the input mesh's (Energy::SetInputMesh).
      solvers[l] = std::make_unique<LocalGlobalSolver>(level_mesh, constraints[l].vertices,
                                                       serialized_factory, l, context,
                                                       l > 0 ? &mesh : nullptr);
    }
    if (l > 0 && (admm || solvers[l]->energy().rotation_site() == RotationSite::kElement)) {
      auto& incident = constraints[l].incident_elements;
      incident.assign(constraints[l].vertices.size(), {});
      std::vector<Index> slot(level_mesh.num_vertices(), kNoVertex);
      for (size_t k = 0; k < constraints[l].vertices.size(); ++k) {
        slot[constraints[l].vertices[k]] = static_cast<Index>(k);
      }
      for (Index e = 0; e < level_mesh.num_elements(); ++e) {
        for (int a = 0; a < level_mesh.simplex_size(); ++a) {
          if (slot[level_mesh.elements(e, a)] != kNoVertex) {
            incident[slot[level_mesh.elements(e, a)]].push_back(e);
          }
        }
      }
    }
    if (l > 0 && !admm) {
      const MeshOrdering& ordering = solvers[l]->ordering();
      LevelConstraints& internal = internal_constraints[l];
      internal = constraints[l];
      for (Index& v : internal.vertices) v = ordering.new_vertex[v];
      for (auto& elements : internal.incident_elements) {
        for (Index& e : elements) e = ordering.new_element[e];
      }
    }
    precompute_seconds[l] = admm ? admm_solvers[l]->precompute_seconds()
                                 : solvers[l]->precompute_seconds();
    constrain_seconds[l] = admm ? admm_solvers[l]->constrain_seconds()
                                : solvers[l]->constrain_seconds();
    level_seconds[l] = level_clock.Seconds();
  };
  // With overlap_setup, a background task sets the levels up from fine to coarse while the
  // caller's thread sets up and solves the coarse levels, from the coarsest down: the finest
  // level's setup (its ordering and factorization alone take about half of the run, and are
  // sequential) then runs from the start beside everything else, and the run takes about
  // max(finest setup, coarse setups + solves) + finest solve instead of the sum of all setups +
  // finest solve (armadillo-bend, 1e-6: 0.9 s instead of 1.2 s, docs/results.md). Each level is
  // set up by whichever thread reaches it first.
  std::vector<int> solved_levels;
  for (int l = coarsest; l >= 0; --l) {
    if (solved[l]) solved_levels.push_back(l);
  }
  const std::vector<int> fine_to_coarse(solved_levels.rbegin(), solved_levels.rend());
  LevelSetupPipeline setup(fine_to_coarse, setup_level,
                           options_.overlap_setup && context.arena->max_concurrency() >= 2,
                           context);

  // S: solve from the coarsest level down.
  Stopwatch solve_clock;
  const double diagonal = BoundingBoxDiagonal(mesh);
  // Time spent waiting for a level's setup belongs to P and C, not to S.
  double waiting_seconds = 0.0;
  const auto wait_for = [&](int l) {
    Stopwatch wait_clock;
    setup.WaitFor(l);
    waiting_seconds += wait_clock.Seconds();
  };
  wait_for(coarsest);
  const RotationSite site =
      admm ? RotationSite::kElement : solvers[coarsest]->energy().rotation_site();
  std::vector<std::string> admm_notes;
  LevelState state;
  bool start_with_global_step = false;
  std::vector<std::string> frozen_target_notes;
  for (int l = coarsest; l >= 0; --l) {
    const HierarchyLevel& level = hierarchy.levels[l];
    if (l < coarsest) {
      LevelState coarse_state = std::move(state);
      state = LevelState();
      upsampler->Upsample(level, hierarchy.levels[l + 1], site, coarse_state, state, context);
      start_with_global_step = upsampler->output() == UpsampleOutput::kRotations;
    } else {
      state.positions = l == 0 ? initial : level.mesh.vertices;
    }
    if (!solved[l]) continue;

    wait_for(l);
    Stopwatch level_clock;
    if (admm) {
      AdmmLevelSolver& admm_solver = *admm_solvers[l];
      AdmmOptions admm_options = options_.admm;
      if (l > 0 && options_.coarse_tolerance >= 0.0) {
        admm_options.tolerance = options_.coarse_tolerance;
      }
      if (l == 0 && options_.coarse_approximation && coarsest > 0) admm_options.max_iterations = 1;
      if (l == 0) {
        for (size_t k = 0; k < problem.constraints.indices.size(); ++k) {
          state.positions.row(problem.constraints.indices[k]) =
              problem.constraints.targets.row(k);
        }
      } else {
        const bool have_rotations =
            static_cast<Index>(state.rotations.size()) == level.mesh.num_elements();
        PlaceConstrainedVertices(constraints[l], site,
                                 have_rotations ? &state.rotations : nullptr, state.positions);
      }
      const auto run = setup.Isolated(
          context, [&] { return admm_solver.Run(state.positions, admm_options, context); });
      // The up-sampler's input: rotations of the elements' polar decompositions.
      if (l > 0) state.rotations = admm_solver.ElementRotations(state.positions, context);
      level_seconds[l] += level_clock.Seconds();
      if (admm_solver.dropped_elements() > 0) {
        admm_notes.push_back(fmt::format("level {}: {} inverted elements dropped", l,
                                         admm_solver.dropped_elements()));
      }
      result.total_iterations += run.iterations;
      LevelResult level_result{l, level.mesh.num_vertices(), level.mesh.num_elements(),
                               run.iterations, run.energy, level_seconds[l], run.converged,
                               admm_solver.system().num_free(), run.linear_solves};
      level_result.inverted_elements = run.inverted_elements;
      result.levels.push_back(level_result);
      if (l == 0) {
        result.iterations = run.iterations;
        result.converged = run.converged;
      }
      if (run.stopped_by_callback) {
        result.stopped_by_callback = true;
        for (int f = l - 1; f >= 0; --f) {
          LevelState coarse_state = std::move(state);
          state = LevelState();
          upsampler->Upsample(hierarchy.levels[f], hierarchy.levels[f + 1], site, coarse_state,
                              state, context);
        }
        break;
      }
      if (l > 0) admm_solvers[l].reset();
      continue;
    }
    LocalGlobalSolver& solver = *solvers[l];
    LocalGlobalOptions options = options_.iterations;
    if (l > 0 && options_.coarse_tolerance >= 0.0) options.tolerance = options_.coarse_tolerance;
    if (l == 0 && options_.coarse_approximation && coarsest > 0) options.max_iterations = 1;
    LocalGlobalSolver::FixedPositionUpdate update;
    if (l == 0) {
      for (size_t k = 0; k < problem.constraints.indices.size(); ++k) {
        state.positions.row(problem.constraints.indices[k]) = problem.constraints.targets.row(k);
      }
    } else {
      const bool have_rotations =
          static_cast<Index>(state.rotations.size()) == solver.energy().num_rotations();
      PlaceConstrainedVertices(constraints[l], site, have_rotations ? &state.rotations : nullptr,
                               state.positions);
      if (options_.update_constraints) {
        update = [&, l](const Rotations& rotations, Positions& positions) {
          PlaceConstrainedVertices(internal_constraints[l], site, &rotations, positions);
        };
      }
    }
    const auto run = setup.Isolated(context, [&] {
      return solver.Run(state, start_with_global_step, options, diagonal, context, update);
    });
    level_seconds[l] += level_clock.Seconds();
    if (run.targets_frozen_at > 0) {
      frozen_target_notes.push_back(fmt::format(
          "level {}: coarse constraint targets stopped following the rotations after iteration "
          "{} (the energy kept rising)",
          l, run.targets_frozen_at));
    }
    result.total_iterations += run.iterations;
    result.levels.push_back(LevelResult{l, level.mesh.num_vertices(), level.mesh.num_elements(),
                                        run.iterations, run.energy, level_seconds[l],
                                        run.converged, solver.system().num_free(),
                                        run.linear_solves});
    RecordAcceleration(options, run, result.levels.back());
    if (l == 0) {
      result.energy = run.energy;
      result.iterations = run.iterations;
      result.converged = run.converged;
    }
    if (run.stopped_by_callback) {
      result.stopped_by_callback = true;
      if (l > 0) {
        // Finish on the finest level without iterating: up-sample what we have.
        for (int f = l - 1; f >= 0; --f) {
          LevelState coarse_state = std::move(state);
          state = LevelState();
          upsampler->Upsample(hierarchy.levels[f], hierarchy.levels[f + 1], site, coarse_state,
                              state, context);
        }
        wait_for(0);
        result.energy = solvers[0]->FitRotations(state, context);
      }
      break;
    }
    if (l > 0) solvers[l].reset();  // the level's factor is no longer needed
  }
  for (int l : solved_levels) wait_for(l);
  for (int l : solved_levels) {
    result.timings.precompute += precompute_seconds[l];
    result.timings.constrain += constrain_seconds[l];
  }
  result.timings.solve = solve_clock.Seconds() - waiting_seconds;
  std::reverse(result.levels.begin(), result.levels.end());

  if (admm) {
    result.energy = admm_solvers[0]->FinalEnergy(state.positions, result.measures, context);
    if (!result.levels.empty() && result.levels.front().level == 0) {
      result.levels.front().energy = result.energy;
    }
    result.constraints = admm_solvers[0]->system().report();
  } else {
    result.measures = solvers[0]->AuxiliaryMeasures(state, context);
    result.constraints = solvers[0]->system().report();
  }
  result.positions = std::move(state.positions);
  result.notes = DescribeConstraintHandling(result.constraints);
  result.notes.insert(result.notes.end(), admm_notes.begin(), admm_notes.end());
  result.notes.insert(result.notes.end(), frozen_target_notes.begin(), frozen_target_notes.end());
  result.timings.total = total.Seconds();
  return result;
}

}  // namespace harap
