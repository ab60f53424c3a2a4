// SPDX-License-Identifier: MIT
#include "experiments/progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>

namespace harap {

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

void ProgressDisplay::Draw() {
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
