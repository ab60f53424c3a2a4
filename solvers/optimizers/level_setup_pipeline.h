// SPDX-License-Identifier: MIT
#pragma once

#include <tbb/task_arena.h>

#include <functional>
#include <memory>
#include <vector>

#include "framework/context.h"

namespace harap {

/// Sets up the levels of a hierarchy (precomputation and factorization, via `setup(level)`) while
/// the caller solves the levels that are ready: the hierarchical optimizer's P and C phases of
/// finer levels overlap the S phase of coarser ones.
///
/// With `overlap`, a task in the context's arena sets the levels up in the given order (the
/// hierarchical optimizer: finest first); a caller that needs a level nobody has started yet
/// sets it up itself (so nothing waits for a thread that may never come, e.g. under a global TBB
/// thread limit), so the caller, walking from the coarsest level down, and the task, walking up
/// from the finest, meet in the middle. Without it, WaitFor() sets levels up on
/// demand, in the caller's thread. Levels must be independent of each other's setup.
class LevelSetupPipeline {
 public:
  /// `levels` in the order the background task should take them. With `more_levels`, AddLevels()
  /// appends the rest later (e.g. once the hierarchy is built), and the background task waits
  /// for them after the first ones.
  LevelSetupPipeline(std::vector<int> levels, std::function<void(int)> setup, bool overlap,
                     const Context& context, bool more_levels = false);
  /// Stops the background task after its current level and waits for it.
  ~LevelSetupPipeline();
  LevelSetupPipeline(const LevelSetupPipeline&) = delete;
  LevelSetupPipeline& operator=(const LevelSetupPipeline&) = delete;

  /// Appends `levels` to the background task's order (after those given so far) and closes the
  /// list; only once, and only if constructed with more_levels.
  void AddLevels(const std::vector<int>& levels);

  /// Returns once `level` is set up; rethrows what its setup threw. Called from one thread (the
  /// caller's): when the background task is setting `level` up and has nothing after it, the
  /// wait is a wait on its task group, which runs part of that setup's parallel work on this
  /// thread (a task group is waited on from one thread at a time).
  void WaitFor(int level);

  /// Runs `f` in the context's arena such that, while it waits for its own parallel work, the
  /// caller's thread never picks up the background setup (which would stall the solve).
  template <class F>
  decltype(auto) Isolated(const Context& context, F&& f) {
    return context.Run([&]() -> decltype(auto) { return tbb::this_task_arena::isolate(f); });
  }

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace harap
