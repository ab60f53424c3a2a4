// SPDX-License-Identifier: MIT
#include "solvers/optimizers/level_setup_pipeline.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include "framework/error.h"

using namespace harap;

TEST_CASE("LevelSetupPipeline sets every level up once, also levels added later", "[optimizers]") {
  for (const bool overlap : {false, true}) {
    const Context context = Context::WithThreads(2);
    std::mutex mutex;
    std::vector<int> done;
    {
      LevelSetupPipeline pipeline(
          {0},
          [&](int level) {
            std::this_thread::sleep_for(std::chrono::milliseconds(level == 0 ? 20 : 1));
            const std::lock_guard lock(mutex);
            done.push_back(level);
          },
          overlap, context, /*more_levels=*/true);
      // The caller adds the coarse levels while level 0 may still be set up (as the
      // hierarchical optimizer does once the hierarchy is built), then walks coarse to fine.
      pipeline.AddLevels({1, 2, 3});
      CHECK_THROWS_AS(pipeline.AddLevels({4}), InternalError);
      for (int level : {3, 2, 1, 0}) pipeline.WaitFor(level);
    }
    std::sort(done.begin(), done.end());
    CHECK(done == std::vector<int>{0, 1, 2, 3});
  }
}

TEST_CASE("LevelSetupPipeline stops a background task still waiting for levels", "[optimizers]") {
  // E.g. the hierarchy's build threw before AddLevels(): the destructor must not hang.
  const Context context = Context::WithThreads(2);
  std::atomic<int> calls{0};
  {
    LevelSetupPipeline pipeline(
        {0}, [&](int) { ++calls; }, /*overlap=*/true, context,
        /*more_levels=*/true);
    pipeline.WaitFor(0);
  }
  CHECK(calls == 1);
}

TEST_CASE("LevelSetupPipeline: a caller waiting for the last level helps with its parallel work",
          "[optimizers]") {
  // The background task sets level 0 up with a parallel loop; the caller, waiting for it with
  // nothing else left to set up, must run part of that loop (not block beside it: classic runs
  // and dragon-lift's finest level wait so). The background's own iterations wait (up to 20 s)
  // until another thread has run one, so the test does not depend on how fast the caller gets
  // there; without the caller's help it fails after those 20 s.
  const Context context = Context::WithThreads(2);
  std::atomic<bool> started{false};
  std::thread::id background;
  std::atomic<bool> helped{false};
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  std::mutex mutex;
  std::vector<std::thread::id> workers;
  {
    LevelSetupPipeline pipeline(
        {0},
        [&](int) {
          background = std::this_thread::get_id();
          started = true;
          context.Run([&] {
            tbb::parallel_for(0, 64, [&](int) {
              if (std::this_thread::get_id() == background) {
                while (!helped && std::chrono::steady_clock::now() < deadline) {
                  std::this_thread::sleep_for(std::chrono::milliseconds(1));
                }
              } else {
                helped = true;
              }
              const std::lock_guard lock(mutex);
              workers.push_back(std::this_thread::get_id());
            });
          });
        },
        /*overlap=*/true, context);
    // Wait until a worker has taken the background task (else WaitFor() runs the level itself).
    while (!started && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
    REQUIRE(started);
    pipeline.WaitFor(0);
  }
  const std::thread::id caller = std::this_thread::get_id();
  CHECK(workers.size() == 64);
  CHECK(std::count(workers.begin(), workers.end(), caller) > 0);
}
