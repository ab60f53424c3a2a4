// SPDX-License-Identifier: MIT
// The `harap` command line: `harap deform SCENARIO.toml ...`, `harap list`, `harap hierarchy`,
// `harap run CONFIG.toml` (experiment sweeps) and `harap report DIR`.
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <new>

#include "experiments/builtins.h"
#include "experiments/component_factory.h"
#include "experiments/deform.h"
#include "experiments/drag_command.h"
#include "experiments/experiment.h"
#include "experiments/process.h"
#include "experiments/runner.h"
#include "framework/error.h"
#include "framework/io/builtin_meshes.h"
#include "framework/io/mesh_io.h"
#include "framework/io/scenario.h"

namespace {

using namespace harap;

template <class Interface>
void ListRegistry(const Registry<Interface>& registry) {
  fmt::print("{}:\n", registry.kind());
  for (const auto& name : registry.Names()) {
    fmt::print("  {:<20} {}\n", name, registry.Description(name));
    for (const auto& option : registry.DescribeOptions(name)) {
      if (option.key == "type") continue;
      fmt::print("      {}.{} = {}\n          {}\n", registry.kind(), option.key,
                 option.default_value, option.help);
    }
  }
  fmt::print("\n");
}

int List() {
  const Registries registries = MakeBuiltinRegistries();
  ListRegistry(registries.optimizers);
  ListRegistry(registries.energies);
  ListRegistry(registries.linear_solvers);
  fmt::print("solver.small_systems (optional table: a second solver for small reduced systems):\n");
  for (const auto& option : DescribeSmallSystemsOptions()) {
    fmt::print("      solver.small_systems.{} = {}\n          {}\n", option.key,
               option.default_value, option.help);
  }
  fmt::print("\n");
  ListRegistry(registries.hierarchies);
  ListRegistry(registries.upsamplers);
  const ConfigNode describing = ConfigNode::Describing();
  MeshRepairOptions::FromConfig(describing.Child("mesh"));
  fmt::print("mesh (run config [mesh] table, applied before solving):\n");
  for (const auto& option : describing.Child("mesh").Options()) {
    fmt::print("      mesh.{} = {}\n          {}\n", option.key, option.default_value, option.help);
  }
  fmt::print("\n");
  fmt::print("built-in meshes (scenario: mesh = {{ builtin = NAME, ... }}):\n");
  for (const auto& name : BuiltinMeshNames()) fmt::print("  {}\n", name);
  fmt::print("volumetric twins of surfaces (scenario: mesh = {{ tetrahedralize = FILE or "
             "{{ builtin = NAME, ... }}, max_volume, max_radius_edge_ratio, "
             "min_dihedral_angle }}, see docs/input.md)\n");
  return 0;
}

struct DeformArguments {
  std::string scenario;
  std::string config_file;
  std::string optimizer, energy, solver, hierarchy, upsampler;
  std::optional<double> tolerance;
  std::optional<int> max_iterations;
  std::vector<std::string> settings;
  std::string out, report;
  std::string out_rest, out_handles;
  bool trace = false;
  bool diagnostics = false;
  bool quiet = false;
  int threads = 0;
};

// Progress on a terminal for runs that take longer than a second: one overwritten line.
class ProgressLine {
 public:
  explicit ProgressLine(bool enabled) : enabled_(enabled && isatty(fileno(stderr))) {}
  ~ProgressLine() { Finish(); }
  CallbackAction operator()(const IterationSummary& s) {
    if (!enabled_ || s.seconds < 1.0 || s.seconds - last_ < 0.2) return CallbackAction::kContinue;
    last_ = s.seconds;
    shown_ = true;
    fmt::print(stderr, "\r  {:6.1f} s  level {}  iteration {:5}  energy {:.6e}  step {:.2e}   ",
               s.seconds, s.level, s.iteration, s.energy, s.displacement);
    std::fflush(stderr);
    return CallbackAction::kContinue;
  }
  void Finish() {
    if (shown_) fmt::print(stderr, "\r{:80}\r", "");
    shown_ = false;
  }

 private:
  bool enabled_;
  bool shown_ = false;
  double last_ = 0.0;
};

void PrintSummary(const Scenario& scenario, const DeformOutcome& outcome) {
  const OptimizeResult& r = outcome.result;
  fmt::print("scenario    {}\n", scenario.file.string());
  fmt::print("mesh        {} ({} vertices, {} {})\n", scenario.mesh_source,
             scenario.mesh.num_vertices(), scenario.mesh.num_elements(),
             scenario.mesh.kind() == ElementKind::kTetrahedron ? "tetrahedra" : "faces");
  fmt::print("pieces      optimizer {} | energy {} | solver {}{}\n", outcome.optimizer,
             outcome.energy_type, outcome.solver,
             outcome.hierarchy.empty() ? "" : fmt::format(" | hierarchy {} | upsampler {}",
                                                          outcome.hierarchy, outcome.upsampler));
  fmt::print("iterations  {} ({})\n", r.iterations,
             r.converged ? "converged" : (r.stopped_by_callback ? "stopped" : "not converged"));
  fmt::print("energy      {:.9e}\n", r.energy);
  for (const auto& [name, value] : r.measures) fmt::print("{:<11} {:.9e}\n", name, value);
  fmt::print("time [s]    hierarchy {:.3f} | precompute {:.3f} | constrain {:.3f} | solve {:.3f} "
             "| total {:.3f}\n",
             r.timings.hierarchy, r.timings.precompute, r.timings.constrain, r.timings.solve,
             r.timings.total);
  fmt::print("memory      {:.1f} MiB peak\n", PeakMemoryBytes() / (1024.0 * 1024.0));
  for (const auto& note : scenario.notes) fmt::print("note        {}\n", note);
  for (size_t k = 0; k < r.levels.size(); ++k) {
    const LevelResult& level = r.levels[k];
    const SolveStatistics& solves = level.linear_solves;
    fmt::print("level {:<5} {:>8} unknowns | {:<12} {:4} solves {:7} iterations {:7.3f} s | max "
               "residual {:.2e}\n",
               level.level, level.unknowns, outcome.level_solvers[k], solves.solves,
               solves.iterations, solves.seconds, solves.max_relative_residual);
    if (const auto it = outcome.spectra.find(level.level); it != outcome.spectra.end()) {
      const SystemSpectrum& spectrum = it->second;
      fmt::print("            A: λ [{:.4e}, {:.4e}] κ {:.3e} | D^-1/2 A D^-1/2: λ [{:.4e}, "
                 "{:.4e}] κ {:.3e} | {:.2f} s\n",
                 spectrum.matrix.smallest, spectrum.matrix.largest,
                 spectrum.matrix.condition_number(), spectrum.jacobi.smallest,
                 spectrum.jacobi.largest, spectrum.jacobi.condition_number(), spectrum.seconds);
    }
  }
  if (outcome.mesh_summary.empty()) fmt::print("checks      no findings\n");
  for (const auto& line : outcome.mesh_summary) fmt::print("checks      {}\n", line);
  if (outcome.mesh_repaired) {
    fmt::print("solved on   {} vertices, {} {} (results written for all {} input vertices)\n",
               outcome.solved_vertices, outcome.solved_elements,
               scenario.mesh.kind() == ElementKind::kTetrahedron ? "tetrahedra" : "faces",
               scenario.mesh.num_vertices());
  }
  for (const auto& note : r.notes) fmt::print("note        {}\n", note);
}

// The run config: --config file, then the shortcut flags, then --set KEY=VALUE.
ConfigNode BuildRunConfig(const DeformArguments& args) {
  ConfigNode config = args.config_file.empty() ? ConfigNode::Parse("", "<command line>")
                                               : ConfigNode::ParseFile(args.config_file);
  auto set_type = [&](const char* table, const std::string& name) {
    if (!name.empty()) config.Set(fmt::format("{}.type", table), fmt::format("\"{}\"", name));
  };
  set_type("optimizer", args.optimizer);
  set_type("energy", args.energy);
  set_type("solver", args.solver);
  set_type("hierarchy", args.hierarchy);
  set_type("upsampler", args.upsampler);
  if (args.tolerance) config.Set("optimizer.tolerance", fmt::format("{}", *args.tolerance));
  if (args.max_iterations) {
    config.Set("optimizer.max_iterations", fmt::format("{}", *args.max_iterations));
  }
  for (const auto& setting : args.settings) {
    const auto eq = setting.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw ConfigError(fmt::format("--set '{}': expected KEY=VALUE, e.g. energy.lambda=0.5",
                                    setting));
    }
    config.Set(setting.substr(0, eq), setting.substr(eq + 1));
  }
  return config;
}

// What the command is doing, for the out-of-memory message (std::bad_alloc carries no context).
std::string_view current_stage = "starting";

int Deform(const DeformArguments& args) {
  const Registries registries = MakeBuiltinRegistries();
  const ConfigNode config = BuildRunConfig(args);
  current_stage = "reading the scenario and its mesh";
  const Scenario scenario = LoadScenario(args.scenario);
  current_stage = "checking the mesh and solving (precomputation, factorization, iterations)";
  ProgressLine progress(!args.quiet);
  DeformOptions options;
  options.threads = args.threads;
  options.diagnostics = args.diagnostics;
  options.progress = [&](const IterationSummary& s) { return progress(s); };
  const DeformOutcome outcome = RunDeform(registries, scenario, config, options);
  progress.Finish();

  current_stage = "writing the results";
  // The report first: it is the smallest and records the whole run, so a mesh file that cannot be
  // written loses nothing else.
  if (!args.report.empty()) {
    std::ofstream file(args.report);
    file << DeformReportJson(scenario, outcome, args.trace) << "\n";
    if (!file) throw InputError(fmt::format("{}: cannot write the report", args.report));
  }
  if (!args.out.empty()) WritePly(args.out, outcome.result.positions, scenario.mesh.elements);
  if (!args.out_rest.empty()) WritePly(args.out_rest, scenario.mesh.vertices, scenario.mesh.elements);
  if (!args.out_handles.empty()) {
    std::ofstream file(args.out_handles);
    file << HandlesJson(scenario) << "\n";
    if (!file) throw InputError(fmt::format("{}: cannot write the handles", args.out_handles));
  }
  if (!args.quiet) PrintSummary(scenario, outcome);
  return 0;
}

// `harap hierarchy`: builds the hierarchy of a scenario's mesh, writes each level as PLY and
// prints a per-level table.
int WriteHierarchy(const DeformArguments& args, const std::string& out_dir) {
  const Registries registries = MakeBuiltinRegistries();
  const ConfigNode config = BuildRunConfig(args);
  ValidateRunConfig(config);
  current_stage = "reading the scenario and its mesh";
  const Scenario scenario = LoadScenario(args.scenario);
  current_stage = "building the hierarchy";
  auto hierarchy = registries.hierarchies.Create(config.Child("hierarchy"), "octree");
  Context context = Context::WithThreads(args.threads);
  Stopwatch clock;
  const MeshHierarchy levels = hierarchy->Build(scenario.mesh, context);
  const double seconds = clock.Seconds();
  if (!out_dir.empty()) std::filesystem::create_directories(out_dir);
  fmt::print("{:>5} {:>10} {:>10} {:>10}  {}\n", "level", "vertices", "faces", "reduction", "file");
  for (int l = 0; l < levels.num_levels(); ++l) {
    const HierarchyLevel& level = levels.levels[l];
    std::string file;
    if (!out_dir.empty()) {
      file = (std::filesystem::path(out_dir) / fmt::format("level_{}.ply", l)).string();
      WritePly(file, level.mesh.vertices, level.mesh.elements);
    }
    const std::string reduction =
        l == 0 ? std::string("-")
               : fmt::format("{:.2f}x", double(levels.levels[l - 1].mesh.num_vertices()) /
                                            level.mesh.num_vertices());
    fmt::print("{:>5} {:>10} {:>10} {:>10}  {}\n", l, level.mesh.num_vertices(),
               level.mesh.num_elements(), reduction, file);
  }
  fmt::print("hierarchy built in {:.3f} s\n", seconds);
  return 0;
}

struct RunArguments {
  std::string config;
  std::string out;
  std::string shard = "0/1";
  int jobs = 1;
  int threads = 0;
  std::vector<std::string> filter;
  bool retry_failed = false;
  bool quiet = false;
};

// `harap run CONFIG.toml`: the experiment sweep (docs/experiments.md).
int RunSweep(const RunArguments& args) {
  const Experiment experiment = LoadExperiment(args.config);
  RunnerOptions options;
  options.out_dir = args.out.empty() ? std::filesystem::path("results") / experiment.name
                                     : std::filesystem::path(args.out);
  options.shard = ParseShard(args.shard);
  if (args.jobs < 1) throw ConfigError("--jobs must be at least 1");
  options.jobs = args.jobs;
  options.threads = args.threads;
  options.executable = std::filesystem::read_symlink("/proc/self/exe");
  options.retry_failed = args.retry_failed;
  options.scenario_filter = args.filter;
  options.quiet = args.quiet;
  const SweepSummary summary = RunExperiment(experiment, options);
  if (!args.quiet) {
    fmt::print("{}: {} runs planned, {} in this shard: {} done before, {} ran now, {} failed\n",
               experiment.name, summary.planned, summary.in_shard, summary.skipped,
               summary.succeeded + summary.failed, summary.failed);
    fmt::print("results in {} (harap report {} makes the report)\n", options.out_dir.string(),
               options.out_dir.string());
  }
  return 0;
}

struct ReportArguments {
  std::string dir;
  std::string script;
  std::string python;
  bool no_render = false;
};

// `harap report DIR`: merges the shards' results and runs experiments/scripts/report.py.
int Report(const ReportArguments& args) {
  const MergeSummary merged = MergeResults(args.dir);
  fmt::print("{}: {} runs planned: {} finished, {} failed, {} missing\n", args.dir,
             merged.planned, merged.succeeded, merged.failed, merged.missing);
  std::string script = args.script;
  if (script.empty()) {
    const char* env = std::getenv("HARAP_REPORT_SCRIPT");
    script = env ? env : HARAP_SCRIPTS_DIR "/report.py";
  }
  if (!std::filesystem::exists(script)) {
    throw InputError(fmt::format("report script {} not found (give --script)", script));
  }
  std::string python = args.python;
  if (python.empty()) {
    // Debian's python3-matplotlib and python3-vtk9 live in the system interpreter.
    const char* env = std::getenv("HARAP_PYTHON");
    python = env ? env : (std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3");
  }
  std::fflush(stdout);
  std::vector<std::string> command = {python, script, args.dir};
  if (args.no_render) command.push_back("--no-render");
  const ProcessResult result = RunProcess(command, {});
  if (!result.started) throw InputError(fmt::format("cannot run {}", python));
  if (!result.ok()) {
    throw InputError(fmt::format("{} {} failed (exit code {})", python, script, result.exit_code));
  }
  return 0;
}

// OpenBLAS and libgomp (both used inside CHOLMOD) handle failed allocations badly: OpenBLAS's
// worker threads retry forever when their 128 MiB work buffer cannot be allocated (the process
// then hangs at exit), and libgomp ends the process ("libgomp: Thread creation failed") when it
// cannot create a thread. Allocations really fail only under an address-space limit
// (`ulimit -v`); there harap runs both single-threaded, so that running out of memory ends in
// harap's own error message: it re-executes itself once with OPENBLAS_NUM_THREADS=1 and
// OMP_THREAD_LIMIT=1 (CHOLMOD asks for 4 OpenMP threads with num_threads(), which only the
// thread limit caps; values the user set are kept). TBB's threads, which do harap's own parallel
// work, are unaffected. Measured in docs/robustness.md.
void SingleThreadedNativeLibrariesUnderMemoryLimit(char** argv) {
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return;
  if (std::getenv("HARAP_REEXECUTED_FOR_MEMORY_LIMIT") != nullptr) return;
  if (std::getenv("OPENBLAS_NUM_THREADS") != nullptr && std::getenv("OMP_THREAD_LIMIT") != nullptr) {
    return;
  }
  setenv("HARAP_REEXECUTED_FOR_MEMORY_LIMIT", "1", 1);
  setenv("OPENBLAS_NUM_THREADS", "1", 0);
  setenv("OMP_THREAD_LIMIT", "1", 0);
  execv("/proc/self/exe", argv);  // returns only if it failed: carry on as we are
}

}  // namespace

int main(int argc, char** argv) {
  SingleThreadedNativeLibrariesUnderMemoryLimit(argv);
  CLI::App app{"harap: hierarchical As-Rigid-As-Possible deformation of large meshes"};
  app.require_subcommand(1);

  auto* list = app.add_subcommand("list", "list every registered piece with its options");

  DeformArguments args;
  auto* deform = app.add_subcommand("deform", "deform a mesh as a scenario file describes");
  deform->add_option("scenario", args.scenario, "scenario TOML file")->required();
  deform->add_option("--config", args.config_file,
                     "TOML file with [optimizer] [energy] [solver] [hierarchy] [upsampler] tables");
  deform->add_option("--optimizer", args.optimizer, "optimizer name (default classic)");
  deform->add_option("--energy", args.energy,
                     "energy name (default spokes_and_rims; elements for tetrahedral and planar "
                     "meshes)");
  deform->add_option("--solver", args.solver, "linear solver name (default cholmod)");
  deform->add_option("--hierarchy", args.hierarchy, "hierarchy name (hierarchical optimizers)");
  deform->add_option("--upsampler", args.upsampler, "upsampler name (hierarchical optimizers)");
  deform->add_option("--tolerance", args.tolerance,
                     "convergence tolerance: squared max displacement / squared diagonal");
  deform->add_option("--max-iterations", args.max_iterations, "iteration cap (per level)");
  deform->add_option("--set", args.settings,
                     "set any option by its config key, e.g. --set energy.lambda=0.5");
  deform->add_option("--out", args.out, "write the deformed mesh (binary PLY, double precision)");
  deform->add_option("--report", args.report, "write a JSON report");
  deform->add_option("--out-rest", args.out_rest, "write the rest mesh (after refine) as PLY");
  deform->add_option("--out-handles", args.out_handles,
                     "write the handles' vertex indices as JSON (for pictures)");
  deform->add_flag("--trace", args.trace, "include the per-iteration energy trace in the report");
  deform->add_flag("--diagnostics", args.diagnostics,
                   "per level: extreme eigenvalues and condition number of the reduced "
                   "global-step matrix and of its Jacobi scaling (Spectra; after the run)");
  deform->add_option("--threads", args.threads, "worker threads (default: all cores)");
  deform->add_flag("--quiet,-q", args.quiet, "print nothing on success");

  DragCommandArguments drag_args;
  auto* drag = AddDragCommand(app, drag_args);

  std::string hierarchy_out;
  auto* hierarchy = app.add_subcommand("hierarchy", "build a scenario's mesh hierarchy, write each "
                                                    "level as PLY, print a per-level table");
  hierarchy->add_option("scenario", args.scenario, "scenario TOML file")->required();
  hierarchy->add_option("--out", hierarchy_out, "folder for level_<l>.ply files");
  hierarchy->add_option("--hierarchy", args.hierarchy, "hierarchy name (default octree)");
  hierarchy->add_option("--config", args.config_file, "TOML file with a [hierarchy] table");
  hierarchy->add_option("--set", args.settings, "set an option, e.g. hierarchy.min_vertices=500");
  hierarchy->add_option("--threads", args.threads, "worker threads (default: all cores)");

  RunArguments run_args;
  auto* run = app.add_subcommand("run", "run an experiment config: every scenario x variant x grid "
                                        "combination, with resume (docs/experiments.md)");
  run->add_option("config", run_args.config, "experiment config (experiments/configs/*.toml)")
      ->required();
  run->add_option("--out", run_args.out, "output folder (default results/<experiment name>)");
  run->add_option("--shard", run_args.shard,
                  "I/N: run only the runs with index % N == I (0 <= I < N), e.g. for Slurm arrays");
  run->add_option("--jobs,-j", run_args.jobs, "runs at once, each its own process (default 1)");
  run->add_option("--threads", run_args.threads,
                  "threads per run (default: [run] threads, else cores / jobs)");
  run->add_option("--filter", run_args.filter,
                  "only scenarios whose name matches this shell pattern (repeatable)");
  run->add_flag("--retry-failed", run_args.retry_failed, "run failed runs again");
  run->add_flag("--quiet,-q", run_args.quiet, "no progress output");

  ReportArguments report_args;
  auto* report = app.add_subcommand("report", "merge the shards of a run folder into results.csv "
                                              "and write report.md with figures and pictures");
  report->add_option("dir", report_args.dir, "output folder of harap run")->required();
  report->add_option("--script", report_args.script, "report script (default experiments/scripts/report.py)");
  report->add_option("--python", report_args.python, "Python interpreter (default /usr/bin/python3)");
  report->add_flag("--no-render", report_args.no_render, "skip the mesh pictures");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error);
  }
  try {
    if (*list) return List();
    if (*hierarchy) return WriteHierarchy(args, hierarchy_out);
    if (*run) return RunSweep(run_args);
    if (*report) return Report(report_args);
    if (*drag) return RunDragCommand(drag_args);
    return Deform(args);
  } catch (const harap::Error& error) {
    fmt::print(stderr, "harap: error: {}\n", error.what());
    return 1;
  } catch (const std::bad_alloc&) {
    fmt::print(stderr,
               "harap: error: out of memory while {}. The run needs more memory than this "
               "process may use (see `ulimit -v`). Try an iterative solver, which needs no "
               "factorization (--solver cg or --solver gauss_seidel), fewer threads, or a smaller "
               "mesh.\n",
               current_stage);
    return 1;
  } catch (const std::exception& error) {
    fmt::print(stderr, "harap: internal error: {}\n", error.what());
    return 2;
  }
}
