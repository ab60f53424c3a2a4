// SPDX-License-Identifier: MIT
// The `harap` command line: `harap deform SCENARIO.toml ...`, `harap list`, `harap hierarchy`,
// `harap register SOURCE TARGET`, `harap known-answer SCENARIO`, `harap run CONFIG.toml`
// (experiment sweeps) and `harap report DIR`.
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <new>

#include "api/builtins.h"
#include "api/component_factory.h"
#include "api/deform.h"
#include "api/library.h"
#include "cli/cli_output.h"
#include "cli/drag_command.h"
#include "cli/handles_command.h"
#include "cli/interrupt.h"
#include "cli/known_answer_command.h"
#include "cli/output_checks.h"
#include "cli/piece_flags.h"
#include "cli/process_settings.h"
#include "cli/progress.h"
#include "cli/register_command.h"
#include "cli/scenario_command.h"
#include "cli/slurm_command.h"
#include "cli/view_command.h"
#include "framework/error.h"
#include "io/builtin_meshes.h"
#include "io/mesh_io.h"
#include "io/mesh_writers.h"
#include "io/scenario.h"
#include "runner/experiment.h"
#include "runner/process.h"
#include "runner/runner.h"

namespace {

using namespace harap;

struct DeformArguments : PieceFlags {
  std::string scenario;
  std::string out, report;
  std::string out_rest, out_handles;
  bool trace = false;
  bool diagnostics = false;
  bool quiet = false;
  int threads = 0;
  double min_time = 0.0;
};

// What the command is doing, for the out-of-memory message (std::bad_alloc carries no context).
std::string_view current_stage = "starting";

int Deform(const DeformArguments& args) {
  const Registries registries = MakeBuiltinRegistries();
  const ConfigNode config = args.BuildConfig();
  RefuseMeshAsScenario(args.scenario);
  // Output names are checked before any long work (the mesh format below, once it is known).
  const std::pair<const std::string*, const char*> outputs[] = {
      {&args.report, "--report"},
      {&args.out, "--out"},
      {&args.out_rest, "--out-rest"},
      {&args.out_handles, "--out-handles"}};
  for (const auto& [file, option] : outputs) {
    if (!file->empty()) CheckWritable(*file, option);
  }
  // Mesh outputs: an extension no mesh can be written as fails now; whether it suits this mesh
  // (tetrahedra-only formats) once the mesh is read, still before solving.
  for (const auto& [out, option] : {outputs[1], outputs[2]}) {
    if (!out->empty()) CheckMeshOutputFormat(*out, ElementKind::kTetrahedron);
  }
  ProgressDisplay progress(stderr, ProgressOptions::For(stderr, args.quiet));
  current_stage = "reading the scenario and its mesh";
  progress.Phase(ScenarioLoadingPhase(args.scenario));
  const Scenario scenario = LoadScenario(args.scenario);
  for (const auto& [out, option] : {outputs[1], outputs[2]}) {
    if (out->empty()) continue;
    CheckMeshOutputFormat(*out, scenario.mesh.kind());
    for (const auto& file : MeshOutputFiles(*out)) CheckWritable(file, option);
  }
  current_stage = "checking the mesh and solving (precomputation, factorization, iterations)";
  // Ctrl-C stops after the current iteration; the report and the mesh so far are still written.
  const InterruptGuard interrupt;
  DeformOptions options;
  options.threads = args.threads;
  options.diagnostics = args.diagnostics;
  options.min_time = args.min_time;
  progress.Follow(options, InterruptGuard::Requested);
  DeformOutcome outcome = RunDeform(registries, scenario, config, options);
  outcome.interrupted = InterruptGuard::Requested();

  current_stage = "writing the results";
  progress.Phase("writing the results");
  // The report first: it is the smallest and records the whole run, so a mesh file that cannot be
  // written loses nothing else.
  if (!args.report.empty()) {
    std::ofstream file(args.report);
    file << DeformReportJson(scenario, outcome, args.trace) << "\n";
    if (!file) throw InputError(fmt::format("{}: cannot write the report", args.report));
  }
  if (!args.out.empty()) WriteMesh(args.out, outcome.result.positions, scenario.mesh.elements);
  if (!args.out_rest.empty())
    WriteMesh(args.out_rest, scenario.mesh.vertices, scenario.mesh.elements);
  if (!args.out_handles.empty()) {
    std::ofstream file(args.out_handles);
    file << HandlesJson(scenario) << "\n";
    if (!file) throw InputError(fmt::format("{}: cannot write the handles", args.out_handles));
  }
  progress.Finish();
  if (!args.quiet) PrintDeformSummary(scenario, outcome);
  // An interrupted run wrote what it had, but did not finish: say so to scripts (128 + SIGINT).
  return outcome.interrupted ? 130 : 0;
}

// `harap hierarchy`: builds the hierarchy of a scenario's mesh, writes each level as PLY and
// prints a per-level table.
int WriteHierarchy(const DeformArguments& args, const std::string& out_dir) {
  const Registries registries = MakeBuiltinRegistries();
  const ConfigNode config = args.BuildConfig();
  ValidateRunConfig(config);
  RefuseMeshAsScenario(args.scenario);
  ProgressDisplay progress(stderr, ProgressOptions::For(stderr, false));
  current_stage = "reading the scenario and its mesh";
  progress.Phase(ScenarioLoadingPhase(args.scenario));
  const Scenario scenario = LoadScenario(args.scenario);
  current_stage = "building the hierarchy";
  auto hierarchy = registries.hierarchies.Create(OptionReader(config.Child("hierarchy")), "octree");
  Context context = Context::WithThreads(args.threads);
  progress.Phase("building the hierarchy");
  Stopwatch clock;
  const MeshHierarchy levels = hierarchy->Build(scenario.mesh, context);
  const double seconds = clock.Seconds();
  progress.Finish();
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
  SlurmArguments slurm;
};

// `harap run CONFIG.toml`: the experiment sweep (docs/experiments.md).
int RunSweep(const RunArguments& args) {
  RefuseMeshAsToml(args.config, "harap run",
                   "an experiment config: [scenarios] files = [...] and [[variant]] tables "
                   "(docs/experiments.md)");
  RefuseScenarioAsConfig(args.config);
  if (args.slurm.slurm) return SubmitSweepToSlurm(args.config, args.out, args.slurm);
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
  ProgressDisplay progress(stderr, ProgressOptions::For(stderr, args.quiet));
  options.observer = &progress;
  const SweepSummary summary = RunExperiment(experiment, options);
  progress.Finish();
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
  fmt::print("{}: {} runs planned: {} finished, {} failed, {} missing\n", args.dir, merged.planned,
             merged.succeeded, merged.failed, merged.missing);
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
    python =
        env ? env : (std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3");
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

CLI::App* AddDeformCommand(CLI::App& app, DeformArguments& args) {
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
  deform->add_option("--preset", args.preset,
                     "named option set: fast or hierarchical (docs/solvers.md; other options win)");
  deform->add_option("--tolerance", args.tolerance,
                     "convergence tolerance: squared max displacement / squared diagonal");
  deform->add_option("--max-iterations", args.max_iterations, "iteration cap (per level)");
  deform->add_option("--set", args.settings,
                     "set any option by its config key, e.g. --set energy.lambda=0.5");
  deform->add_option("--out", args.out,
                     "write the deformed mesh; the extension picks the format: .ply (binary, "
                     "double), .obj, .off, .stl; tetrahedra also .mesh, .node");
  deform->add_option("--report", args.report, "write a JSON report");
  deform->add_option("--out-rest", args.out_rest,
                     "write the rest mesh (after refine); formats as --out");
  deform->add_option("--out-handles", args.out_handles,
                     "write the handles' vertex indices as JSON (for pictures)");
  deform->add_flag("--trace", args.trace, "include the per-iteration energy trace in the report");
  deform->add_flag("--diagnostics", args.diagnostics,
                   "per level: extreme eigenvalues and condition number of the reduced "
                   "global-step matrix and of its Jacobi scaling (Spectra; after the run)");
  deform->add_option("--threads", args.threads, "worker threads (default: all cores)");
  deform
      ->add_option("--min-time", args.min_time,
                   "repeat the solve in this process until the repetitions took this many "
                   "seconds in all (at most 30); report the median one (timing short runs, "
                   "docs/experiments.md)")
      ->check(CLI::Range(0.0, 3600.0));
  deform->add_flag("--quiet,-q", args.quiet, "print nothing on success");
  return deform;
}

// `harap hierarchy` shares deform's arguments (scenario, hierarchy, config, settings, threads).
CLI::App* AddHierarchyCommand(CLI::App& app, DeformArguments& args, std::string& out) {
  auto* hierarchy = app.add_subcommand("hierarchy",
                                       "build a scenario's mesh hierarchy, write each "
                                       "level as PLY, print a per-level table");
  hierarchy->add_option("scenario", args.scenario, "scenario TOML file")->required();
  hierarchy->add_option("--out", out, "folder for level_<l>.ply files");
  hierarchy->add_option("--hierarchy", args.hierarchy, "hierarchy name (default octree)");
  hierarchy->add_option("--config", args.config_file, "TOML file with a [hierarchy] table");
  hierarchy->add_option("--set", args.settings, "set an option, e.g. hierarchy.min_vertices=500");
  hierarchy->add_option("--threads", args.threads, "worker threads (default: all cores)");
  return hierarchy;
}

CLI::App* AddHandlesCommand(CLI::App& app, std::string& scenario, std::string& out) {
  auto* handles = app.add_subcommand(
      "handles",
      "show what a scenario's handles select and where they go, without solving: "
      "bounding box, per handle vertex count, centroid and motion; --out writes the "
      "mesh with the handles coloured");
  handles->add_option("scenario", scenario, "scenario TOML file")->required();
  handles->add_option("--out", out,
                      "write the rest mesh as PLY with each handle's vertices coloured");
  return handles;
}

CLI::App* AddRunCommand(CLI::App& app, RunArguments& run_args) {
  auto* run = app.add_subcommand("run",
                                 "run an experiment config: every scenario x variant x grid "
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
  AddSlurmOptions(*run, run_args.slurm);
  return run;
}

CLI::App* AddReportCommand(CLI::App& app, ReportArguments& report_args) {
  auto* report = app.add_subcommand("report",
                                    "merge the shards of a run folder into results.csv "
                                    "and write report.md with figures and pictures");
  report->add_option("dir", report_args.dir, "output folder of harap run")->required();
  report->add_option("--script", report_args.script,
                     "report script (default experiments/scripts/report.py)");
  report->add_option("--python", report_args.python,
                     "Python interpreter (default /usr/bin/python3)");
  report->add_flag("--no-render", report_args.no_render, "skip the mesh pictures");
  return report;
}

}  // namespace

int main(int argc, char** argv) {
  RestartWithProcessSettings(argv);
  // Nothing in this process has called BLAS yet and nothing else will: OpenBLAS's idle workers,
  // started when it loaded, would only spin beside the run's threads (docs/solvers.md).
  StopIdleNativeThreads();
  CLI::App app{"harap: hierarchical As-Rigid-As-Possible deformation of large meshes"};
  app.require_subcommand(1);

  app.set_version_flag("--version", VersionString(), "print the version and exit");
  auto* list = app.add_subcommand("list", "list every registered piece with its options");
  std::string list_kind;
  list->add_option("kind", list_kind,
                   "only this kind: optimizers, energies, solvers, hierarchies, upsamplers, "
                   "level_solvers, mesh, registration, builtins, presets");
  DeformArguments args;
  AddDeformCommand(app, args);
  DragCommandArguments drag_args;
  auto* drag = AddDragCommand(app, drag_args);
  std::string hierarchy_out;
  auto* hierarchy = AddHierarchyCommand(app, args, hierarchy_out);
  std::string handles_scenario, handles_out;
  auto* handles = AddHandlesCommand(app, handles_scenario, handles_out);
  ScenarioCommandArguments scenario_args;
  auto* scenario = AddScenarioCommand(app, scenario_args);
  std::string status_dir;
  auto* status = AddStatusCommand(app, status_dir);
  RunArguments run_args;
  auto* run = AddRunCommand(app, run_args);
  ReportArguments report_args;
  auto* report = AddReportCommand(app, report_args);
  ViewArguments view_args;
  auto* view = AddViewCommand(app, view_args);
  RegisterCommandArguments register_args;
  auto* register_command = AddRegisterCommand(app, register_args);
  KnownAnswerCommandArguments known_answer_args;
  auto* known_answer = AddKnownAnswerCommand(app, known_answer_args);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error);
  }
  try {
    if (*list) return ListPieces(list_kind);
    if (*hierarchy) return WriteHierarchy(args, hierarchy_out);
    if (*handles) {
      RefuseMeshAsScenario(handles_scenario);
      return HandlesCommand(handles_scenario, handles_out);
    }
    if (*scenario) return ScenarioCommand(scenario_args);
    if (*status) return StatusCommand(status_dir);
    if (*run) return RunSweep(run_args);
    if (*report) return Report(report_args);
    if (*drag) return RunDragCommand(drag_args);
    if (*view) return RunViewCommand(view_args);
    if (*register_command) return RunRegisterCommand(register_args);
    if (*known_answer) return KnownAnswerCommand(known_answer_args);
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
