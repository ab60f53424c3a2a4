// SPDX-License-Identifier: MIT
// Handle edits of an interactive session (docs/session.md) on armadillo-bend's finest level: the
// masked global-step matrix (all vertices; the scenario's handles' rows and columns replaced by
// the identity's, pattern unchanged) is factored, then a ball of 1% of the vertices becomes
// constrained and is released again, each edit one LinearSolver::Refactor():
//
//   HandleEdit_factorize/armadillo-bend   Factorize() of the masked matrix from scratch
//                                          (counters: analysis_ms, numeric_ms, solve_setup_ms,
//                                          refactor_MB: the copies kept for Refactor())
//   HandleEdit_<route>/armadillo-bend     one iteration = add the ball + release it, with
//                                          CholmodSolver option refactor = <route> (full,
//                                          numeric, update, partial, auto); counters per edit:
//                                          add_ms, remove_ms, the route taken (0 full,
//                                          1 numeric, 2 update, 3 partial), the estimates of
//                                          auto's rule (partial_work: the share of the
//                                          factorization's flops partial recomputes), the time
//                                          the parallel solve's plan took after the last edit,
//                                          the relative residual of a solve after each edit and
//                                          the time of a 3-column solve (add_solve3_ms,
//                                          remove_solve3_ms: the factor an update leaves is
//                                          unpacked, with moved columns).
//
//   HandleEditSmall_<route>/armadillo-bend  the same with a ball of 0.01% of the vertices (17)
//   HandleEdit_{factorize,numeric}_native2  with native_threads = 2 (CHOLMOD's BLAS and OpenMP
//                                          on both cores)
//
// Compare with Factorization_auto_amd/armadillo-bend (the reduced matrix) in the same run:
//   ./build/harap_benchmarks --benchmark_filter='HandleEdit|Factorization_auto_amd/armadillo'
// Skipped (not registered) when ../shared is absent; the data is loaded on first use.
#ifdef HARAP_HAVE_CHOLMOD

#include <benchmark/benchmark.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "api/builtins.h"
#include "benchmarks/edit_ball.h"
#include "framework/config.h"
#include "framework/context.h"
#include "io/scenario.h"
#include "solvers/linear/cholmod_solver.h"
#include "solvers/optimizers/vertex_ordering.h"

namespace {

using namespace harap;

// `a` with the rows and columns of `handles` replaced by the identity's, every entry kept.
SparseMatrix Masked(const SparseMatrix& a, const std::vector<char>& handle) {
  SparseMatrix masked = a;
  masked.makeCompressed();
  for (Index j = 0; j < masked.outerSize(); ++j) {
    for (SparseMatrix::InnerIterator it(masked, j); it; ++it) {
      if (handle[it.row()] || handle[it.col()]) {
        it.valueRef() = it.row() == it.col() ? 1.0 : 0.0;
      }
    }
  }
  return masked;
}

struct EditFixture {
  Context context;
  SparseMatrix before;      ///< masked with the scenario's handles
  SparseMatrix after;       ///< and with the ball
  std::vector<Index> ball;  ///< sorted, none of them a scenario handle
  Eigen::MatrixXd rhs;

  /// `fraction`: the ball's share of the vertices.
  explicit EditFixture(double fraction) {
    Scenario scenario = LoadScenario(ArmadilloBendScenario());
    // The optimizers renumber each level for locality; so do the other benchmarks.
    const MeshOrdering ordering = LocalityOrdering(scenario.mesh);
    scenario.mesh = ordering.mesh;
    Registries registries = MakeBuiltinRegistries();
    auto energy = registries.energies.Create("spokes_and_rims", ConfigNode());
    energy->Precompute(scenario.mesh, context);
    const Index n = scenario.mesh.num_vertices();
    std::vector<Index> handles;
    for (Index v : scenario.MergedConstraints().indices) handles.push_back(ordering.new_vertex[v]);
    std::vector<char> handle(n, 0);
    for (Index v : handles) handle[v] = 1;
    before = Masked(energy->system_matrix(), handle);

    ball = EditBall(scenario.mesh, handles, fraction);
    for (Index v : ball) handle[v] = 1;
    after = Masked(energy->system_matrix(), handle);
    rhs = Eigen::MatrixXd::Random(n, 3);
  }
};

// A ball of 1% of the vertices (docs/results.md, "Handle edits"), and one of 0.01% (17 vertices).
EditFixture& Fixture(bool small = false) {
  if (small) {
    static EditFixture fixture(1e-4);
    return fixture;
  }
  static EditFixture fixture(1e-2);
  return fixture;
}

std::unique_ptr<CholmodSolver> MakeSolver(const std::string& refactor, int native_threads = 1) {
  // The defaults (mode auto, AMD, native_threads 1) and the route, as a config would set them.
  ConfigNode node;
  node.Set("refactor", "\"" + refactor + "\"");
  node.Set("native_threads", std::to_string(native_threads));
  auto solver =
      std::make_unique<CholmodSolver>(CholmodSolver::Options::FromConfig(OptionReader(node)));
  // As a session's level (LevelSetup::handle_edits): refactor = "auto" keeps the
  // copies Refactor() reuses only when prepared.
  solver->PrepareForRefactor();
  return solver;
}

// The relative residual of a 3-column solve with the current factor; `seconds`: the solve's
// time (the median of 5, after a warm-up), to compare solves after each route.
double Residual(CholmodSolver& solver, const SparseMatrix& a, EditFixture& f, double& seconds) {
  Eigen::MatrixXd x(f.rhs.rows(), 3);
  solver.Solve(f.rhs, x, f.context);
  std::vector<double> times;
  for (int k = 0; k < 5; ++k) times.push_back(solver.Solve(f.rhs, x, f.context).seconds);
  std::nth_element(times.begin(), times.begin() + 2, times.end());
  seconds = times[2];
  const Eigen::MatrixXd r = f.rhs - a * x;
  double worst = 0.0;
  for (Eigen::Index c = 0; c < 3; ++c) {
    worst = std::max(worst, r.col(c).norm() / f.rhs.col(c).norm());
  }
  return worst;
}

void Factorize(benchmark::State& state, int native_threads) {
  EditFixture& f = Fixture();
  double analysis = 0.0, numeric = 0.0, setup = 0.0, kept = 0.0;
  for (auto _ : state) {
    auto solver = MakeSolver("auto", native_threads);
    solver->Factorize(f.before, f.context);
    analysis += solver->factor_info().analysis_seconds;
    numeric += solver->factor_info().numeric_seconds;
    setup += solver->factor_info().solve_setup_seconds;
    kept = solver->factor_info().refactor_bytes;
    benchmark::DoNotOptimize(solver.get());
  }
  const double iterations = static_cast<double>(state.iterations());
  state.counters["analysis_ms"] = 1e3 * analysis / iterations;
  state.counters["numeric_ms"] = 1e3 * numeric / iterations;
  state.counters["solve_setup_ms"] = 1e3 * setup / iterations;
  state.counters["refactor_MB"] = kept / 1e6;
  state.counters["nnz_A"] = static_cast<double>(f.before.nonZeros());
  state.counters["vertices"] = static_cast<double>(f.before.rows());
  state.counters["ball"] = static_cast<double>(f.ball.size());
}

void Edit(benchmark::State& state, std::string refactor, bool small, int native_threads) {
  EditFixture& f = Fixture(small);
  auto solver = MakeSolver(refactor, native_threads);
  solver->Factorize(f.before, f.context);
  double add = 0.0, remove = 0.0, residual = 0.0;
  double add_route = 0.0, remove_route = 0.0;
  double add_estimate_update = 0.0, add_estimate_numeric = 0.0, remove_estimate_update = 0.0;
  double add_estimate_partial = 0.0, partial_fraction = 0.0;
  double solve_setup = 0.0, add_solve = 0.0, remove_solve = 0.0;
  for (auto _ : state) {
    const auto added = solver->Refactor(f.after, f.ball, f.context);
    add += added.seconds;
    add_route = static_cast<double>(added.route);
    add_estimate_update = solver->factor_info().estimated_update_seconds;
    add_estimate_numeric = solver->factor_info().estimated_numeric_seconds;
    add_estimate_partial = solver->factor_info().estimated_partial_seconds;
    partial_fraction = solver->factor_info().partial_work_fraction;
    state.PauseTiming();
    residual = std::max(residual, Residual(*solver, f.after, f, add_solve));
    state.ResumeTiming();
    const auto removed = solver->Refactor(f.before, f.ball, f.context);
    remove += removed.seconds;
    remove_route = static_cast<double>(removed.route);
    remove_estimate_update = solver->factor_info().estimated_update_seconds;
    solve_setup = solver->factor_info().solve_setup_seconds;
    state.PauseTiming();
    residual = std::max(residual, Residual(*solver, f.before, f, remove_solve));
    state.ResumeTiming();
  }
  const double iterations = static_cast<double>(state.iterations());
  state.counters["add_ms"] = 1e3 * add / iterations;
  state.counters["remove_ms"] = 1e3 * remove / iterations;
  state.counters["add_route"] = add_route;
  state.counters["remove_route"] = remove_route;
  state.counters["add_est_update_ms"] = 1e3 * add_estimate_update;
  state.counters["remove_est_update_ms"] = 1e3 * remove_estimate_update;
  state.counters["est_numeric_ms"] = 1e3 * add_estimate_numeric;
  state.counters["add_est_partial_ms"] = 1e3 * add_estimate_partial;
  state.counters["partial_work"] = partial_fraction;
  state.counters["residual"] = residual;
  state.counters["solve_setup_ms"] = 1e3 * solve_setup;
  state.counters["add_solve3_ms"] = 1e3 * add_solve;
  state.counters["remove_solve3_ms"] = 1e3 * remove_solve;
  state.counters["ball"] = static_cast<double>(f.ball.size());
}

[[maybe_unused]] const bool registered = [] {
  if (!std::filesystem::exists(ArmadilloBendScenario())) return false;
  const auto add = [](const std::string& name, auto... args) {
    RegisterArmadilloBendBenchmark(name, args...);
  };
  add("HandleEdit_factorize", Factorize, 1);
  for (const std::string route : {"full", "numeric", "update", "partial", "auto"}) {
    add("HandleEdit_" + route, Edit, route, false, 1);
  }
  for (const std::string route : {"numeric", "update", "partial", "auto"}) {
    add("HandleEditSmall_" + route, Edit, route, true, 1);
  }
  // With both cores for CHOLMOD's BLAS and OpenMP, as a session could run an edit when nothing
  // else runs.
  add("HandleEdit_factorize_native2", Factorize, 2);
  add("HandleEdit_numeric_native2", Edit, std::string("numeric"), false, 2);
  return true;
}();

}  // namespace

#endif  // HARAP_HAVE_CHOLMOD
