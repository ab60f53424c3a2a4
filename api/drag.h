// SPDX-License-Identifier: MIT
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "framework/config.h"
#include "framework/registries.h"
#include "io/scenario.h"
#include "solvers/optimizers/deformation_session.h"

namespace harap {

/// A handle edit during a drag (`--edits FILE.toml`): before frame `frame`'s solve, either add a
/// handle (the vertices a scenario selection picks that are no handles yet, held where the last
/// frame left them) or remove the handle an earlier edit added under `name`.
///
///   [[edit]]
///   frame = 10
///   add = { name = "knee", select.ball = { center = [0.5, 0.3, 0.5], radius = 0.05 } }
///   [[edit]]
///   frame = 20
///   remove = "knee"
///
/// Selections as in scenarios (select.ball, select.slab, select.indices; box fractions of the
/// mesh's referenced vertices, ball radius in units of the box diagonal).
/// `harap drag`: replays an interaction with a scenario's handles.
struct DragOptions {
  int frames = 30;  ///< the handles reach the scenario's end pose at the last frame
  int threads = 0;
  double frame_budget_ms = 0.0;  ///< per-frame time budget of a session solve (0: none)
  bool preview = false;          ///< session Preview() frames instead of Solve()
  bool from_scratch = false;     ///< a fresh one-shot run per frame (the baseline)
  SessionOptions::FrameStart frame_start = SessionOptions::FrameStart::kCorrected;
  std::string out_frames;         ///< folder for frame_NNN.ply (empty: none)
  std::vector<HandleEdit> edits;  ///< session modes only (LoadHandleEdits)
  IterationCallback progress;
};

struct DragFrame {
  int frame = 0;         ///< 1-based
  double seconds = 0.0;  ///< the frame's solve (from scratch: the whole one-shot run)
  double energy = 0.0;
  int iterations = 0;  ///< finest level
  int total_iterations = 0;
  bool converged = false;
  std::vector<LevelResult> levels;  ///< finest first
  std::vector<std::string> notes;
  /// An edit frame: what the edit did (seconds of all levels' refactorization, per level route).
  std::optional<HandleEditResult> edit;
  std::string edit_description;
};

struct DragOutcome {
  std::string mode;  ///< "session", "preview" or "from_scratch"
  std::string optimizer;
  double setup_seconds = 0.0;      ///< session: hierarchy and precomputation
  double constrain_seconds = 0.0;  ///< session: the first SetHandles (factoring every level)
  std::vector<DragFrame> frames;
  double frames_seconds = 0.0;  ///< sum of the frames' seconds
  std::vector<std::string> notes;
  std::string resolved_config;
};

/// The handles' targets at fraction `t` of the motion (0: rest, 1: the scenario's targets), merged
/// over handles as Scenario::MergedConstraints() does. Each handle's motion is the rigid motion
/// that best maps its rest vertices to its targets (least squares, about the handle's centroid)
/// with the angle and translation scaled by t, plus t times what that motion leaves over (so
/// t = 1 gives exactly the scenario's targets).
Constraints FrameConstraints(const Scenario& scenario, double t);

/// Runs the frames with the pieces named in `config` (as `harap deform`).
DragOutcome RunDrag(const Registries& registries, const Scenario& scenario,
                    const ConfigNode& config, const DragOptions& options);

/// The JSON report: {"mode", "optimizer", "setup_seconds", "constrain_seconds", "frames_seconds",
/// "frames": [{"frame", "seconds", "energy", "iterations", "total_iterations", "converged",
/// "levels": [{"level", "iterations", "energy", "seconds"}], "notes", and on edit frames
/// "edit_seconds", "edit": {"description", "levels": [{"level", "route", "changed_rows",
/// "seconds"}]}}], ...}.
std::string DragReportJson(const Scenario& scenario, const DragOutcome& outcome);

/// The per-frame table for the terminal.
std::string DragTable(const DragOutcome& outcome);

}  // namespace harap
