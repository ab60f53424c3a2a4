// SPDX-License-Identifier: MIT
// Mesh independence of the multigrid solver (docs/solvers.md, "multigrid"): iterations to a
// relative residual of 1e-8 on the finest global-step system of armadillo-bend (armadillo-43k
// refined once: 173K vertices) and of its Loop refinements (692K, 2.77M; the scale scenarios of
// experiments/scenarios/scale/), from a zero start, with smoothed and piecewise constant
// prolongation; beside it CHOLMOD's factorization and solve of the same system. Each benchmark
// runs once (setup and solve times are counters, `setup_s` and `solve_s`). Named bend-173k,
// bend-692k, bend-2.77m so that the armadillo filters of arap_benchmark.cpp leave them out.
//
//   ./build/harap_benchmarks --benchmark_filter=Multigrid
#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "api/builtins.h"
#include "framework/constrained_system.h"
#include "io/scenario.h"
#include "solvers/linear/multigrid_solver.h"
#include "solvers/optimizers/vertex_ordering.h"

namespace {

using namespace harap;

/// The first global step's system of a scenario: A_ff and B_f − A_fc U_c with the rotations
/// fitted to the rest pose with its handles moved, in the optimizers' locality ordering.
struct GlobalStepSystem {
  SparseMatrix a;
  Eigen::MatrixXd b;
  Index vertices = 0;
};

GlobalStepSystem BuildSystem(const std::filesystem::path& file) {
  Scenario scenario = LoadScenario(file);
  const MeshOrdering ordering = LocalityOrdering(scenario.mesh);
  scenario.mesh = ordering.mesh;
  Constraints constraints = scenario.MergedConstraints();
  for (Index& v : constraints.indices) v = ordering.new_vertex[v];
  const Registries registries = MakeBuiltinRegistries();
  const Context context;
  auto energy = registries.energies.Create("spokes_and_rims", ConfigNode());
  energy->Precompute(scenario.mesh, context);
  ConstrainedSystem system(energy->system_matrix(), constraints.indices);
  Positions u = scenario.mesh.vertices;
  for (size_t k = 0; k < constraints.indices.size(); ++k) {
    u.row(constraints.indices[k]) = constraints.targets.row(k);
  }
  system.SetFixedPositions(u);
  Rotations rotations(energy->num_rotations(), Rotation::Identity());
  energy->FitRotations(u, rotations, context);
  Positions rhs(u.rows(), 3);
  energy->AssembleRhs(rotations, rhs, context);
  GlobalStepSystem result;
  system.ReducedRhs(rhs, result.b);
  result.a = system.reduced_matrix();
  result.vertices = scenario.mesh.num_vertices();
  return result;
}

/// One system at a time (the 2.77M one takes a few GB).
const GlobalStepSystem& System(const std::filesystem::path& file) {
  static std::filesystem::path loaded;
  static GlobalStepSystem system;
  if (loaded != file) {
    system = GlobalStepSystem();
    system = BuildSystem(file);
    loaded = file;
  }
  return system;
}

void Solve(benchmark::State& state, std::filesystem::path file, std::string solver_name,
           std::string options) {
  const GlobalStepSystem& system = System(file);
  const Registries registries = MakeBuiltinRegistries();
  const Context context;
  for (auto _ : state) {
    auto solver = registries.linear_solvers.Create(
        solver_name, ConfigNode::Parse(options, "multigrid benchmark"));
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(system.a.rows(), 3);
    solver->Factorize(system.a, context);
    const SolveSummary summary = solver->Solve(system.b, x, context);
    state.counters["setup_s"] = solver->factorize_seconds();
    state.counters["solve_s"] = summary.seconds;
    state.counters["iterations"] = summary.iterations;
    state.counters["relative_residual"] = summary.relative_residual;
    if (const auto* multigrid = dynamic_cast<const MultigridSolver*>(solver.get())) {
      state.counters["levels"] = static_cast<double>(multigrid->level_unknowns().size());
      state.counters["operator_complexity"] = multigrid->operator_complexity();
    }
  }
  state.counters["vertices"] = static_cast<double>(system.vertices);
  state.counters["unknowns"] = static_cast<double>(system.a.rows());
}

[[maybe_unused]] const bool registered = [] {
  const std::filesystem::path shared(HARAP_SHARED_DIR);
  const std::filesystem::path scale =
      std::filesystem::path(HARAP_SOURCE_DIR) / "experiments/scenarios/scale";
  if (!std::filesystem::exists(shared / "scenarios/armadillo-bend.toml")) return false;
  const std::map<std::string, std::filesystem::path> scenes = {
      {"bend-173k", shared / "scenarios/armadillo-bend.toml"},
      {"bend-692k", scale / "armadillo-bend-692k.toml"},
      {"bend-2.77m", scale / "armadillo-bend-2.77m.toml"},
  };
  const std::map<std::string, std::string> solvers = {
      {"multigrid_smoothed", "prolongation = \"smoothed\"\ntolerance = 1e-8\nmax_iterations = 500"},
      {"multigrid_constant", "prolongation = \"constant\"\ntolerance = 1e-8\nmax_iterations = 500"},
      {"cholmod", ""},
  };
  for (const auto& [scene, file] : scenes) {
    for (const auto& [name, options] : solvers) {
      const std::string solver = name == "cholmod" ? "cholmod" : "multigrid";
      benchmark::RegisterBenchmark(("Multigrid/" + scene + "/" + name).c_str(), Solve, file, solver,
                                   options)
          ->Iterations(1)
          ->Unit(benchmark::kSecond)
          ->UseRealTime();
    }
  }
  return true;
}();

}  // namespace
