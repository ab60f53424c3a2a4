// SPDX-License-Identifier: MIT
#include "solvers/optimizers/hierarchical_optimizer.h"

#include <fmt/format.h>

#include <algorithm>

#include "framework/error.h"
#include "solvers/optimizers/classic_optimizer.h"
#include "solvers/optimizers/coarse_constraints.h"

namespace harap {


HierarchicalOptimizer::Options HierarchicalOptimizer::Options::FromConfig(const ConfigNode& node) {
  Options options;
  options.iterations = ReadLocalGlobalOptions(node);
  options.coarse_tolerance =
      node.Get("coarse_tolerance", options.coarse_tolerance,
               "convergence tolerance on the coarse levels (negative: same as tolerance)");
  options.level_step = node.Get("level_step", options.level_step,
                                "solve every k-th level (1: all; the finest and coarsest always)");
  options.coarsest_only = node.Get("coarsest_only", options.coarsest_only,
                                   "solve only the coarsest and the finest level (Fig. 14)");
  options.coarse_approximation =
      node.Get("coarse_approximation", options.coarse_approximation,
               "up-sample the coarsest solution straight to the finest level and solve once "
               "(Fig. 15)");
  options.update_constraints =
      node.Get("update_constraints", options.update_constraints,
               "re-evaluate coarse constraint targets with the current rotations (Fig. 16)");
  node.RejectUnknownKeys();
  if (options.level_step < 1) {
    throw ConfigError(fmt::format("{}: level_step must be >= 1, got {}", node.Where("level_step"),
                                  options.level_step));
  }
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
  std::vector<double> level_seconds(hierarchy.num_levels(), 0.0);
  for (int l = coarsest; l >= 0; --l) {
    if (!solved[l]) continue;
    Stopwatch level_clock;
    const Mesh& level_mesh = hierarchy.levels[l].mesh;
    if (l == 0) {
      constraints[0].vertices = problem.constraints.indices;
    } else {
      constraints[l] = MapConstraints(hierarchy, l, problem.constraints);
    }
    // Coarse levels' energies are normalized like the input mesh's (Energy::SetInputMesh).
    solvers[l] = std::make_unique<LocalGlobalSolver>(level_mesh, constraints[l].vertices, factory,
                                                     l, context, l > 0 ? &mesh : nullptr);
    if (l > 0 && solvers[l]->energy().rotation_site() == RotationSite::kElement) {
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
    if (l > 0) {
      const MeshOrdering& ordering = solvers[l]->ordering();
      LevelConstraints& internal = internal_constraints[l];
      internal = constraints[l];
      for (Index& v : internal.vertices) v = ordering.new_vertex[v];
      for (auto& elements : internal.incident_elements) {
        for (Index& e : elements) e = ordering.new_element[e];
      }
    }
    result.timings.precompute += solvers[l]->precompute_seconds();
    result.timings.constrain += solvers[l]->constrain_seconds();
    level_seconds[l] = level_clock.Seconds();
  }

  // S: solve from the coarsest level down.
  Stopwatch solve_clock;
  const double diagonal = BoundingBoxDiagonal(mesh);
  LevelState state;
  bool start_with_global_step = false;
  std::vector<std::string> target_notes;
  for (int l = coarsest; l >= 0; --l) {
    const HierarchyLevel& level = hierarchy.levels[l];
    if (l < coarsest) {
      LevelState coarse_state = std::move(state);
      state = LevelState();
      const RotationSite site = solvers[0]->energy().rotation_site();
      upsampler->Upsample(level, hierarchy.levels[l + 1], site, coarse_state, state, context);
      start_with_global_step = upsampler->output() == UpsampleOutput::kRotations;
    } else {
      state.positions = l == 0 ? initial : level.mesh.vertices;
    }
    if (!solved[l]) continue;

    Stopwatch level_clock;
    LocalGlobalSolver& solver = *solvers[l];
    const RotationSite site = solver.energy().rotation_site();
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
        update = [&, l, site](const Rotations& rotations, Positions& positions) {
          PlaceConstrainedVertices(internal_constraints[l], site, &rotations, positions);
        };
      }
    }
    const auto run = solver.Run(state, start_with_global_step, options, diagonal, context, update);
    if (run.update_stopped_at > 0) {
      target_notes.push_back(fmt::format(
          "level {}: coarse constraint targets stopped following the rotations after iteration "
          "{}, which increased the energy",
          l, run.update_stopped_at));
    }
    level_seconds[l] += level_clock.Seconds();
    result.total_iterations += run.iterations;
    result.levels.push_back(LevelResult{l, level.mesh.num_vertices(), level.mesh.num_elements(),
                                        run.iterations, run.energy, level_seconds[l],
                                        run.converged});
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
        result.energy = solvers[0]->energy().FitRotations(state.positions, state.rotations,
                                                          context);
      }
      break;
    }
    if (l > 0) solvers[l].reset();  // the level's factor is no longer needed
  }
  result.timings.solve = solve_clock.Seconds();
  std::reverse(result.levels.begin(), result.levels.end());

  result.positions = std::move(state.positions);
  result.constraints = solvers[0]->system().report();
  result.notes = DescribeConstraintHandling(result.constraints);
  result.notes.insert(result.notes.end(), target_notes.begin(), target_notes.end());
  result.timings.total = total.Seconds();
  return result;
}

}  // namespace harap
