// SPDX-License-Identifier: MIT
//
// The sweep runner behind `harap run`. Decisions:
//   - Every run is its own `harap deform` process: a crash, an abort inside a library or an
//     out-of-memory kill costs one run, not the sweep; the peak memory in each report is that
//     run's alone; a timeout can kill it. Threads per run are passed with --threads (and to
//     OpenBLAS/OpenMP through the environment unless the user set those), so `--jobs K` runs
//     K processes without oversubscribing the cores.
//   - Files are written to a temporary name and renamed, so a report on disk is always
//     complete: resume only has to check that runs/ID.json exists (and, unless
//     --retry-failed, regardless of its status).
//   - Each shard writes its own CSV; `harap report` merges all reports into results.csv. Shards
//     may share DIR (one file system) or be copied together afterwards.
//   - Temporary names carry PID@HOST: shards on several hosts of a cluster share one folder on a
//     network file system, where a PID alone names different processes on different hosts. A
//     shard removes only its own host's temporaries whose process is gone.
#include "runner/runner.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <fnmatch.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <thread>

#include "api/known_answer.h"
#include "framework/error.h"
#include "io/scenario.h"
#include "runner/process.h"
#include "runner/run_folder.h"

namespace harap {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace runner_internal;
using Clock = std::chrono::steady_clock;

// "PID@HOST": what makes a temporary file's name unique among the processes of every host
// sharing a folder. Host names are reduced to letters, digits and '-' (no dots: the stale-file
// scan splits names at dots).
std::string HostName(const std::string& injected) {
  std::string host = injected;
  if (host.empty()) {
    char buffer[256] = {};
    host = gethostname(buffer, sizeof buffer - 1) == 0 ? buffer : "localhost";
  }
  for (char& c : host) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-') c = '_';
  }
  return host;
}

std::string TemporaryTag(const std::string& host) { return fmt::format("{}@{}", getpid(), host); }

void WriteFileAtomically(const fs::path& file, const std::string& content,
                         const std::string& tag = TemporaryTag(HostName(""))) {
  const fs::path temporary =
      file.parent_path() / fmt::format(".{}.{}.tmp", file.filename().string(), tag);
  {
    std::ofstream stream(temporary, std::ios::binary);
    stream << content;
    if (!stream) throw InputError(fmt::format("{}: cannot write", temporary.string()));
  }
  fs::rename(temporary, file);
}

// ---------------------------------------------------------------------------------------------
// results.csv

const std::vector<std::string> kReportColumns = {"status",
                                                 "optimizer",
                                                 "energy_type",
                                                 "solver",
                                                 "hierarchy",
                                                 "upsampler",
                                                 "vertices",
                                                 "faces",
                                                 "energy",
                                                 "iterations",
                                                 "total_iterations",
                                                 "converged",
                                                 "level_iterations",
                                                 "t_hierarchy",
                                                 "t_precompute",
                                                 "t_constrain",
                                                 "t_solve",
                                                 "t_total",
                                                 "repetitions",
                                                 "peak_memory_mb",
                                                 "answer_mean_error",
                                                 "answer_max_error",
                                                 "threads",
                                                 "wall_seconds",
                                                 "error"};

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"') quoted += '"';
    quoted += c == '\n' ? ' ' : c;
  }
  return quoted + "\"";
}

std::string CsvLine(const std::vector<std::string>& fields) {
  std::string line;
  for (size_t i = 0; i < fields.size(); ++i) {
    if (i > 0) line += ',';
    line += CsvField(fields[i]);
  }
  return line;
}

std::vector<std::string> CsvHeader(const std::vector<std::string>& grid_keys) {
  std::vector<std::string> header = {"index", "id", "scenario", "variant", "label"};
  header.insert(header.end(), grid_keys.begin(), grid_keys.end());
  header.insert(header.end(), kReportColumns.begin(), kReportColumns.end());
  return header;
}

std::string Number(const json& value, const char* format = "{:.17g}") {
  if (value.is_null()) return "";
  if (value.is_number_integer()) return fmt::format("{}", value.get<long long>());
  if (value.is_number()) return fmt::format(fmt::runtime(format), value.get<double>());
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_string()) return value.get<std::string>();
  return value.dump();
}

std::string CsvRow(const json& report, const std::vector<std::string>& grid_keys) {
  const json& run = report["run"];
  auto get = [](const json& object, const char* key) {
    return object.contains(key) ? object[key] : json();
  };
  std::vector<std::string> fields = {Number(run["index"]), Number(run["id"]),
                                     Number(run["scenario"]), Number(get(run, "variant")),
                                     Number(get(run, "label"))};
  for (const std::string& key : grid_keys) {
    fields.push_back(run["parameters"].contains(key) ? Number(run["parameters"][key]) : "");
  }
  const json timings = get(report, "timings");
  std::string level_iterations;
  if (report.contains("levels")) {
    for (const json& level : report["levels"]) {
      if (!level_iterations.empty()) level_iterations += " ";
      level_iterations += Number(level["iterations"]);
    }
  }
  const json memory = get(report, "peak_memory_bytes");
  // A registration's report (`harap register`) names some of these differently.
  const bool registration = get(report, "command") == "register";
  const json mesh = registration ? get(report, "source") : get(report, "mesh");
  const json answer = get(report, "answer");
  fields.insert(
      fields.end(),
      {Number(run["status"]),
       Number(get(report, registration ? "mode" : "optimizer")),
       Number(get(report, "energy_type")),
       Number(get(report, "solver")),
       Number(get(report, "hierarchy")),
       Number(get(report, "upsampler")),
       mesh.is_null() ? "" : Number(get(mesh, "vertices")),
       mesh.is_null() ? "" : Number(get(mesh, registration ? "triangles" : "faces")),
       Number(get(report, registration ? "arap_energy" : "energy")),
       Number(get(report, "iterations")),
       Number(get(report, registration ? "iterations" : "total_iterations")),
       Number(registration ? json(get(report, "status") == "converged") : get(report, "converged")),
       level_iterations,
       timings.is_null() ? "" : Number(timings["hierarchy"], "{:.4f}"),
       timings.is_null() ? "" : Number(timings["precompute"], "{:.4f}"),
       timings.is_null() ? "" : Number(timings["constrain"], "{:.4f}"),
       timings.is_null() ? "" : Number(timings["solve"], "{:.4f}"),
       timings.is_null() ? "" : Number(timings["total"], "{:.4f}"),
       report.contains("repetitions") ? Number(report["repetitions"]["count"]) : "",
       memory.is_null() ? "" : fmt::format("{:.1f}", memory.get<double>() / (1024.0 * 1024.0)),
       answer.is_null() ? "" : Number(answer["mean_error_relative"]),
       answer.is_null() ? "" : Number(answer["max_error_relative"]),
       Number(get(run, "threads")),
       Number(get(run, "wall_seconds"), "{:.3f}"),
       Number(get(run, "error"))});
  return CsvLine(fields);
}

// A finished run in one line: its energy and time; a registration's errors against the answer.
std::string RunDetail(const json& report) {
  const double seconds = report["timings"]["total"].get<double>();
  if (report.value("command", "") != "register") {
    return fmt::format("E = {:.6g}, {:.2f} s", report["energy"].get<double>(), seconds);
  }
  if (!report.contains("answer")) return fmt::format("{:.2f} s", seconds);
  return fmt::format("error mean {:.3g}%, max {:.3g}% of the diagonal, {:.2f} s",
                     100.0 * report["answer"]["mean_error_relative"].get<double>(),
                     100.0 * report["answer"]["max_error_relative"].get<double>(), seconds);
}

std::string CsvText(const std::vector<std::string>& grid_keys,
                    const std::map<int, std::string>& rows) {
  std::string text = CsvLine(CsvHeader(grid_keys)) + "\n";
  for (const auto& [index, row] : rows) text += row + "\n";
  return text;
}

// ---------------------------------------------------------------------------------------------
// The plan file

json PlanJson(const Experiment& experiment) {
  json plan = json::parse(experiment.report_json);
  plan["config_file"] = experiment.file.string();
  plan["grid_keys"] = experiment.grid_keys;
  plan["settings"] = {{"threads", experiment.settings.threads},
                      {"save_mesh", experiment.settings.save_mesh},
                      {"timeout", experiment.settings.timeout},
                      {"min_time", experiment.settings.min_time}};
  json scenarios = json::array();
  for (const ExperimentScenario& scenario : experiment.scenarios) {
    scenarios.push_back({{"name", scenario.name},
                         {"file", scenario.file.string()},
                         {"mesh", scenario.mesh.string()},
                         {"templated", scenario.templated()}});
  }
  plan["scenarios"] = scenarios;
  json runs = json::array();
  for (const ExperimentRun& run : experiment.runs) {
    json parameters = json::object();
    for (const auto& [key, literal] : run.parameters) parameters[key] = literal;
    runs.push_back({{"index", run.index},
                    {"id", run.id},
                    {"scenario", experiment.scenarios[run.scenario].name},
                    {"variant", run.variant},
                    {"label", run.label},
                    {"parameters", parameters},
                    {"config", run.config_toml}});
  }
  plan["runs"] = runs;
  return plan;
}

// Parameters for the CSV: TOML literals shown without string quotes.
json DisplayParameters(const ExperimentRun& run) {
  json parameters = json::object();
  for (const auto& [key, literal] : run.parameters) {
    std::string text = literal;
    if (text.size() >= 2 && (text.front() == '"' || text.front() == '\'') &&
        text.back() == text.front()) {
      text = text.substr(1, text.size() - 2);
    }
    parameters[key] = text;
  }
  return parameters;
}

// ---------------------------------------------------------------------------------------------
// One run in a child process

// The line of a failed run's output that says why.
std::string ErrorFromLog(const fs::path& log_file) {
  std::istringstream lines(ReadText(log_file));
  std::string line, last, error;
  while (std::getline(lines, line)) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    last = line;
    if (line.find("error:") != std::string::npos) error = line;
  }
  std::string message = error.empty() ? last : error;
  if (message.size() > 600) message = message.substr(0, 600) + "...";
  return message;
}

// Bounding-box extent of a scenario's mesh, read the way `harap deform` reads it.
void MeshExtent(const fs::path& mesh, double extent[3]) {
  const Scenario scenario = ParseScenario(fmt::format("mesh = \"{}\"\n", mesh.generic_string()),
                                          mesh.string(), mesh.parent_path());
  const auto& vertices = scenario.mesh.vertices;
  for (int d = 0; d < 3; ++d) {
    extent[d] = vertices.rows() ? vertices.col(d).maxCoeff() - vertices.col(d).minCoeff() : 0.0;
  }
}

// experiment.json (the plan) and config.toml (the config as written) in `dir`.
void WriteExperimentPlan(const Experiment& experiment, const fs::path& dir,
                         const std::string& tag) {
  WriteFileAtomically(dir / "experiment.json", PlanJson(experiment).dump(1) + "\n", tag);
  WriteFileAtomically(
      dir / "config.toml",
      fmt::format("# {} as run by harap run\n{}", experiment.file.string(), experiment.source_text),
      tag);
}

// ---------------------------------------------------------------------------------------------

class Sweep {
 public:
  Sweep(const Experiment& experiment, const RunnerOptions& options)
      : experiment_(experiment), options_(options), dir_(options.out_dir) {
    threads_ = options.threads > 0 ? options.threads : experiment.settings.threads;
    if (threads_ <= 0) {
      threads_ = std::max(
          1, static_cast<int>(std::thread::hardware_concurrency()) / std::max(1, options.jobs));
    }
    csv_file_ = dir_ / fmt::format("results{}.csv", options.shard.Suffix());
    host_ = HostName(options.host);
    tag_ = TemporaryTag(host_);
  }

  SweepSummary Run() {
    for (const char* sub : {"runs", "scenarios", "meshes", "cases"}) {
      fs::create_directories(dir_ / sub);
    }
    WriteExperimentPlan(experiment_, dir_, tag_);

    RemoveStaleTemporaries();
    if (options_.observer) {
      for (const std::string& warning : experiment_.warnings) options_.observer->Warning(warning);
    }
    SweepSummary summary;
    summary.planned = static_cast<int>(experiment_.runs.size());
    std::vector<const ExperimentRun*> pending;
    for (const ExperimentRun& run : experiment_.runs) {
      if (!options_.shard.Contains(run.index) || !Selected(run)) continue;
      ++summary.in_shard;
      const fs::path report = dir_ / "runs" / (run.id + ".json");
      if (fs::exists(report)) {
        try {
          const json existing = json::parse(ReadText(report));
          const bool ok = existing["run"]["status"] == "ok";
          if (ok || !options_.retry_failed) {
            rows_[run.index] = CsvRow(existing, experiment_.grid_keys);
            ++summary.skipped;
            continue;
          }
        } catch (const json::exception&) {
          // Unreadable: run it again.
        }
      }
      pending.push_back(&run);
    }
    WriteCsv();

    SweepObserver* observer = options_.observer;
    if (observer) observer->SweepStarted(summary.in_shard, summary.skipped);
    std::atomic<size_t> next{0};
    std::atomic<int> succeeded{0}, failed{0};
    auto worker = [&] {
      for (size_t k; (k = next++) < pending.size();) {
        const ExperimentRun& run = *pending[k];
        if (observer) observer->RunStarted(RunName(run));
        const json report = Execute(run);
        const std::string status = report["run"]["status"];
        (status == "ok" ? succeeded : failed)++;
        {
          std::lock_guard lock(rows_mutex_);
          rows_[run.index] = CsvRow(report, experiment_.grid_keys);
          WriteCsv();
        }
        const std::string detail =
            status == "ok" ? RunDetail(report) : report["run"]["error"].get<std::string>();
        if (observer) observer->RunFinished(RunName(run), status, detail);
      }
    };
    std::vector<std::thread> workers;
    const int jobs = std::max(1, std::min<int>(options_.jobs, static_cast<int>(pending.size())));
    for (int j = 0; j < jobs; ++j) workers.emplace_back(worker);
    for (auto& thread : workers) thread.join();
    summary.succeeded = succeeded;
    summary.failed = failed;
    return summary;
  }

 private:
  // "scenario | label" (variant and grid values) for progress lines; the id when unlabelled.
  std::string RunName(const ExperimentRun& run) const {
    const std::string& scenario = experiment_.scenarios[run.scenario].name;
    return run.label.empty() ? fmt::format("{} ({})", scenario, run.id)
                             : fmt::format("{} | {}", scenario, run.label);
  }

  // Temporary files of sweeps that were killed (SIGKILL, power loss) before they could rename
  // or remove them: ".NAME.PID@HOST.*" in runs/, meshes/, scenarios/, cases/ (folders) and the
  // folder itself,
  // written on this host by a process that is no longer running. Files of live processes and of
  // other hosts (whose PIDs cannot be checked from here) stay.
  void RemoveStaleTemporaries() const {
    for (const fs::path& folder :
         {dir_, dir_ / "runs", dir_ / "meshes", dir_ / "scenarios", dir_ / "cases"}) {
      std::error_code error;
      for (const auto& entry : fs::directory_iterator(folder, error)) {
        const std::string name = entry.path().filename().string();
        if (name.size() < 2 || name[0] != '.') continue;
        // The tag is the last part between dots of the form DIGITS@HOST.
        long pid = 0;
        std::string host;
        size_t start = 1;
        while (start < name.size()) {
          const size_t end = std::min(name.find('.', start), name.size());
          const std::string part = name.substr(start, end - start);
          const size_t at = part.find('@');
          if (at != std::string::npos && at > 0 && at < 10 &&
              part.find_first_not_of("0123456789") == at) {
            pid = std::stol(part.substr(0, at));
            host = part.substr(at + 1);
          }
          start = end + 1;
        }
        if (pid <= 0 || host != host_ || pid == getpid()) continue;
        if (kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM) continue;  // alive
        fs::remove_all(entry.path(), error);
      }
    }
  }

  bool Selected(const ExperimentRun& run) const {
    const std::string& name = experiment_.scenarios[run.scenario].name;
    const auto& patterns = options_.scenario_filter;
    return patterns.empty() || std::any_of(patterns.begin(), patterns.end(), [&](const auto& p) {
             return fnmatch(p.c_str(), name.c_str(), 0) == 0;
           });
  }

  void WriteCsv() { WriteFileAtomically(csv_file_, CsvText(experiment_.grid_keys, rows_), tag_); }

  // The scenario file of a run (generated from the template on first use).
  fs::path ScenarioFile(const ExperimentScenario& scenario) {
    if (!scenario.templated()) return scenario.file;
    const fs::path file = dir_ / "scenarios" / (scenario.name + ".toml");
    std::lock_guard lock(scenario_mutex_);
    if (!fs::exists(file) && scenario.generated) {
      // A mesh that cannot be read or cannot hold handles throws: the run fails with the reason.
      WriteFileAtomically(file,
                          GenerateScenarioForFile(scenario.mesh, scenario.mesh.generic_string(),
                                                  scenario.generator),
                          tag_);
    } else if (!fs::exists(file)) {
      double extent[3] = {1.0, 1.0, 1.0};
      if (scenario.handles.axis == "longest" || scenario.handles.bend_axis == "auto") {
        MeshExtent(scenario.mesh, extent);
      }
      WriteFileAtomically(file, TemplateScenarioToml(scenario, extent), tag_);
    }
    return file;
  }

  // Why a run's child process failed: the timeout, the signal, or the error its log ends with.
  std::string ChildError(const ProcessResult& child, const fs::path& log_file) const {
    std::string error = ErrorFromLog(log_file);
    if (child.timed_out) {
      error = fmt::format("killed after the timeout of {} s", experiment_.settings.timeout);
    } else if (child.signal) {
      error = fmt::format("killed by signal {} ({}){}", child.signal, strsignal(child.signal),
                          error.empty() ? "" : ": " + error);
    } else if (error.empty()) {
      error = fmt::format("exit code {} without a message", child.exit_code);
    }
    return error;
  }

  // The files of a registration run's known-answer case (api/known_answer.h), made on first
  // use by `harap known-answer` into a temporary folder renamed when complete, so that a killed
  // child or a shard on another host never leaves a partial case under the final name. Throws
  // InputError with the child's message when it fails.
  KnownAnswerFiles KnownAnswerCase(const ExperimentScenario& scenario) {
    const fs::path folder = dir_ / "cases" / scenario.name;
    std::lock_guard lock(case_mutex_);
    if (const std::optional<KnownAnswerFiles> files = KnownAnswerFiles::Find(folder)) {
      return *files;
    }
    const fs::path temporary = dir_ / "cases" / fmt::format(".{}.{}", scenario.name, tag_);
    const fs::path log = dir_ / "cases" / (scenario.name + ".log");
    const KnownAnswerOptions& settings = experiment_.known_answers.options;
    const std::vector<std::string> arguments = {options_.executable.string(),
                                                "known-answer",
                                                ScenarioFile(scenario).string(),
                                                "--target",
                                                scenario.known_answer_target,
                                                "--out-dir",
                                                temporary.string(),
                                                "--points-per-vertex",
                                                fmt::format("{}", settings.points_per_vertex),
                                                "--removed",
                                                fmt::format("{}", settings.damage.removed),
                                                "--outliers",
                                                fmt::format("{}", settings.damage.outliers),
                                                "--seed",
                                                std::to_string(settings.seed),
                                                "--threads",
                                                std::to_string(threads_),
                                                "--quiet"};
    const ProcessResult child = RunProcess(arguments, ChildProcessOptions(log));
    std::error_code ignore;
    if (!child.started) {
      throw InputError(fmt::format("cannot start {}", options_.executable.string()));
    }
    if (child.exit_code != 0 || child.timed_out || child.signal) {
      fs::remove_all(temporary, ignore);
      throw InputError(
          fmt::format("making the known-answer case failed: {}", ChildError(child, log)));
    }
    fs::remove(log, ignore);
    // Another host may have made the same (deterministic) case meanwhile: keep the first.
    fs::rename(temporary, folder, ignore);
    fs::remove_all(temporary, ignore);
    const std::optional<KnownAnswerFiles> files = KnownAnswerFiles::Find(folder);
    if (!files) {
      throw InputError(fmt::format("{}: the known-answer case was not written", folder.string()));
    }
    return *files;
  }

  // How every child runs: its output in `log`, the run timeout, killed with this process, and
  // OpenBLAS/OpenMP held to the run's threads unless the user set them.
  ProcessOptions ChildProcessOptions(const fs::path& log) const {
    ProcessOptions process;
    process.output_file = log;
    process.timeout = experiment_.settings.timeout;
    process.die_with_parent = true;
    process.default_environment = {fmt::format("OPENBLAS_NUM_THREADS={}", threads_),
                                   fmt::format("OMP_NUM_THREADS={}", threads_)};
    return process;
  }

  // The command line of a run's child: `harap deform SCENARIO` or, for a registration case
  // (`known`), `harap register SOURCE TARGET --answer ANSWER`, with the run's config.
  std::vector<std::string> RunArguments(const ExperimentScenario& scenario,
                                        const std::optional<KnownAnswerFiles>& known,
                                        const fs::path& config_file, const fs::path& report_file) {
    std::vector<std::string> arguments = {options_.executable.string(), experiment_.command()};
    if (known) {
      arguments.insert(arguments.end(), {known->source.string(), known->target.string(), "--answer",
                                         known->answer.string()});
    } else {
      arguments.insert(arguments.end(), {ScenarioFile(scenario).string(), "--trace"});
      if (experiment_.settings.min_time > 0) {
        arguments.insert(arguments.end(),
                         {"--min-time", fmt::format("{}", experiment_.settings.min_time)});
      }
    }
    arguments.insert(arguments.end(),
                     {"--config", config_file.string(), "--report", report_file.string(),
                      "--threads", std::to_string(threads_), "--quiet"});
    return arguments;
  }

  json Execute(const ExperimentRun& run) {
    const ExperimentScenario& scenario = experiment_.scenarios[run.scenario];
    const fs::path runs = dir_ / "runs";
    const fs::path report_file = runs / (run.id + ".json");
    const fs::path temporary_report = runs / fmt::format(".{}.{}.report", run.id, tag_);
    const fs::path config_file = runs / (run.id + ".config.toml");
    const fs::path log_file = runs / (run.id + ".log");
    json info = {{"index", run.index},
                 {"id", run.id},
                 {"experiment", experiment_.name},
                 {"scenario", scenario.name},
                 {"variant", run.variant},
                 {"label", run.label},
                 {"parameters", DisplayParameters(run)},
                 {"threads", threads_},
                 {"jobs", options_.jobs}};
    json report = json::object();
    const auto start = Clock::now();
    try {
      WriteFileAtomically(config_file, run.config_toml);
      // A registration run's case (made on first use); it has no handles.
      const bool registration = !scenario.known_answer_target.empty();
      const std::optional<KnownAnswerFiles> known =
          registration ? std::optional(KnownAnswerCase(scenario)) : std::nullopt;
      std::vector<std::string> arguments =
          RunArguments(scenario, known, config_file, temporary_report);
      const fs::path mesh_file = dir_ / "meshes" / (run.id + ".ply");
      // The child writes the mesh under a temporary name; renamed when the run succeeded, so a
      // killed run leaves no partial mesh under the final name.
      const fs::path mesh_temporary = dir_ / "meshes" / fmt::format(".{}.{}.ply", run.id, tag_);
      const fs::path rest_file = dir_ / "meshes" / (scenario.name + ".rest.ply");
      const fs::path handles_file = dir_ / "meshes" / (scenario.name + ".handles.json");
      const fs::path rest_temporary =
          dir_ / "meshes" / fmt::format(".{}.{}.rest.ply", run.id, tag_);
      const fs::path handles_temporary =
          dir_ / "meshes" / fmt::format(".{}.{}.handles.json", run.id, tag_);
      const bool write_rest =
          experiment_.settings.save_mesh && !registration && !fs::exists(rest_file);
      if (experiment_.settings.save_mesh) {
        arguments.insert(arguments.end(), {"--out", mesh_temporary.string()});
        info["mesh"] = "meshes/" + mesh_file.filename().string();
        info["rest_mesh"] = known ? fs::relative(known->source, dir_).generic_string()
                                  : "meshes/" + rest_file.filename().string();
        if (!registration) info["handles"] = "meshes/" + handles_file.filename().string();
      }
      if (write_rest) {
        arguments.insert(arguments.end(), {"--out-rest", rest_temporary.string(), "--out-handles",
                                           handles_temporary.string()});
      }
      info["command"] = fmt::format("{}", fmt::join(arguments, " "));

      const ProcessResult child = RunProcess(arguments, ChildProcessOptions(log_file));
      if (!child.started) {
        throw InputError(fmt::format("cannot start {}", options_.executable.string()));
      }
      if (child.exit_code == 0 && fs::exists(temporary_report)) {
        report = json::parse(ReadText(temporary_report));
        info["status"] = "ok";
        fs::remove(log_file);
        std::error_code ignore;
        if (experiment_.settings.save_mesh) fs::rename(mesh_temporary, mesh_file, ignore);
        if (write_rest) {
          fs::rename(rest_temporary, rest_file, ignore);
          fs::rename(handles_temporary, handles_file, ignore);
        }
      } else {
        info["status"] = child.timed_out ? "timeout" : "failed";
        info["exit_code"] = child.exit_code;
        if (child.signal) info["signal"] = child.signal;
        info["error"] = ChildError(child, log_file);
        info["log"] = "runs/" + log_file.filename().string();
      }
    } catch (const std::exception& error) {
      info["status"] = "failed";
      info["error"] = error.what();
    }
    std::error_code ignore;
    fs::remove(temporary_report, ignore);
    for (const char* suffix : {"ply", "rest.ply", "handles.json"}) {  // of a failed run
      fs::remove(dir_ / "meshes" / fmt::format(".{}.{}.{}", run.id, tag_, suffix), ignore);
    }
    info["wall_seconds"] = std::chrono::duration<double>(Clock::now() - start).count();
    report["run"] = info;
    WriteFileAtomically(report_file, report.dump(1) + "\n", tag_);
    return report;
  }

  const Experiment& experiment_;
  const RunnerOptions& options_;
  fs::path dir_;
  fs::path csv_file_;
  std::string host_;  ///< this host's name as it appears in temporary names
  std::string tag_;   ///< PID@HOST of this process, in its temporary names
  int threads_ = 1;
  std::mutex rows_mutex_, scenario_mutex_, case_mutex_;
  std::map<int, std::string> rows_;
};

}  // namespace

SweepSummary RunExperiment(const Experiment& experiment, const RunnerOptions& options) {
  if (options.executable.empty() || !fs::exists(options.executable)) {
    throw InputError(fmt::format("harap executable '{}' not found", options.executable.string()));
  }
  return Sweep(experiment, options).Run();
}

void WriteExperimentPlan(const Experiment& experiment, const fs::path& dir) {
  WriteExperimentPlan(experiment, dir, TemporaryTag(HostName("")));
}

MergeSummary MergeResults(const fs::path& dir) {
  const json plan = ReadPlan(dir);
  const std::vector<std::string> grid_keys = plan["grid_keys"];
  MergeSummary summary;
  std::map<int, std::string> rows;
  for (const json& run : plan["runs"]) {
    ++summary.planned;
    const fs::path report_file = dir / "runs" / (run["id"].get<std::string>() + ".json");
    if (!fs::exists(report_file)) {
      ++summary.missing;
      continue;
    }
    const json report = ReadJson(report_file);
    (report["run"]["status"] == "ok" ? summary.succeeded : summary.failed)++;
    rows[run["index"].get<int>()] = CsvRow(report, grid_keys);
  }
  WriteFileAtomically(dir / "results.csv", CsvText(grid_keys, rows));
  return summary;
}

bool IsTimingColumn(const std::string& column) {
  return column.starts_with("t_") || column == "wall_seconds" || column == "peak_memory_mb" ||
         column == "repetitions";
}

}  // namespace harap
