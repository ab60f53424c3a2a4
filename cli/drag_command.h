// SPDX-License-Identifier: MIT
#pragma once

// The `harap drag` subcommand's command line (CLI11: included by main.cpp only; the work is in
// drag.h).

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "api/builtins.h"
#include "api/drag.h"
#include "cli/output_checks.h"
#include "cli/piece_flags.h"
#include "framework/error.h"

namespace harap {

struct DragCommandArguments : PieceFlags {
  std::string scenario;
  std::string report, edits, frame_start = "corrected";
  bool quiet = false;
  DragOptions options;
};

inline CLI::App* AddDragCommand(CLI::App& app, DragCommandArguments& a) {
  CLI::App* drag = app.add_subcommand(
      "drag",
      "replay an interaction: the scenario's handles move from rest to their targets "
      "over --frames frames, one solve per frame in a session");
  drag->add_option("scenario", a.scenario, "scenario TOML file")->required();
  drag->add_option("--config", a.config_file, "TOML file with the run config tables");
  drag->add_option("--optimizer", a.optimizer, "classic (default) or hierarchical");
  drag->add_option("--energy", a.energy, "energy name");
  drag->add_option("--solver", a.solver, "linear solver name (default cholmod)");
  drag->add_option("--hierarchy", a.hierarchy, "hierarchy name");
  drag->add_option("--upsampler", a.upsampler, "upsampler name");
  drag->add_option("--tolerance", a.tolerance, "per-frame convergence tolerance");
  drag->add_option("--max-iterations", a.max_iterations, "per-frame iteration cap (per level)");
  drag->add_option("--set", a.settings, "set any option by its config key");
  drag->add_option("--frames", a.options.frames, "frames to the end pose (default 30)");
  drag->add_option("--frame-budget-ms", a.options.frame_budget_ms,
                   "per-frame time budget in milliseconds (0: none)");
  drag->add_flag("--preview", a.options.preview, "preview frames (the coarse approximation)");
  drag->add_flag("--from-scratch", a.options.from_scratch,
                 "a fresh one-shot run per frame (the baseline)");
  drag->add_option("--frame-start", a.frame_start,
                   "where a hierarchical session's finer levels start a frame: corrected (default: "
                   "each level's last solution plus the up-sampled coarse change), upsampled (the "
                   "one-shot cascade) or previous (the finest level alone, from its last "
                   "solution)");
  drag->add_option("--edits", a.edits,
                   "TOML file of handle edits: [[edit]] frame = N, add = {name, select} or "
                   "remove = \"name\" (see api/drag.h)");
  drag->add_option("--report", a.report, "write a JSON report with a `frames` array");
  drag->add_option("--out-frames", a.options.out_frames, "folder for frame_NNN.ply");
  drag->add_option("--threads", a.options.threads, "worker threads (default: all cores)");
  drag->add_flag("--quiet,-q", a.quiet, "print nothing on success");
  return drag;
}

inline int RunDragCommand(const DragCommandArguments& a) {
  // Wrong file names fail now, not after the frames are solved.
  RefuseMeshAsScenario(a.scenario);
  // The frames' folder first, as the run would make it: a report may go beside the frames.
  if (!a.options.out_frames.empty()) {
    std::error_code error;
    std::filesystem::create_directories(a.options.out_frames, error);
    if (error) {
      throw InputError(fmt::format("--out-frames {}: cannot create the folder ({})",
                                   a.options.out_frames, error.message()));
    }
  }
  if (!a.report.empty()) CheckWritable(a.report, "--report");
  const ConfigNode config = a.BuildConfig();
  DragOptions options = a.options;
  options.frame_start = SessionOptions::ParseFrameStart(a.frame_start);
  const Registries registries = MakeBuiltinRegistries();
  const Scenario scenario = LoadScenario(a.scenario);
  if (!a.edits.empty()) options.edits = LoadHandleEdits(a.edits, scenario);
  const DragOutcome outcome = RunDrag(registries, scenario, config, options);
  if (!a.report.empty()) {
    std::ofstream file(a.report);
    file << DragReportJson(scenario, outcome) << "\n";
    if (!file) throw InputError(fmt::format("{}: cannot write the report", a.report));
  }
  if (!a.quiet) fmt::print("{}", DragTable(outcome));
  return 0;
}

}  // namespace harap
