// SPDX-License-Identifier: MIT
// Progress of a long command on stderr: the phases the algorithms announce through
// Context::phase_callback and the iterations they report, shown once they take a while; and the
// runs of a sweep (`harap run`): a bar with the counts and an estimate of the time left.
#pragma once

#include <condition_variable>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "api/run_options.h"
#include "framework/context.h"
#include "runner/runner.h"

namespace harap {

struct ProgressOptions {
  /// Off: nothing is shown and no thread is started (`--quiet`).
  bool enabled = true;
  /// A terminal gets one line, redrawn in place; otherwise (a pipe or a file) plain lines.
  bool terminal = false;
  /// Terminal: the live line appears once the command has run this long. Plain lines: a phase
  /// gets a line once it has lasted this long.
  double show_after = 1.0;
  /// Terminal: the line is redrawn this often (seconds).
  double refresh_interval = 0.2;
  /// Plain lines: besides the line per long phase, one line (the current state) this often, so
  /// no stretch of silence is longer, however short the phases.
  double line_interval = 2.0;

  /// Enabled unless `quiet`; terminal when `stream` is one (isatty).
  static ProgressOptions For(std::FILE* stream, bool quiet);
};

/// Renders progress for one command. Phase() and Iteration() only record the state under a
/// mutex (cheap enough for every iteration, and safe from several threads); a background thread
/// draws it at the rates above, so a phase that runs for minutes without reporting still shows
/// its elapsed time. As a SweepObserver it shows a sweep instead: a line per finished run (above
/// the bar on a terminal) and, on a terminal, a bar with runs done, failed, skipped, the elapsed
/// time, an estimate of the time left and the runs in progress.
class ProgressDisplay final : public SweepObserver {
 public:
  ProgressDisplay(std::FILE* stream, ProgressOptions options);
  ~ProgressDisplay() override;
  ProgressDisplay(const ProgressDisplay&) = delete;
  ProgressDisplay& operator=(const ProgressDisplay&) = delete;

  /// A new phase starts (or, with the same name, reports `fraction` of it done, in [0, 1];
  /// negative: unknown).
  void Phase(std::string_view phase, double fraction = -1.0);
  /// An iteration finished: the phase becomes "solving level L" with its latest numbers.
  void Iteration(const IterationSummary& summary);
  /// Clears the terminal line and stops drawing (idempotent; also done by the destructor).
  void Finish();

  /// A Context::phase_callback that forwards to Phase().
  PhaseCallback AsPhaseCallback();
  /// Shows a one-shot run (deform, register): its phases and iterations go to this display, and
  /// the run stops after the current iteration once `stop()` says so (e.g. after Ctrl-C).
  void Follow(RunOptions& options, std::function<bool()> stop);

  // SweepObserver
  void SweepStarted(int total, int skipped) override;
  void RunStarted(const std::string& name) override;
  void RunFinished(const std::string& name, const std::string& status,
                   const std::string& detail) override;
  void Warning(const std::string& text) override;

 private:
  void Draw();       // with mutex_ held
  void DrawSweep();  // with mutex_ held
  void Loop();
  void PrintLine(const std::string& text);  // with mutex_ held: above the live line

  std::FILE* stream_;
  ProgressOptions options_;
  Stopwatch clock_;

  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::string phase_;
  double phase_start_ = 0.0;
  double fraction_ = -1.0;
  bool have_iteration_ = false;
  IterationSummary iteration_;
  bool phase_printed_ = false;  // plain lines: this phase has had its line
  double last_line_ = -1e300;   // plain lines: when the last one was written
  size_t drawn_width_ = 0;      // terminal: characters on the live line

  // A sweep's runs (SweepStarted): drawn instead of phases.
  bool sweep_ = false;
  int runs_total_ = 0, runs_done_ = 0, runs_skipped_ = 0, runs_failed_ = 0, runs_now_ = 0;
  std::vector<std::string> runs_running_;
  std::thread thread_;
};

}  // namespace harap
