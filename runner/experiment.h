// SPDX-License-Identifier: MIT
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "api/known_answer.h"
#include "io/scenario_generator.h"

namespace harap {

/// Handles generated for every mesh of a `[[scenarios.folder]]` (docs/experiments.md): the lowest
/// `fixed` fraction of the bounding box along `axis` is held in place, the highest `moved`
/// fraction is rotated by `degrees` about `bend_axis` (through its centroid) and shifted by
/// `translate` (in box diagonals, world axes). Written out as an ordinary scenario file
/// (../shared/scenarios/FORMAT.md, `select.slab` handles).
struct HandleTemplate {
  std::string axis = "longest";    ///< "x", "y", "z" or "longest" (of the mesh's bounding box)
  double fixed = 0.1;              ///< fraction of the extent held fixed, from the minimum
  double moved = 0.1;              ///< fraction of the extent moved, up to the maximum
  double degrees = 45.0;           ///< rotation of the moved part
  std::string bend_axis = "auto";  ///< "x", "y", "z" or "auto": the shorter of the other two
  double translate[3] = {0.0, 0.0, 0.0};  ///< shift of the moved part, in box diagonals
};

/// One scenario of an experiment: an existing scenario file, a mesh with a handle template, or
/// a mesh with a generated scenario (`[scenarios] meshes`, scenario_generator.h).
struct ExperimentScenario {
  std::string name;                    ///< unique within the experiment (file stem, made unique)
  std::filesystem::path file;          ///< the scenario file (absolute); empty for template meshes
  std::filesystem::path mesh;          ///< template and generated scenarios: the mesh (absolute)
  HandleTemplate handles;              ///< template scenarios: how to place the handles
  bool generated = false;              ///< the scenario is made by GenerateScenarioForFile
  ScenarioGeneratorOptions generator;  ///< generated scenarios: kind, refinement, handle size
  /// Registration experiments (`[known_answers]`): the target made from this scenario's answer
  /// ("mesh", "points", "damaged"; api/known_answer.h); empty for deformation runs.
  std::string known_answer_target;
  bool templated() const { return file.empty(); }
};

/// `[known_answers]`: the experiment registers instead of deforming. Every scenario, solved by
/// `harap deform`, is the answer of one registration case per target (`harap known-answer`).
struct KnownAnswerSettings {
  bool enabled = false;
  std::vector<std::string> targets = {"mesh", "points", "damaged"};
  /// How every case is made (its `target` is each of `targets` in turn).
  KnownAnswerOptions options;
};

/// One run of the sweep: a scenario with one combination of variant and grid values.
struct ExperimentRun {
  int index = 0;        ///< position in the expanded plan (scenario-major)
  std::string id;       ///< stable: scenario name + hash of scenario and run config
  int scenario = 0;     ///< index into Experiment::scenarios
  std::string variant;  ///< `[[variant]]` name ("" without variants)
  /// The values this run sets on top of the base tables, in order: variant keys, then grid keys
  /// (dotted key, TOML literal).
  std::vector<std::pair<std::string, std::string>> parameters;
  std::string label;        ///< variant name and grid values, for tables and legends
  std::string config_toml;  ///< the resolved run config (`harap deform --config` content)
};

/// Per-run settings of the `[run]` table.
struct ExperimentRunSettings {
  int threads = 0;         ///< threads per run (0: cores / --jobs)
  bool save_mesh = false;  ///< write the rest and deformed meshes (PLY) for the pictures
  double timeout = 0.0;    ///< seconds before a run is killed and recorded as failed (0: none)
  /// `harap deform --min-time`: a deform run shorter than this is repeated in its process and
  /// timed by the median repetition (0: every run once).
  double min_time = 0.0;
};

/// The `[slurm]` table: defaults of `harap run --slurm` (its command-line options win).
struct ExperimentSlurmSettings {
  int tasks = 0;          ///< array tasks (= shards); 0: one per run, at most 100
  std::string partition;  ///< "" : the cluster's default partition
  std::string time;       ///< time limit per task (sbatch --time, e.g. "2:00:00"); "": default
  int cpus_per_task = 1;  ///< CPUs per task; the runs of a task use them as threads
  std::string mem;        ///< memory per task (sbatch --mem, e.g. "8G"); "": default
  int throttle = 0;       ///< at most this many tasks at once (--array=...%K); 0: no limit
  std::vector<std::string> sbatch_flags;  ///< further sbatch options, e.g. ["--qos=long"]
};

/// An experiment config (experiments/configs/*.toml, format in docs/experiments.md), expanded.
struct Experiment {
  std::filesystem::path file;
  std::string name;
  std::string title;
  std::string source_text;  ///< the config as written
  std::string report_json;  ///< the `[experiment]` and `[report]` tables as JSON, for the report
  std::vector<std::string> grid_keys;  ///< keys varied by [grid] (dotted), in file order
  std::vector<ExperimentScenario> scenarios;
  std::vector<ExperimentRun> runs;
  ExperimentRunSettings settings;
  ExperimentSlurmSettings slurm;
  KnownAnswerSettings known_answers;
  /// The `harap` subcommand every run executes: "register" with `[known_answers]`, else "deform".
  const char* command() const { return known_answers.enabled ? "register" : "deform"; }
  /// Things that are allowed but probably not meant, for `harap run` to print before it starts
  /// (e.g. runs that compare different energies).
  std::vector<std::string> warnings;
};

/// Parses and expands an experiment config; every run config is validated against the
/// registries and the [report] table against the report script's keys and figure names
/// (experiments/scripts/report_keys.json), so unknown names and keys fail before any run starts.
/// Relative paths start at
/// `[scenarios] relative_to` (itself relative to the config's folder; default the folder).
Experiment LoadExperiment(const std::filesystem::path& file);
Experiment ParseExperiment(std::string_view toml_text, const std::string& source_name,
                           const std::filesystem::path& base_directory);

/// `--shard I/N`: runs with index % N == I (0 <= I < N).
struct Shard {
  int index = 0;
  int count = 1;
  bool Contains(int run_index) const { return run_index % count == index; }
  std::string Suffix() const;  ///< "" for 0/1, else "-shard-I-of-N"
};
Shard ParseShard(std::string_view text);

/// The scenario file text a handle template makes for a mesh whose bounding box has the given
/// extent (needed for "longest" and "auto").
/// The figure names and [report] keys the report script knows, read from
/// experiments/scripts/report_keys.json (the file report.py reads too).
struct ReportKeys {
  std::vector<std::string> figures;
  std::vector<std::string> keys;
};
ReportKeys LoadReportKeys();

std::string TemplateScenarioToml(const ExperimentScenario& scenario, const double extent[3]);

}  // namespace harap
