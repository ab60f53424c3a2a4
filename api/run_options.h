// SPDX-License-Identifier: MIT
#pragma once

#include "framework/context.h"

namespace harap {

/// What a one-shot run of the API (RunDeform, RunRegister) takes from its caller besides the
/// problem and the config: its threads and its callbacks.
struct RunOptions {
  int threads = 0;  ///< 0: all hardware threads.
  /// Called for every iteration, e.g. for a progress display; returning kStop ends the run after
  /// that iteration (e.g. on Ctrl-C).
  IterationCallback progress;
  /// Receives the phases of the run (see Context::phase_callback). May be empty.
  PhaseCallback phase;

  /// The run's context: `threads` worker threads, reporting iterations to `progress` and phases
  /// to `phase`.
  Context MakeContext() const {
    Context context = Context::WithThreads(threads);
    context.iteration_callback = progress;
    context.phase_callback = phase;
    return context;
  }
};

}  // namespace harap
