// SPDX-License-Identifier: MIT
#pragma once

#include <tbb/task_arena.h>

#include <chrono>
#include <functional>
#include <memory>
#include <string_view>

#include "framework/types.h"

namespace harap {

/// Wall-clock stopwatch (steady clock), in seconds.
class Stopwatch {
 public:
  Stopwatch() : start_(Clock::now()) {}
  void Restart() { start_ = Clock::now(); }
  double Seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
};

/// What one local/global iteration reports to the callback (Ceres' IterationSummary idea).
struct IterationSummary {
  int level = 0;              ///< Hierarchy level (0 = input mesh; classic ARAP is always 0).
  int iteration = 0;          ///< 1-based iteration count on this level.
  double energy = 0.0;        ///< E(U, R) after the iteration's global step, R fitted to U.
  double displacement = 0.0;  ///< Squared max-norm of the global step's displacement / diag².
  double seconds = 0.0;       ///< Wall time since the start of the run (precomputation included).
  /// ADMM optimizers (admm_pd, wrapd): elements with det F_t < 0 after the iteration; −1 where
  /// the optimizer does not count them (local/global).
  Index inverted_elements = -1;
};

/// Return kStop to end the optimization after this iteration (the result reports it).
enum class CallbackAction { kContinue, kStop };
using IterationCallback = std::function<CallbackAction(const IterationSummary&)>;

/// Hands a level's reduced global-step matrix A_ff (free × free, full symmetric storage, in the
/// level's internal vertex numbering) to the caller, once per solved level right after it is
/// factored. For analyses the optimizer knows nothing about (`harap deform --diagnostics`
/// computes its extreme eigenvalues); the time spent in it counts towards the C phase, so a
/// caller that wants clean timings copies the matrix and analyses it after the run.
using SystemCallback = std::function<void(int level, const SparseMatrix& reduced_matrix)>;

/// Announces that an algorithm starts a phase that may take a while ("building the hierarchy",
/// "factoring level 0"), so a caller can show progress; algorithms never print. `fraction` is
/// how much of the phase is done, in [0, 1], or negative when unknown (most phases announce
/// only their start). Levels may be set up on a background thread while others are solved, so
/// the callback may be called from several threads at once: it must be thread-safe, and cheap
/// (it is called a handful of times per level, never per iteration).
using PhaseCallback = std::function<void(std::string_view phase, double fraction)>;

/// Everything an algorithm needs from its caller besides its inputs: threads, the run clock and
/// the callbacks. Passed by reference; algorithms never create global thread pools or print.
struct Context {
  /// Runs `f` inside the run's task arena (so the thread count holds for TBB algorithms).
  template <class F>
  decltype(auto) Run(F&& f) const {
    return arena->execute(std::forward<F>(f));
  }

  std::shared_ptr<tbb::task_arena> arena = std::make_shared<tbb::task_arena>();
  Stopwatch run_clock;  ///< Started when the run starts; trace times count from it.
  IterationCallback iteration_callback;  ///< May be empty.
  SystemCallback system_callback;        ///< May be empty.
  PhaseCallback phase_callback;          ///< May be empty.

  /// Calls phase_callback if there is one.
  void ReportPhase(std::string_view phase, double fraction = -1.0) const {
    if (phase_callback) phase_callback(phase, fraction);
  }

  /// The worker threads the run's arena uses (the requested count, or all the process may use).
  int threads() const { return arena->max_concurrency(); }

  /// A context with `threads` worker threads (0 = all hardware threads).
  static Context WithThreads(int threads) {
    Context context;
    if (threads > 0) context.arena = std::make_shared<tbb::task_arena>(threads);
    return context;
  }
};

}  // namespace harap
