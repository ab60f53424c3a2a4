// SPDX-License-Identifier: MIT
#include "solvers/optimizers/classic_optimizer.h"

#include <fmt/format.h>

namespace harap {

ClassicOptimizer::Options ClassicOptimizer::Options::FromConfig(const ConfigNode& node) {
  Options options;
  options.iterations = ReadLocalGlobalOptions(node);
  node.RejectUnknownKeys();
  return options;
}

std::unique_ptr<Optimizer> ClassicOptimizer::Create(const ConfigNode& node) {
  return std::make_unique<ClassicOptimizer>(Options::FromConfig(node));
}

std::vector<std::string> DescribeConstraintHandling(const ConstraintReport& report) {
  std::vector<std::string> notes;
  if (report.isolated_vertices > 0) {
    notes.push_back(fmt::format("{} vertices are used by no (non-degenerate) element; they keep "
                                "their initial positions",
                                report.isolated_vertices));
  }
  if (report.free_components > 0) {
    notes.push_back(fmt::format("{} connected components ({} vertices) have no constrained "
                                "vertex; one vertex of each is pinned at its initial position "
                                "(the energy is invariant to translating them)",
                                report.free_components, report.vertices_in_free_components));
  }
  return notes;
}

OptimizeResult ClassicOptimizer::Optimize(const DeformationProblem& problem,
                                          const ComponentFactory& factory,
                                          const Context& context) const {
  Stopwatch total;
  OptimizeResult result;
  const Mesh& mesh = *problem.mesh;
  LevelState state;
  state.positions = InitialPositions(problem);

  LocalGlobalSolver level(mesh, problem.constraints.indices, factory, 0, context);
  result.timings.precompute = level.precompute_seconds();
  result.timings.constrain = level.constrain_seconds();

  Stopwatch solve_clock;
  const auto run = level.Run(state, /*start_with_global_step=*/false, options_.iterations,
                             BoundingBoxDiagonal(mesh), context);
  result.timings.solve = solve_clock.Seconds();

  result.measures = level.AuxiliaryMeasures(state, context);
  result.positions = std::move(state.positions);
  result.energy = run.energy;
  result.iterations = run.iterations;
  result.total_iterations = run.iterations;
  result.converged = run.converged;
  result.stopped_by_callback = run.stopped_by_callback;
  result.constraints = level.system().report();
  result.notes = DescribeConstraintHandling(result.constraints);
  result.timings.total = total.Seconds();
  result.levels.push_back(LevelResult{0, mesh.num_vertices(), mesh.num_elements(),
                                      run.iterations, run.energy, result.timings.total,
                                      run.converged, level.system().num_free(),
                                      run.linear_solves});
  RecordAcceleration(options_.iterations, run, result.levels.back());
  return result;
}

}  // namespace harap
