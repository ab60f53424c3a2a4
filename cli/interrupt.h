// SPDX-License-Identifier: MIT
// Ctrl-C during a long command: stop cleanly at the next iteration, keep what was computed.
#pragma once

namespace harap {

/// While alive, SIGINT no longer ends the process: the first one sets a flag (Requested()) and
/// says on stderr that the run stops after the current iteration; a second one ends the process
/// at once (exit code 130, as a shell reports an interrupted command). The previous handler is
/// restored on destruction. One guard at a time.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

  /// Whether SIGINT arrived since the guard was created (async-signal-safe flag).
  static bool Requested();
};

}  // namespace harap
