// SPDX-License-Identifier: MIT
#include "solvers/optimizers/level_setup_pipeline.h"

#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <condition_variable>
#include <exception>
#include <map>
#include <mutex>

#include "framework/error.h"

namespace harap {

// Shared with the background task. The task runs in a task_group that the pipeline's destructor
// waits for (running the task itself if no worker ever picked it up: it then finds `cancelled`
// and returns at once), so no task outlives the pipeline (an enqueued task that never ran was
// leaked at exit, found by LeakSanitizer).
struct LevelSetupPipeline::State {
  enum class Phase { kPending, kRunning, kDone };
  struct Level {
    Phase phase = Phase::kPending;
    std::exception_ptr error;
  };

  std::mutex mutex;
  std::condition_variable changed;
  std::map<int, Level> levels;  // (entries stay in place when levels are added)
  std::vector<int> order;       // the background task's
  bool closed = true;           // no more levels will be added
  std::function<void(int)> setup;
  bool cancelled = false;
  bool background_running = false;
  std::shared_ptr<tbb::task_arena> arena;  // set when a background task was started
  tbb::task_group group;

  // Claims `level` if nobody has; then runs it. Called with `lock` held; returns with it held.
  bool TryRun(int level, std::unique_lock<std::mutex>& lock) {
    Level& entry = levels.at(level);
    if (entry.phase != Phase::kPending) return false;
    entry.phase = Phase::kRunning;
    lock.unlock();
    std::exception_ptr error;
    try {
      if (arena) {
        // Isolated: while this setup waits for its own parallel loops, its thread must not pick
        // up another task of the arena. The background task is spawned by the caller's thread
        // and stays in that thread's task pool until a worker steals it; without isolation the
        // caller, setting up a coarse level on demand, could run the whole background task
        // (finest level first) inside its own parallel loop before it got back to the coarse
        // levels.
        arena->execute([&] { tbb::this_task_arena::isolate([&] { setup(level); }); });
      } else {
        setup(level);
      }
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    entry.phase = Phase::kDone;
    entry.error = error;
    changed.notify_all();
    return true;
  }

  // Whether the background task will end once its current level is set up: all levels are
  // known and none is left pending (it skips the ones others have set up). Called with the
  // mutex held.
  bool BackgroundEndsAfterRun() const {
    if (!closed) return false;
    for (const auto& [level, entry] : levels) {
      if (entry.phase == Phase::kPending) return false;
    }
    return true;
  }
};

LevelSetupPipeline::LevelSetupPipeline(std::vector<int> levels, std::function<void(int)> setup,
                                       bool overlap, const Context& context, bool more_levels)
    : state_(std::make_shared<State>()) {
  for (int level : levels) state_->levels[level];
  state_->order = std::move(levels);
  state_->closed = !more_levels;
  state_->setup = std::move(setup);
  if (!overlap) return;
  State* state = state_.get();  // outlives the task: the destructor waits for the group
  state_->arena = context.arena;
  context.arena->execute([&] {
    state->group.run([state] {
      std::unique_lock lock(state->mutex);
      if (state->cancelled) return;
      state->background_running = true;
      for (size_t i = 0;; ++i) {
        // Levels still to be added (AddLevels) are waited for here.
        state->changed.wait(
            lock, [&] { return state->cancelled || i < state->order.size() || state->closed; });
        if (state->cancelled || i >= state->order.size()) break;
        state->TryRun(state->order[i], lock);
      }
      state->background_running = false;
      state->changed.notify_all();
    });
  });
}

void LevelSetupPipeline::AddLevels(const std::vector<int>& levels) {
  const std::lock_guard lock(state_->mutex);
  HARAP_CHECK(!state_->closed, "AddLevels: the pipeline's levels were already complete");
  for (int level : levels) {
    HARAP_CHECK(state_->levels.count(level) == 0, "level {} added twice", level);
    state_->levels[level];
    state_->order.push_back(level);
  }
  state_->closed = true;
  state_->changed.notify_all();
}

LevelSetupPipeline::~LevelSetupPipeline() {
  {
    std::unique_lock lock(state_->mutex);
    state_->cancelled = true;
    state_->changed.notify_all();  // a background task waiting for AddLevels() stops
    state_->changed.wait(lock, [&] { return !state_->background_running; });
  }
  if (state_->arena) state_->arena->execute([&] { state_->group.wait(); });
}

void LevelSetupPipeline::WaitFor(int level) {
  std::unique_lock lock(state_->mutex);
  HARAP_CHECK(state_->levels.count(level) == 1, "level {} is not set up by this pipeline", level);
  state_->TryRun(level, lock);
  State::Level& entry = state_->levels.at(level);
  if (entry.phase == State::Phase::kRunning && state_->arena && state_->BackgroundEndsAfterRun()) {
    // The background task is setting `level` up and has nothing after it: waiting for the task
    // is waiting for the level, and a task_group wait lets this thread run the setup's parallel
    // work (its loops, its factorization's subtrees) instead of blocking while the background
    // thread does it alone (classic runs; dragon-lift's finest level, whose setup outlasts the
    // coarse levels' solves).
    lock.unlock();
    state_->arena->execute([&] { state_->group.wait(); });
    lock.lock();
  }
  state_->changed.wait(lock, [&] { return entry.phase == State::Phase::kDone; });
  if (entry.error) std::rethrow_exception(entry.error);
}

}  // namespace harap
