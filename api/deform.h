// SPDX-License-Identifier: MIT
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "api/run_options.h"
#include "framework/config.h"
#include "framework/optimizer.h"
#include "framework/registries.h"
#include "io/mesh_repair.h"
#include "io/scenario.h"
#include "solvers/linear/spectral_bounds.h"

namespace harap {

/// One entry of the energy trace (the report's `trace` array).
struct TraceEntry {
  double t = 0.0;  ///< Seconds since the start of the run (precomputation included).
  double energy = 0.0;
  int level = 0;
  Index inverted_elements =
      -1;  ///< ADMM optimizers: det F < 0 after the iteration (−1: not counted)
};

/// The threads and callbacks (RunOptions: `progress` is called after the iteration is recorded in
/// the trace; the phases are checking the mesh, the optimizer's hierarchy, precompute and
/// factorization per level), and:
struct DeformOptions : RunOptions {
  /// Compute the extreme eigenvalues of every solved level's reduced global-step matrix (A and
  /// its Jacobi scaling; Spectra, see solvers/spectral_bounds.h). The matrices are copied during
  /// the run and analysed after it, so the run's timings do not include the analysis.
  bool diagnostics = false;
  /// Per-element stiffness factors of the scenario's mesh (framework/stiffness.h), e.g. from
  /// arrays; empty: the scenario's `[[stiffness]]` regions (Scenario::ElementStiffness).
  std::vector<double> stiffness;
  /// For timing short runs: the optimizer's run is repeated in this process until the
  /// repetitions' timings.total add up to min_time seconds, at most max_repetitions times, and
  /// the outcome is the repetition with the median total (of an even count, the lower one;
  /// 0: one run). A run of a few
  /// milliseconds timed once in a fresh process mostly measures first-use costs (worker threads
  /// starting, fresh memory faulted in) that differ from run to run more than the methods being
  /// compared do (docs/experiments.md, "Timing short runs").
  double min_time = 0.0;
  int max_repetitions = 30;
};

/// How often RunDeform ran the optimizer (DeformOptions::min_time) and the spread of the
/// repetitions' timings.total.
struct DeformRepetitions {
  int count = 1;
  double fastest_total = 0.0;
  double slowest_total = 0.0;
};

/// Everything a `harap deform` run produced.
struct DeformOutcome {
  std::string optimizer;
  std::string energy_type;
  std::string solver;
  std::string hierarchy;  ///< Empty for single-level optimizers.
  std::string upsampler;
  std::vector<std::string> level_solvers;  ///< Solver name per entry of result.levels.
  std::vector<bool> level_solver_direct;   ///< Whether that solver factors (no iterations).
  int threads = 0;
  OptimizeResult result;
  std::vector<TraceEntry> trace;
  DeformRepetitions repetitions;          ///< result and trace are the median repetition's
  std::string resolved_config;            ///< The run's config as TOML.
  std::map<int, SystemSpectrum> spectra;  ///< With diagnostics: per solved level.
  MeshCheckReport mesh_checks;  ///< The input mesh's checks, with the action taken for each.
  std::vector<std::string> mesh_summary;  ///< One line per finding (PreparedProblem::Summary).
  double mesh_check_seconds = 0.0;
  bool mesh_repaired = false;  ///< Welded or dropped something: the solved mesh differs.
  Index solved_vertices = 0;
  Index solved_elements = 0;
  /// When mesh_repaired: the checks of the solved (repaired) mesh and their summary lines.
  MeshCheckReport repaired_mesh_checks;
  std::vector<std::string> repaired_mesh_summary;
  /// RunWarnings (run_warnings.h): results that probably do not mean what they seem to.
  std::vector<std::string> warnings;
  /// Set by the caller when the run was stopped by Ctrl-C (the report's status "interrupted").
  bool interrupted = false;
};

/// Solves the scenario's deformation with the pieces named in `config` (tables `optimizer`,
/// `energy`, `solver`, `hierarchy`, `upsampler`; each with `type` and options; `mesh` with the
/// MeshRepairOptions). Checks the mesh first (CheckMesh), repairs what `mesh` asks for, and
/// returns positions for every input vertex in the input's order.
DeformOutcome RunDeform(const Registries& registries, const Scenario& scenario,
                        const ConfigNode& config, const DeformOptions& options);

/// The JSON report (see docs/report.md for the keys); `include_trace` adds the `trace` array.
std::string DeformReportJson(const Scenario& scenario, const DeformOutcome& outcome,
                             bool include_trace);

/// The scenario's handles as JSON: {"handles": [{"name": ..., "vertices": [indices]}]} (for
/// pictures that mark the handles).
std::string HandlesJson(const Scenario& scenario);

/// Peak resident memory of this process so far, in bytes.
long long PeakMemoryBytes();

}  // namespace harap
