// SPDX-License-Identifier: MIT
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "runner/experiment.h"

namespace harap {

/// What a sweep tells while it runs (the `harap` command's progress display implements it).
/// Called from the runner's worker threads: implementations must be thread-safe.
class SweepObserver {
 public:
  virtual ~SweepObserver() = default;
  /// The plan is known: `total` runs in this shard, `skipped` of them finished before.
  virtual void SweepStarted(int total, int skipped) = 0;
  /// `name`: scenario and variant/grid label, as in the report.
  virtual void RunStarted(const std::string& name) = 0;
  /// `status`: "ok" or the failure's kind; `detail`: energy and time, or the error.
  virtual void RunFinished(const std::string& name, const std::string& status,
                           const std::string& detail) = 0;
  /// Something about the experiment worth knowing before it runs.
  virtual void Warning(const std::string& text) = 0;
};

struct RunnerOptions {
  std::filesystem::path out_dir;
  Shard shard;
  /// Runs executed at once, each in its own `harap deform` process.
  int jobs = 1;
  /// Threads per run; 0: the config's [run] threads, else max(1, cores / jobs).
  int threads = 0;
  /// The harap executable each run is started with (`harap deform ...`).
  std::filesystem::path executable;
  /// Only scenarios whose name matches one of these shell patterns (all when empty).
  std::vector<std::string> scenario_filter;
  /// Also re-run runs recorded as failed (finished runs are always skipped).
  bool retry_failed = false;
  /// This machine's name in temporary file names (PID@HOST), which keeps shards on several
  /// hosts sharing one folder from removing each other's files; empty: gethostname().
  std::string host;
  /// Told of every run started and finished; nullptr: nothing is told.
  SweepObserver* observer = nullptr;
};

struct SweepSummary {
  int planned = 0;    ///< runs in the whole plan
  int in_shard = 0;   ///< runs of this shard (and of the scenarios --filter selects)
  int skipped = 0;    ///< already finished (resume)
  int succeeded = 0;  ///< run now, successfully
  int failed = 0;     ///< run now, failed (error recorded)
};

/// Runs this shard's runs of `experiment` into `options.out_dir`:
///   experiment.json     the plan (every run's id, label, parameters and resolved config)
///   config.toml         the config as written
///   runs/ID.json        per run: the `harap deform --report --trace` keys plus `run`
///   runs/ID.config.toml the run's resolved config; runs/ID.log the output of a failed run
///   scenarios/NAME.toml scenario files generated from handle templates
///   meshes/ID.ply, meshes/SCENARIO.rest.ply (+ .handles.json) with [run] save_mesh
///   results[-shard-I-of-N].csv  one row per finished run of this shard
/// A run that fails is recorded (status, error) and the sweep goes on.
SweepSummary RunExperiment(const Experiment& experiment, const RunnerOptions& options);

/// Writes the plan of `experiment` into `dir` (experiment.json, config.toml), as a sweep does
/// before its first run: for submitters that start the shards elsewhere.
void WriteExperimentPlan(const Experiment& experiment, const std::filesystem::path& dir);

struct MergeSummary {
  int planned = 0;
  int succeeded = 0;
  int failed = 0;
  int missing = 0;  ///< planned runs without a report yet
};

/// Merges the run reports of every shard in `dir` (per its experiment.json) into
/// `dir/results.csv`, in plan order.
MergeSummary MergeResults(const std::filesystem::path& dir);

/// The columns of results.csv whose values are timings or memory (they differ between
/// otherwise identical runs).
bool IsTimingColumn(const std::string& column);

}  // namespace harap
