// SPDX-License-Identifier: MIT
//
// Decisions:
//   - The array size N is written into the script and recorded with the folder: a task finds its
//     shard from SLURM_ARRAY_TASK_ID alone. SLURM_ARRAY_TASK_COUNT cannot be used, as a
//     resubmission of some tasks (--array=7) has a different count.
//   - Resubmission is decided from the run reports on disk, not from Slurm's records (job
//     accounting is often off, and finished jobs leave squeue after MinJobAge): a shard is
//     submitted again when one of its runs has no report or a failed one, and its task retries
//     the failed runs.
//   - The report job depends with afterany, not afterok: a cancelled or timed-out task must not
//     keep the runs that did finish out of results.csv.
//   - Jobs are read with squeue (no accounting needed); sbatch --wait is not used (it polls at
//     2, 8, 32 s).
#include "runner/slurm.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "framework/error.h"
#include "runner/process.h"
#include "runner/run_folder.h"
#include "runner/runner.h"

namespace harap {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace runner_internal;

bool OnPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::stringstream folders(path ? path : "");
  for (std::string folder; std::getline(folders, folder, ':');) {
    if (!folder.empty() && access((fs::path(folder) / program).c_str(), X_OK) == 0) return true;
  }
  return false;
}

// Runs a command and returns {exit ok, its output (stdout and stderr)}.
std::pair<bool, std::string> Capture(const std::vector<std::string>& command) {
  const fs::path output =
      fs::temp_directory_path() / fmt::format("harap-slurm-{}-{}.out", getpid(), command[0]);
  ProcessOptions options;
  options.output_file = output;
  const ProcessResult result = RunProcess(command, options);
  std::string text = ReadText(output);
  std::error_code ignore;
  fs::remove(output, ignore);
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  return {result.ok(), text};
}

// A word for a bash script, single-quoted.
std::string Quoted(const std::string& word) {
  std::string quoted = "'";
  for (const char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

const char* kInstallAdvice =
    "install Slurm's client (Debian: sudo apt-get install slurm-client) on a machine of the "
    "cluster; for a one-machine cluster also slurmctld slurmd munge, started by "
    ".ci/slurm-local start DIR (docs/experiments.md). Other schedulers: run the shards with "
    "--shard I/N";

json ReadSubmissions(const fs::path& dir) {
  const fs::path file = dir / "slurm" / "submissions.json";
  return fs::exists(file) ? ReadJson(file) : json();
}

// Per planned run of the folder's experiment.json: {index, id, name, status, error}.
struct PlannedRun {
  int index = 0;
  std::string id, name, status, error;  ///< status: "ok", "failed", "timeout" or "missing"
};

std::vector<PlannedRun> ReadRuns(const fs::path& dir) {
  const json plan = ReadPlan(dir);
  std::vector<PlannedRun> runs;
  for (const json& entry : plan["runs"]) {
    PlannedRun run;
    run.index = entry["index"];
    run.id = entry["id"];
    const std::string label = entry["label"];
    run.name = label.empty() ? entry["scenario"].get<std::string>()
                             : fmt::format("{} | {}", entry["scenario"].get<std::string>(), label);
    run.status = "missing";
    const fs::path report = dir / "runs" / (run.id + ".json");
    if (fs::exists(report)) {
      try {
        const json info = json::parse(ReadText(report))["run"];
        run.status = info["status"];
        if (info.contains("error")) run.error = info["error"];
      } catch (const json::exception&) {
        run.status = "missing";  // unreadable: run again, as the runner does
      }
    }
    runs.push_back(std::move(run));
  }
  return runs;
}

// The shard count of a folder: as submitted to Slurm, else from results-shard-I-of-N.csv.
int ShardCount(const fs::path& dir, const json& submissions) {
  if (submissions.is_object()) return submissions["tasks"];
  int count = 1;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(dir, error)) {
    const std::string name = entry.path().filename().string();
    int index = 0, total = 0;
    if (std::sscanf(name.c_str(), "results-shard-%d-of-%d.csv", &index, &total) == 2) {
      count = std::max(count, total);
    }
  }
  return count;
}

// squeue's lines for the jobs of the last submission ("" when none is queued); nullopt when
// squeue cannot be run.
std::optional<std::vector<std::string>> QueuedJobs(const json& submissions) {
  if (!submissions.is_object() || submissions["submissions"].empty())
    return std::vector<std::string>{};
  if (!OnPath("squeue")) return std::nullopt;
  const json& last = submissions["submissions"].back();
  const std::string ids = fmt::format("{},{}", last["array_job"].get<std::string>(),
                                      last["report_job"].get<std::string>());
  const auto [ok, output] = Capture({"squeue", "-h", "-r", "-j", ids, "-o", "%i %j %T %R"});
  std::vector<std::string> lines;
  if (!ok) {
    // squeue fails for job ids it no longer knows: none of them is queued.
    if (output.find("Invalid job id") != std::string::npos) return lines;
    return std::nullopt;
  }
  std::stringstream stream(output);
  for (std::string line; std::getline(stream, line);) {
    if (!line.empty()) lines.push_back(line);
  }
  return lines;
}

std::string ShellScriptHeader(const std::string& job_name, const fs::path& log,
                              const ExperimentSlurmSettings& settings, int cpus) {
  std::string text = fmt::format(
      "#!/bin/bash\n"
      "# Written by harap run --slurm; submitted again (for the shards with runs missing or\n"
      "# failed) by the same command. Paths are absolute: the job runs from any folder.\n"
      "#SBATCH --job-name={}\n#SBATCH --output={}\n#SBATCH --cpus-per-task={}\n",
      job_name, log.string(), cpus);
  if (!settings.partition.empty())
    text += fmt::format("#SBATCH --partition={}\n", settings.partition);
  if (!settings.time.empty()) text += fmt::format("#SBATCH --time={}\n", settings.time);
  if (!settings.mem.empty()) text += fmt::format("#SBATCH --mem={}\n", settings.mem);
  for (const std::string& flag : settings.sbatch_flags) text += fmt::format("#SBATCH {}\n", flag);
  return text;
}

std::string Submit(const std::vector<std::string>& command) {
  const auto [ok, output] = Capture(command);
  if (!ok) {
    // Without slurm.conf (or SLURM_CONF) the client looks for the controller in DNS and fails.
    const bool no_cluster = output.find("DNS SRV") != std::string::npos;
    throw InputError(fmt::format("{} refused the job: {}{}", fmt::join(command, " "), output,
                                 no_cluster ? fmt::format("\n(no Slurm cluster is configured on "
                                                          "this machine: {})",
                                                          kInstallAdvice)
                                            : ""));
  }
  // --parsable prints "ID" or "ID;CLUSTER".
  const std::string id = output.substr(0, output.find(';'));
  if (id.empty() || id.find_first_not_of("0123456789") != std::string::npos) {
    throw InputError(fmt::format("{}: unexpected answer '{}'", fmt::join(command, " "), output));
  }
  return id;
}

std::string Now() {
  const std::time_t now = std::time(nullptr);
  char text[32] = {};
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  return text;
}

}  // namespace

SlurmSubmission SubmitToSlurm(const Experiment& experiment, const SlurmSubmitOptions& options) {
  if (!OnPath("sbatch")) {
    throw InputError(fmt::format("--slurm: Slurm's sbatch is not on PATH; {}", kInstallAdvice));
  }
  const fs::path dir = fs::absolute(options.out_dir).lexically_normal();
  const fs::path slurm = dir / "slurm";
  fs::create_directories(slurm / "logs");
  fs::create_directories(dir / "runs");
  json submissions = ReadSubmissions(dir);
  const ExperimentSlurmSettings& settings = options.settings;
  const int runs = static_cast<int>(experiment.runs.size());
  SlurmSubmission result;
  if (submissions.is_object()) {
    result.tasks = submissions["tasks"];
    if (settings.tasks > 0 && settings.tasks != result.tasks) {
      throw InputError(fmt::format(
          "{} was submitted with {} tasks; its shards keep that size (leave out --tasks, or use "
          "another --out)",
          dir.string(), result.tasks));
    }
    const auto queued = QueuedJobs(submissions);
    if (queued && !queued->empty()) {
      throw InputError(fmt::format(
          "jobs of {} are still queued or running ({}); wait for them (harap status {}) or "
          "cancel them (scancel) before submitting again",
          dir.string(), fmt::join(*queued, "; "), dir.string()));
    }
  } else {
    result.tasks = settings.tasks > 0 ? settings.tasks : std::min(runs, 100);
    submissions = {{"tasks", result.tasks},
                   {"config", fs::absolute(options.config).lexically_normal().string()},
                   {"submissions", json::array()}};
  }
  WriteExperimentPlan(experiment, dir);

  // The shards with a run missing or failed.
  std::set<int> shards;
  for (const PlannedRun& run : ReadRuns(dir)) {
    if (run.status != "ok") shards.insert(run.index % result.tasks);
  }
  result.shards.assign(shards.begin(), shards.end());
  if (shards.empty()) return result;

  const int cpus = std::max(1, settings.cpus_per_task);
  std::string array = fmt::format("{}", fmt::join(result.shards, ","));
  if (settings.throttle > 0) array += fmt::format("%{}", settings.throttle);
  result.script = slurm / "array.sh";
  std::string script = ShellScriptHeader(fmt::format("harap-{}", experiment.name),
                                         slurm / "logs" / "shard-%a-job-%A.log", settings, cpus);
  script += fmt::format("#SBATCH --array={}\n", array);
  script += fmt::format(
      "echo \"harap shard ${{SLURM_ARRAY_TASK_ID}}/{} (job ${{SLURM_ARRAY_JOB_ID}}_"
      "${{SLURM_ARRAY_TASK_ID}}) on $(hostname)\"\n"
      "exec {} run {} --out {} --shard \"${{SLURM_ARRAY_TASK_ID}}/{}\" --threads {} "
      "--retry-failed\n",
      result.tasks, Quoted(options.executable.string()),
      Quoted(fs::absolute(options.config).lexically_normal().string()), Quoted(dir.string()),
      result.tasks, cpus);
  std::ofstream(result.script) << script;
  const fs::path report_script = slurm / "report.sh";
  std::ofstream(report_script) << ShellScriptHeader(fmt::format("harap-{}-report", experiment.name),
                                                    slurm / "logs" / "report-job-%j.log", settings,
                                                    1)
                               << fmt::format("exec {} report {}\n",
                                              Quoted(options.executable.string()),
                                              Quoted(dir.string()));

  result.array_job = Submit({"sbatch", "--parsable", result.script.string()});
  result.report_job =
      Submit({"sbatch", "--parsable", fmt::format("--dependency=afterany:{}", result.array_job),
              report_script.string()});
  submissions["submissions"].push_back({{"array_job", result.array_job},
                                        {"report_job", result.report_job},
                                        {"shards", result.shards},
                                        {"submitted", Now()}});
  std::ofstream(slurm / "submissions.json") << submissions.dump(1) << "\n";
  return result;
}

FolderStatus CollectStatus(const fs::path& dir) {
  FolderStatus status;
  const json submissions = ReadSubmissions(dir);
  const std::vector<PlannedRun> runs = ReadRuns(dir);
  status.tasks = ShardCount(dir, submissions);
  status.shards.resize(static_cast<size_t>(status.tasks));
  for (int s = 0; s < status.tasks; ++s) status.shards[s].shard = s;
  for (const PlannedRun& run : runs) {
    ShardStatus& shard = status.shards[run.index % status.tasks];
    if (run.status == "ok") {
      ++shard.done;
    } else if (run.status == "missing") {
      ++shard.missing;
    } else {
      ++shard.failed;
      shard.failures.push_back(
          fmt::format("{} ({}): {}: {}", run.name, run.id, run.status, run.error));
    }
  }
  if (submissions.is_object()) {
    const auto queued = QueuedJobs(submissions);
    if (!queued) {
      status.jobs.push_back("Slurm's squeue is not available here: job states unknown");
    } else if (queued->empty()) {
      status.jobs.push_back("no job of the last submission is queued or running");
    } else {
      status.jobs = *queued;
    }
  }
  return status;
}

std::string FormatStatus(const fs::path& dir, const FolderStatus& status) {
  std::string text =
      fmt::format("{}: {} shard{}\n{:>7} {:>7} {:>7} {:>7}\n", dir.string(), status.tasks,
                  status.tasks == 1 ? "" : "s", "shard", "done", "failed", "missing");
  ShardStatus total;
  for (const ShardStatus& shard : status.shards) {
    if (status.tasks <= 64 || shard.failed + shard.missing > 0) {
      text += fmt::format("{:>7} {:>7} {:>7} {:>7}\n", shard.shard, shard.done, shard.failed,
                          shard.missing);
    }
    total.done += shard.done;
    total.failed += shard.failed;
    total.missing += shard.missing;
  }
  text +=
      fmt::format("{:>7} {:>7} {:>7} {:>7}\n", "total", total.done, total.failed, total.missing);
  for (const ShardStatus& shard : status.shards) {
    for (const std::string& failure : shard.failures) {
      text += fmt::format("failed in shard {}: {}\n", shard.shard, failure);
    }
  }
  if (!status.jobs.empty()) {
    text += "Slurm jobs (id name state reason):\n";
    for (const std::string& job : status.jobs) text += "  " + job + "\n";
  }
  return text;
}

}  // namespace harap
