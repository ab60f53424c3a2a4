// SPDX-License-Identifier: MIT
#include "cli/progress.h"

#include <fmt/format.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <utility>

namespace harap {

namespace {

// h:mm:ss or m:ss.
std::string FormatDuration(double seconds) {
  const long total = static_cast<long>(seconds + 0.5);
  if (total >= 3600)
    return fmt::format("{}:{:02}:{:02}", total / 3600, total / 60 % 60, total % 60);
  return fmt::format("{}:{:02}", total / 60, total % 60);
}

// Columns of the terminal less one (a full line would wrap), 79 if unknown.
size_t TerminalWidth(std::FILE* stream) {
  winsize size{};
  if (ioctl(fileno(stream), TIOCGWINSZ, &size) == 0 && size.ws_col > 1) {
    return static_cast<size_t>(size.ws_col) - 1;
  }
  return 79;
}

}  // namespace

ProgressOptions ProgressOptions::For(std::FILE* stream, bool quiet) {
  ProgressOptions options;
  options.enabled = !quiet;
  options.terminal = isatty(fileno(stream)) != 0;
  return options;
}

ProgressDisplay::ProgressDisplay(std::FILE* stream, ProgressOptions options)
    : stream_(stream), options_(options) {
  if (options_.enabled) thread_ = std::thread([this] { Loop(); });
}

ProgressDisplay::~ProgressDisplay() { Finish(); }

void ProgressDisplay::Phase(std::string_view phase, double fraction) {
  if (!options_.enabled) return;
  const std::lock_guard lock(mutex_);
  if (phase != phase_) {
    phase_ = phase;
    phase_start_ = clock_.Seconds();
    phase_printed_ = false;
    have_iteration_ = false;
  }
  fraction_ = fraction;
}

void ProgressDisplay::Iteration(const IterationSummary& summary) {
  if (!options_.enabled) return;
  const std::lock_guard lock(mutex_);
  // Formatting a name per iteration would cost more than the rest of this; compare first.
  if (!have_iteration_ || iteration_.level != summary.level) {
    phase_ = fmt::format("solving level {}", summary.level);
    phase_start_ = clock_.Seconds();
    phase_printed_ = false;
    fraction_ = -1.0;
  }
  have_iteration_ = true;
  iteration_ = summary;
}

void ProgressDisplay::Finish() {
  {
    const std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
    if (options_.terminal && drawn_width_ > 0) {
      fmt::print(stream_, "\r{:{}}\r", "", drawn_width_);
      std::fflush(stream_);
      drawn_width_ = 0;
    }
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

PhaseCallback ProgressDisplay::AsPhaseCallback() {
  if (!options_.enabled) return {};
  return [this](std::string_view phase, double fraction) { Phase(phase, fraction); };
}

void ProgressDisplay::Follow(RunOptions& options, std::function<bool()> stop) {
  options.phase = AsPhaseCallback();
  options.progress = [this, stop = std::move(stop)](const IterationSummary& summary) {
    Iteration(summary);
    return stop() ? CallbackAction::kStop : CallbackAction::kContinue;
  };
}

void ProgressDisplay::SweepStarted(int total, int skipped) {
  if (!options_.enabled) return;
  const std::lock_guard lock(mutex_);
  sweep_ = true;
  runs_total_ = total;
  runs_done_ = runs_skipped_ = skipped;
}

void ProgressDisplay::RunStarted(const std::string& name) {
  if (!options_.enabled) return;
  const std::lock_guard lock(mutex_);
  runs_running_.push_back(name);
  if (options_.terminal) DrawSweep();
}

void ProgressDisplay::RunFinished(const std::string& name, const std::string& status,
                                  const std::string& detail) {
  if (!options_.enabled) return;
  const std::lock_guard lock(mutex_);
  ++runs_done_;
  ++runs_now_;
  runs_failed_ += status != "ok";
  if (const auto it = std::find(runs_running_.begin(), runs_running_.end(), name);
      it != runs_running_.end()) {
    runs_running_.erase(it);
  }
  PrintLine(fmt::format("[{}/{}] {:7} {}  {}", runs_done_, runs_total_, status, name, detail));
  if (options_.terminal) DrawSweep();
}

void ProgressDisplay::Warning(const std::string& text) {
  if (!options_.enabled) return;
  const std::lock_guard lock(mutex_);
  PrintLine(fmt::format("harap: warning: {}", text));
}

void ProgressDisplay::PrintLine(const std::string& text) {
  if (options_.terminal && drawn_width_ > 0) {
    fmt::print(stream_, "\r{:{}}\r", "", drawn_width_);
    drawn_width_ = 0;
  }
  fmt::print(stream_, "{}\n", text);
  std::fflush(stream_);
}

void ProgressDisplay::DrawSweep() {
  if (!options_.terminal) return;  // plain lines: one per finished run, written as it finishes
  const double elapsed = clock_.Seconds();
  const int remaining = runs_total_ - runs_done_;
  const std::string eta =
      runs_now_ > 0 ? FormatDuration(elapsed / runs_now_ * remaining) : std::string("--:--");
  constexpr int kWidth = 28;
  const int filled = runs_total_ > 0 ? kWidth * runs_done_ / runs_total_ : kWidth;
  std::string running =
      runs_running_.empty() ? std::string() : "  running " + runs_running_.front();
  if (runs_running_.size() > 1) running += fmt::format(" (+{})", runs_running_.size() - 1);
  if (running.size() > 60) running = running.substr(0, 57) + "...";
  const std::string line =
      fmt::format("[{}{}] {}/{} runs  {} failed  {} skipped  elapsed {}  ETA {}{}",
                  std::string(filled, '#'), std::string(kWidth - filled, '.'), runs_done_,
                  runs_total_, runs_failed_, runs_skipped_, FormatDuration(elapsed), eta, running);
  const std::string shown = line.substr(0, TerminalWidth(stream_));
  fmt::print(stream_, "\r{:{}}", shown, std::max(shown.size(), drawn_width_));
  drawn_width_ = shown.size();
  std::fflush(stream_);
}

void ProgressDisplay::Draw() {
  if (sweep_) {
    DrawSweep();
    return;
  }
  const double now = clock_.Seconds();
  const double in_phase = now - phase_start_;
  if (phase_.empty()) return;
  if (options_.terminal) {
    // The live line appears once the command has run for show_after, then follows every phase.
    if (now < options_.show_after) return;
  } else {
    // A line when a phase has lasted show_after, and otherwise one every line_interval, so a
    // run of many short phases is not silent either.
    const bool long_phase = !phase_printed_ && in_phase >= options_.show_after;
    const bool due = now >= options_.line_interval && now - last_line_ >= options_.line_interval;
    if (!long_phase && !due) return;
  }
  std::string text = fmt::format("harap: {:7.1f} s  {}", now, phase_);
  if (have_iteration_) {
    text += fmt::format(": iteration {}, energy {:.6e}, step {:.2e}", iteration_.iteration,
                        iteration_.energy, iteration_.displacement);
  } else if (fraction_ >= 0.0) {
    text += fmt::format(" ({:.0f}%)", 100.0 * fraction_);
  } else {
    text += fmt::format(" ({:.1f} s)", in_phase);
  }
  if (options_.terminal) {
    const size_t width = text.size();
    fmt::print(stream_, "\r{:{}}", text, std::max(width, drawn_width_));
    drawn_width_ = width;
  } else {
    fmt::print(stream_, "{}\n", text);
    phase_printed_ = true;
    last_line_ = now;
  }
  std::fflush(stream_);
}

void ProgressDisplay::Loop() {
  const double interval =
      options_.terminal ? options_.refresh_interval : std::min(0.25, options_.line_interval);
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    wake_.wait_for(lock, std::chrono::duration<double>(interval));
    if (stopping_) break;
    Draw();
  }
}

}  // namespace harap
