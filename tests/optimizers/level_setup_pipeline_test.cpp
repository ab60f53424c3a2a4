// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include "framework/error.h"
#include "solvers/optimizers/level_setup_pipeline.h"

using namespace harap;

TEST_CASE("LevelSetupPipeline sets every level up once, also levels added later",
          "[optimizers]") {
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

TEST_CASE("LevelSetupPipeline stops a background task still waiting for levels",
          "[optimizers]") {
  // E.g. the hierarchy's build threw before AddLevels(): the destructor must not hang.
  const Context context = Context::WithThreads(2);
  std::atomic<int> calls{0};
  {
    LevelSetupPipeline pipeline({0}, [&](int) { ++calls; }, /*overlap=*/true, context,
                                /*more_levels=*/true);
    pipeline.WaitFor(0);
  }
  CHECK(calls == 1);
}
