// SPDX-License-Identifier: MIT
// Slurm as a backend of `harap run`: the job-array script (one task per shard), its submission
// with a dependent `harap report` job, resubmission of the shards with missing or failed runs,
// and the status of a run folder (`harap status`).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "runner/experiment.h"

namespace harap {

struct SlurmSubmitOptions {
  ExperimentSlurmSettings settings;  ///< the config's [slurm] table with the command line's values
  std::filesystem::path config;      ///< the experiment config
  std::filesystem::path out_dir;     ///< the run folder (shared by every task)
  std::filesystem::path executable;  ///< the harap executable the tasks run
};

struct SlurmSubmission {
  int tasks = 0;                 ///< N: array tasks = shards, fixed for the folder
  std::vector<int> shards;       ///< submitted now (empty: every run is done)
  std::string array_job;         ///< job id of the array ("" when nothing was submitted)
  std::string report_job;        ///< job id of the dependent `harap report`
  std::filesystem::path script;  ///< the array script written
};

/// Writes DIR/slurm/array.sh and DIR/slurm/report.sh (absolute paths; per-task logs in
/// DIR/slurm/logs named by shard and job id), submits the array for the shards that have runs
/// missing or failed, and `harap report DIR` with --dependency=afterany on it; records the
/// submission in DIR/slurm/submissions.json. The number of tasks is fixed at the first
/// submission (a resubmission of some shards keeps every shard's runs). Throws InputError when
/// sbatch is missing (saying how to install Slurm), when jobs of this folder are still queued,
/// or when sbatch refuses the job (with its message).
SlurmSubmission SubmitToSlurm(const Experiment& experiment, const SlurmSubmitOptions& options);

/// One shard's runs in a run folder.
struct ShardStatus {
  int shard = 0;
  int done = 0, failed = 0, missing = 0;
  std::vector<std::string> failures;  ///< "scenario | label (id): error" per failed run
};

struct FolderStatus {
  int tasks = 1;  ///< shards: as submitted to Slurm, else as the shard CSV files say
  std::vector<ShardStatus> shards;
  /// Per job of the last Slurm submission: "ID STATE REASON" from squeue, or why not known.
  std::vector<std::string> jobs;
};

/// The state of every planned run of a folder written by `harap run` (done, failed with the
/// reason, missing), per shard, and the Slurm state of its jobs when squeue is there.
FolderStatus CollectStatus(const std::filesystem::path& dir);
/// The text `harap status` prints.
std::string FormatStatus(const std::filesystem::path& dir, const FolderStatus& status);

}  // namespace harap
