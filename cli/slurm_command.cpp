// SPDX-License-Identifier: MIT
#include "cli/slurm_command.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <filesystem>

#include "framework/error.h"
#include "runner/experiment.h"
#include "runner/slurm.h"

namespace harap {

void AddSlurmOptions(CLI::App& run, SlurmArguments& args) {
  run.add_flag("--slurm", args.slurm,
               "submit the sweep to Slurm as a job array (one task per shard) with a dependent "
               "harap report job; again: only the shards with runs missing or failed");
  run.add_option("--tasks", args.tasks,
                 "--slurm: array tasks (= shards; default [slurm] tasks, else one per run, at "
                 "most 100); fixed once submitted");
  run.add_option("--partition", args.partition, "--slurm: partition (default [slurm] partition)");
  run.add_option("--time", args.time, "--slurm: time limit per task, e.g. 2:00:00");
  run.add_option("--cpus-per-task", args.cpus_per_task,
                 "--slurm: CPUs per task, the runs' threads (default [slurm] cpus_per_task, 1)");
  run.add_option("--mem", args.mem, "--slurm: memory per task, e.g. 8G");
  run.add_option("--throttle", args.throttle, "--slurm: at most K tasks at once (--array=...%K)");
  run.add_option("--sbatch-flag", args.sbatch_flags,
                 "--slurm: a further sbatch option, e.g. --sbatch-flag=--qos=long (repeatable)");
}

int SubmitSweepToSlurm(const std::string& config, const std::string& out,
                       const SlurmArguments& args) {
  const Experiment experiment = LoadExperiment(config);
  SlurmSubmitOptions options;
  options.settings = experiment.slurm;
  ExperimentSlurmSettings& settings = options.settings;
  if (args.tasks < 0) throw ConfigError("--tasks must be at least 1");
  if (args.tasks > 0) settings.tasks = args.tasks;
  if (!args.partition.empty()) settings.partition = args.partition;
  if (!args.time.empty()) settings.time = args.time;
  if (!args.mem.empty()) settings.mem = args.mem;
  if (args.cpus_per_task < 0) throw ConfigError("--cpus-per-task must be at least 1");
  if (args.cpus_per_task > 0) settings.cpus_per_task = args.cpus_per_task;
  if (args.throttle >= 0) settings.throttle = args.throttle;
  settings.sbatch_flags.insert(settings.sbatch_flags.end(), args.sbatch_flags.begin(),
                               args.sbatch_flags.end());
  options.config = config;
  options.out_dir =
      out.empty() ? std::filesystem::path("results") / experiment.name : std::filesystem::path(out);
  options.executable = std::filesystem::read_symlink("/proc/self/exe");
  const SlurmSubmission submission = SubmitToSlurm(experiment, options);
  const std::string dir = std::filesystem::absolute(options.out_dir).lexically_normal().string();
  if (submission.shards.empty()) {
    fmt::print("{}: every run of the {} shards is done; nothing submitted (harap report {})\n", dir,
               submission.tasks, dir);
    return 0;
  }
  fmt::print("submitted array job {} ({} of {} shards: {}) and report job {} (afterany:{})\n",
             submission.array_job, submission.shards.size(), submission.tasks,
             fmt::join(submission.shards, ","), submission.report_job, submission.array_job);
  fmt::print("script {}; logs in {}/slurm/logs; progress: harap status {}\n",
             submission.script.string(), dir, dir);
  return 0;
}

CLI::App* AddStatusCommand(CLI::App& app, std::string& dir) {
  auto* status = app.add_subcommand("status",
                                    "runs done, failed (with the reason) and missing per shard "
                                    "of a run folder, and its Slurm jobs' states");
  status->add_option("dir", dir, "output folder of harap run")->required();
  return status;
}

int StatusCommand(const std::string& dir) {
  fmt::print("{}", FormatStatus(dir, CollectStatus(dir)));
  return 0;
}

}  // namespace harap
