// SPDX-License-Identifier: MIT
// Micro-benchmarks of the classic ARAP kernels: local step, right-hand side, factorization,
// one solve, one full iteration; and of the hierarchical pieces: building each registered
// hierarchy, and each registered up-sampler from level 1 to the input mesh — on a generated
// cylinder and, when ../shared is present, on the armadillo-bend scenario (armadillo-43k refined
// once: ~173K vertices) and the tetrahedral WRAPD rabbit (26K vertices, 102K tetrahedra, energy
// `elements`). Octree vs edge collapse on meshes in file order (also dragon-lift) are registered
// from hierarchy_benchmark.cpp as HierarchyBuildFileOrder_<name>.
// The iterative solvers (gauss_seidel, cg, chebyshev) get their setup cost and the cost of one
// solve with a fixed budget of 10 iterations (counter `per_iteration`: seconds per solver
// iteration, 3 columns).
//
//   ./build/harap_benchmarks --benchmark_filter=armadillo
//   ./build/harap_benchmarks --benchmark_filter='Iterative.*armadillo'
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "api/builtins.h"
#include "api/huge_pages.h"
#include "benchmarks/hierarchy_benchmark.h"
#include "framework/constrained_system.h"
#include "framework/error.h"
#include "io/builtin_meshes.h"
#include "io/mesh_repair.h"
#include "io/scenario.h"
#include "solvers/linear/cholmod_solver.h"
#include "solvers/optimizers/vertex_ordering.h"

namespace {

using namespace harap;

/// One loaded problem with its energy precomputed and its reduced system factored.
struct Fixture {
  Scenario scenario;
  Mesh input_mesh;  ///< The scenario's mesh in file order, as `harap deform` checks it.
  Registries registries = MakeBuiltinRegistries();
  Context context;
  std::unique_ptr<Energy> energy;
  std::unique_ptr<ConstrainedSystem> system;
  std::unique_ptr<LinearSolver> solver;
  Positions u, rhs;
  Rotations rotations;
  Eigen::MatrixXd reduced_rhs, reduced_x;

  Fixture(Scenario loaded, const std::string& energy_name)
      : scenario(std::move(loaded)), input_mesh(scenario.mesh) {
    // The optimizers renumber each level for locality; measure the kernels the same way.
    const MeshOrdering ordering = LocalityOrdering(scenario.mesh);
    scenario.mesh = ordering.mesh;
    Constraints constraints = scenario.MergedConstraints();
    for (Index& v : constraints.indices) v = ordering.new_vertex[v];
    energy = registries.energies.Create(energy_name, ConfigNode());
    energy->Precompute(scenario.mesh, context);
    system = std::make_unique<ConstrainedSystem>(energy->system_matrix(), constraints.indices);
    solver = registries.linear_solvers.Create("cholmod", ConfigNode());
    solver->Factorize(system->reduced_matrix(), context);
    u = scenario.mesh.vertices;
    for (size_t k = 0; k < constraints.indices.size(); ++k) {
      u.row(constraints.indices[k]) = constraints.targets.row(k);
    }
    system->SetFixedPositions(u);
    rotations.assign(energy->num_rotations(), Rotation::Identity());
    rhs.resize(u.rows(), 3);
    system->GatherFree(u, reduced_x);
    // A few iterations so the state (and the rotation warm starts) look like mid-solve.
    for (int i = 0; i < 3; ++i) Iterate();
  }

  void Iterate() {
    energy->FitRotations(u, rotations, context);
    energy->AssembleRhs(rotations, rhs, context);
    system->ReducedRhs(rhs, reduced_rhs);
    if (!solver->is_direct()) system->GatherFree(u, reduced_x);
    solver->Solve(reduced_rhs, reduced_x, context);
    system->ScatterFree(reduced_x, u);
  }
};

std::map<std::string, std::unique_ptr<Fixture>>& Fixtures() {
  static std::map<std::string, std::unique_ptr<Fixture>> fixtures;
  return fixtures;
}

Fixture& Get(const std::string& key) { return *Fixtures().at(key); }

void SetCounters(benchmark::State& state, const Fixture& fixture) {
  state.counters["vertices"] = fixture.scenario.mesh.num_vertices();
  state.SetComplexityN(fixture.scenario.mesh.num_vertices());
}

void LocalStep(benchmark::State& state, std::string key) {
  Fixture& f = Get(key);
  for (auto _ : state)
    benchmark::DoNotOptimize(f.energy->FitRotations(f.u, f.rotations, f.context));
  SetCounters(state, f);
}

void RightHandSide(benchmark::State& state, std::string key) {
  Fixture& f = Get(key);
  for (auto _ : state) {
    f.energy->AssembleRhs(f.rotations, f.rhs, f.context);
    f.system->ReducedRhs(f.rhs, f.reduced_rhs);
    benchmark::ClobberMemory();
  }
  SetCounters(state, f);
}

/// The second-order kernels of the Newton steps (optimizer.newton): preparing the rotation
/// derivative (exact or projected) at the current state, and the rotation part of one
/// Hessian-vector product (R'(u)[v] and B of it; the rest of the product is A v and the
/// preconditioning solve). Fits the fixture's rotations and returns the rotation derivative's
/// curvature there.
std::vector<Eigen::Matrix3d> FittedCurvature(Fixture& f, bool project) {
  std::vector<Eigen::Matrix3d> curvature;
  f.energy->FitRotations(f.u, f.rotations, f.context);
  f.energy->PrepareRotationDerivative(f.u, f.rotations, project, curvature, f.context);
  return curvature;
}

void PrepareRotationDerivative(benchmark::State& state, std::string key, bool project) {
  Fixture& f = Get(key);
  std::vector<Eigen::Matrix3d> curvature = FittedCurvature(f, project);
  for (auto _ : state) {
    f.energy->PrepareRotationDerivative(f.u, f.rotations, project, curvature, f.context);
    benchmark::ClobberMemory();
  }
  SetCounters(state, f);
}

void RotationDerivativeProduct(benchmark::State& state, std::string key) {
  Fixture& f = Get(key);
  const std::vector<Eigen::Matrix3d> curvature = FittedCurvature(f, /*project=*/false);
  const Positions direction = f.u - f.scenario.mesh.vertices;
  Rotations d_rotations;
  for (auto _ : state) {
    f.energy->RotationDerivative(direction, f.rotations, curvature, d_rotations, f.context);
    f.energy->AssembleRhs(d_rotations, f.rhs, f.context);
    benchmark::ClobberMemory();
  }
  SetCounters(state, f);
}

ConfigNode SolverOptions(const std::string& mode, const std::string& ordering,
                         bool parallel_solve = true, int native_threads = 1,
                         const std::string& numeric = "parallel") {
  ConfigNode options;
  options.Set("mode", fmt::format("\"{}\"", mode));
  options.Set("ordering", fmt::format("\"{}\"", ordering));
  options.Set("parallel_solve", parallel_solve ? "true" : "false");
  options.Set("native_threads", std::to_string(native_threads));
  options.Set("numeric", fmt::format("\"{}\"", numeric));
  return options;
}

void Factorization(benchmark::State& state, std::string key, std::string mode, std::string ordering,
                   bool parallel_solve, int native_threads, std::string numeric) {
  Fixture& f = Get(key);
  const ConfigNode options = SolverOptions(mode, ordering, parallel_solve, native_threads, numeric);
  for (auto _ : state) {
    auto solver = f.registries.linear_solvers.Create("cholmod", options);
    solver->Factorize(f.system->reduced_matrix(), f.context);
    benchmark::DoNotOptimize(solver.get());
#ifdef HARAP_HAVE_CHOLMOD
    // Where the time of the last iteration went (the solver's own stopwatches).
    const auto& info = static_cast<const CholmodSolver&>(*solver).factor_info();
    state.counters["analysis_s"] = info.analysis_seconds;
    state.counters["numeric_s"] = info.numeric_seconds;
    state.counters["setup_s"] = info.solve_setup_seconds;
    state.counters["nnz_L"] = info.nnz_l;
    state.counters["flops"] = info.flops;
#endif
  }
  SetCounters(state, f);
}

// Two factorizations of the reduced matrix at once, one on a thread of its own, as the
// hierarchical optimizer's setup runs them (one level in the background, another in the
// caller's thread); with CHOLMOD's own threads on (native_threads = 0: OpenMP asks for 4, OpenBLAS
// one per core) they compete with each other on top of the two factorizations.
void ConcurrentFactorizations(benchmark::State& state, std::string key, int native_threads) {
  Fixture& f = Get(key);
  const ConfigNode options = SolverOptions("auto", "amd", true, native_threads);
  const auto factorize = [&] {
    auto solver = f.registries.linear_solvers.Create("cholmod", options);
    solver->Factorize(f.system->reduced_matrix(), f.context);
    benchmark::DoNotOptimize(solver.get());
  };
  for (auto _ : state) {
    std::thread other(factorize);
    factorize();
    other.join();
  }
  SetCounters(state, f);
}

void Solve(benchmark::State& state, std::string key, std::string mode, std::string ordering,
           bool parallel_solve) {
  Fixture& f = Get(key);
  const ConfigNode options = SolverOptions(mode, ordering, parallel_solve);
  auto solver = f.registries.linear_solvers.Create("cholmod", options);
  solver->Factorize(f.system->reduced_matrix(), f.context);
#ifdef HARAP_HAVE_CHOLMOD
  if (const auto* cholmod = dynamic_cast<const CholmodSolver*>(solver.get())) {
    state.counters["blocks"] = cholmod->factor_info().solve_blocks;
    state.counters["critical_path"] = cholmod->factor_info().solve_critical_path;
    state.counters["nnz_L"] = cholmod->factor_info().nnz_l;
  }
#endif
  Eigen::MatrixXd x = f.reduced_x;
  for (auto _ : state) {
    solver->Solve(f.reduced_rhs, x, f.context);
    benchmark::ClobberMemory();
  }
  SetCounters(state, f);
}

/// An iterative solver configuration, benchmarked with max_iterations = kBudget and no tolerance.
struct IterativeCase {
  std::string label;
  std::string solver;
  std::string options;
};

constexpr int kBudget = 10;

const std::vector<IterativeCase>& IterativeCases() {
  static const std::vector<IterativeCase> cases = {
      {"gauss_seidel_forward", "gauss_seidel", ""},
      {"gauss_seidel_symmetric", "gauss_seidel", "sweep = \"symmetric\""},
      {"gauss_seidel_natural", "gauss_seidel", "ordering = \"natural\""},
      {"gauss_seidel_symmetric_blocks", "gauss_seidel",
       "sweep = \"symmetric\"\nordering = \"blocks\""},
      {"cg_jacobi", "cg", ""},
      {"cg_incomplete_cholesky", "cg", "preconditioner = \"incomplete_cholesky\""},
      {"chebyshev_budget", "chebyshev", ""},
      {"chebyshev_shift_invert", "chebyshev", "lower_bound = \"shift_invert\""},
  };
  return cases;
}

ConfigNode IterativeOptions(const IterativeCase& c) {
  return ConfigNode::Parse(fmt::format("max_iterations = {}\n{}", kBudget, c.options), c.label);
}

// Factorize(): colouring, preconditioner, spectral bounds.
void IterativeSetup(benchmark::State& state, std::string key, IterativeCase c) {
  Fixture& f = Get(key);
  const ConfigNode options = IterativeOptions(c);
  for (auto _ : state) {
    auto solver = f.registries.linear_solvers.Create(c.solver, options);
    f.context.Run([&] { solver->Factorize(f.system->reduced_matrix(), f.context); });
    benchmark::DoNotOptimize(solver.get());
  }
  SetCounters(state, f);
}

// One warm-started solve of the three coordinates with kBudget iterations.
void IterativeSolve(benchmark::State& state, std::string key, IterativeCase c) {
  Fixture& f = Get(key);
  auto solver = f.registries.linear_solvers.Create(c.solver, IterativeOptions(c));
  f.context.Run([&] { solver->Factorize(f.system->reduced_matrix(), f.context); });
  Eigen::MatrixXd x = f.reduced_x;
  for (auto _ : state) {
    f.context.Run([&] { benchmark::DoNotOptimize(solver->Solve(f.reduced_rhs, x, f.context)); });
  }
  state.counters["per_iteration"] = benchmark::Counter(
      static_cast<double>(kBudget),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  SetCounters(state, f);
}

// The input checks and repairs `harap deform` runs before any optimizer (PreparedProblem:
// CheckMesh, then welding and duplicate removal), on the mesh in file order.
void PrepareProblem(benchmark::State& state, std::string key) {
  Fixture& f = Get(key);
  DeformationProblem problem;
  problem.mesh = &f.input_mesh;
  problem.constraints = f.scenario.MergedConstraints();
  for (auto _ : state) {
    const PreparedProblem prepared(problem, MeshRepairOptions());
    benchmark::DoNotOptimize(prepared.checks().boundary_edges.count);
  }
  SetCounters(state, f);
}

void FullIteration(benchmark::State& state, std::string key) {
  Fixture& f = Get(key);
  for (auto _ : state) {
    f.Iterate();
    benchmark::ClobberMemory();
  }
  SetCounters(state, f);
}

/// A scenario's mesh with its hierarchy (default options) and a coarse state to up-sample.
struct HierarchyFixture {
  Mesh mesh;
  Registries registries = MakeBuiltinRegistries();
  Context context;
  MeshHierarchy hierarchy;
  LevelState coarse_state;

  explicit HierarchyFixture(const Mesh& input) : mesh(input) {
    hierarchy = registries.hierarchies.Create("octree", ConfigNode())->Build(mesh, context);
    // A smooth rotation field on level 1 (a twist about z growing with height), as a solve
    // would leave it, and the positions it implies.
    const Mesh& coarse = hierarchy.levels.at(1).mesh;
    const double z0 = coarse.vertices.col(2).minCoeff();
    const double height = std::max(coarse.vertices.col(2).maxCoeff() - z0, 1e-12);
    coarse_state.positions = coarse.vertices;
    coarse_state.rotations.resize(coarse.num_vertices());
    for (Index v = 0; v < coarse.num_vertices(); ++v) {
      const double angle = 1.2 * (coarse.vertices(v, 2) - z0) / height;
      coarse_state.rotations[v] =
          Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      coarse_state.positions.row(v) =
          (coarse_state.rotations[v] * coarse.vertices.row(v).transpose()).transpose();
    }
  }
};

std::map<std::string, std::unique_ptr<HierarchyFixture>>& HierarchyFixtures() {
  static std::map<std::string, std::unique_ptr<HierarchyFixture>> fixtures;
  return fixtures;
}

void HierarchyBuild(benchmark::State& state, std::string key, std::string name) {
  HierarchyFixture& f = *HierarchyFixtures().at(key);
  auto hierarchy = f.registries.hierarchies.Create(name, ConfigNode());
  int levels = 0;
  for (auto _ : state) {
    const MeshHierarchy built = hierarchy->Build(f.mesh, f.context);
    levels = built.num_levels();
    benchmark::DoNotOptimize(built.levels.data());
  }
  state.counters["vertices"] = f.mesh.num_vertices();
  state.counters["levels"] = levels;
}

void Upsample(benchmark::State& state, std::string key, std::string name) {
  HierarchyFixture& f = *HierarchyFixtures().at(key);
  auto upsampler = f.registries.upsamplers.Create(name, ConfigNode());
  LevelState fine_state;
  for (auto _ : state) {
    upsampler->Upsample(f.hierarchy.levels[0], f.hierarchy.levels[1], RotationSite::kVertex,
                        f.coarse_state, fine_state, f.context);
    benchmark::ClobberMemory();
  }
  state.counters["vertices"] = f.mesh.num_vertices();
  state.counters["coarse_vertices"] = f.hierarchy.levels[1].mesh.num_vertices();
}

void RegisterAll(const std::string& key) {
  auto add = [&](const std::string& name, auto&&... args) {
    benchmark::RegisterBenchmark((name + "/" + key).c_str(), args...)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  };
  add("LocalStep", LocalStep, key);
  add("RightHandSide", RightHandSide, key);
  if (Get(key).energy->has_rotation_derivative()) {
    add("PrepareRotationDerivative_exact", PrepareRotationDerivative, key, false);
    add("PrepareRotationDerivative_projected", PrepareRotationDerivative, key, true);
    add("RotationDerivativeProduct", RotationDerivativeProduct, key);
  }
  for (const char* ordering : {"amd", "metis"}) {
    for (const char* mode : {"auto", "simplicial", "supernodal"}) {
      const std::string suffix = std::string(mode) + "_" + ordering;
      add("Factorization_" + suffix, Factorization, key, std::string(mode), std::string(ordering),
          true, 1, std::string("parallel"));
      add("Solve3_" + suffix, Solve, key, std::string(mode), std::string(ordering), true);
      if (std::string_view(mode) != "supernodal") {
        // CHOLMOD's own sequential solve with the same factor, for the side-by-side ratio.
        add("Factorization_" + suffix + "_sequential", Factorization, key, std::string(mode),
            std::string(ordering), false, 1, std::string("parallel"));
        add("Solve3_" + suffix + "_sequential", Solve, key, std::string(mode),
            std::string(ordering), false);
      }
    }
  }
  // CHOLMOD's own numeric factorization (cholmod_factorize) beside harap's (numeric =
  // "parallel", the default: the same values, no permuted copies of A, subtrees on the threads).
  for (const char* mode : {"auto", "supernodal"}) {
    add("Factorization_" + std::string(mode) + "_amd_cholmod_numeric", Factorization, key,
        std::string(mode), std::string("amd"), true, 1, std::string("cholmod"));
  }
  // CHOLMOD's own threads (OpenMP, OpenBLAS) on, beside the default native_threads = 1.
  add("Factorization_auto_amd_native_threads", Factorization, key, std::string("auto"),
      std::string("amd"), true, 0, std::string("parallel"));
  add("Factorization_supernodal_amd_native_threads", Factorization, key, std::string("supernodal"),
      std::string("amd"), true, 0, std::string("parallel"));
  // Two native threads (OpenMP and OpenBLAS on both cores of the 2-core VM), for a factorization
  // that has the machine to itself (classic's one level), and CHOLMOD's default ordering choice.
  for (const char* mode : {"auto", "supernodal"}) {
    add("Factorization_" + std::string(mode) + "_amd_2_native_threads", Factorization, key,
        std::string(mode), std::string("amd"), true, 2, std::string("parallel"));
    add("Factorization_" + std::string(mode) + "_best", Factorization, key, std::string(mode),
        std::string("best"), true, 1, std::string("parallel"));
  }
  add("ConcurrentFactorizations", ConcurrentFactorizations, key, 1);
  add("ConcurrentFactorizations_native_threads", ConcurrentFactorizations, key, 0);
  add("FullIteration", FullIteration, key);
  add("PrepareProblem", PrepareProblem, key);

  HierarchyFixtures()[key] = std::make_unique<HierarchyFixture>(Get(key).scenario.mesh);
  const Registries& registries = HierarchyFixtures()[key]->registries;
  for (const std::string& name : registries.hierarchies.Names()) {
    add("HierarchyBuild_" + name, HierarchyBuild, key, name);
  }
  for (const std::string& name : registries.upsamplers.Names()) {
    add("Upsample_" + name, Upsample, key, name);
  }
  for (const IterativeCase& c : IterativeCases()) {
    add("IterativeSetup_" + c.label, IterativeSetup, key, c);
    add("IterativeSolve3_" + c.label, IterativeSolve, key, c);
  }
}

}  // namespace

int main(int argc, char** argv) {
  // As the harap command does (api/huge_pages.h): the large cases' times otherwise measure page
  // faults. GLIBC_TUNABLES=glibc.malloc.hugetlb=0 measures without.
  if (RequestHugePagesForMalloc()) execv("/proc/self/exe", argv);
  benchmark::Initialize(&argc, argv);
  // Generated: no data needed.
  {
    Scenario cylinder = ParseScenario(R"(
mesh = { builtin = "cylinder", vertices = 170000 }
[[handle]]
select.slab = { axis = "z", from = 0.0, to = 0.02 }
[[handle]]
select.slab = { axis = "z", from = 0.98, to = 1.0 }
rotate = { axis = [1.0, 0.0, 0.0], degrees = 90.0 }
translate = [0.0, 0.35, -0.3]
)",
                                      "cylinder-170k", ".");
    Fixtures()["cylinder-170k"] = std::make_unique<Fixture>(std::move(cylinder), "spokes_and_rims");
    RegisterAll("cylinder-170k");
  }
  const std::filesystem::path armadillo =
      std::filesystem::path(HARAP_SHARED_DIR) / "scenarios/armadillo-bend.toml";
  if (std::filesystem::exists(armadillo)) {
    Fixtures()["armadillo-bend"] =
        std::make_unique<Fixture>(LoadScenario(armadillo), "spokes_and_rims");
    RegisterAll("armadillo-bend");
  } else {
    fmt::print(stderr, "note: {} not found; armadillo benchmarks skipped\n", armadillo.string());
  }
  // A volumetric WRAPD scene with the per-element energy (needs the TetGen reader).
  const std::filesystem::path rabbit =
      std::filesystem::path(HARAP_SHARED_DIR) / "scenarios/tets/rabbit.toml";
  try {
    if (!std::filesystem::exists(rabbit)) throw InputError(rabbit.string() + " not found");
    Fixtures()["wrapd-rabbit"] = std::make_unique<Fixture>(LoadScenario(rabbit), "elements");
    RegisterAll("wrapd-rabbit");
  } catch (const InputError& error) {
    fmt::print(stderr, "note: wrapd-rabbit benchmarks skipped: {}\n", error.what());
  }
  harap::benchmarks::RegisterHierarchyBenchmarks(HARAP_SHARED_DIR);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
