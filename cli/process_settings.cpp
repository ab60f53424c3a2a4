// SPDX-License-Identifier: MIT
#include "cli/process_settings.h"

#include <sys/resource.h>
#include <unistd.h>

#include <cstdlib>

#include "api/huge_pages.h"

namespace harap {

namespace {

/// Sets the single-threaded native libraries under `ulimit -v`; true if it changed anything.
bool SingleThreadedNativeLibrariesUnderMemoryLimit() {
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return false;
  if (std::getenv("HARAP_REEXECUTED_FOR_MEMORY_LIMIT") != nullptr) return false;
  if (std::getenv("OPENBLAS_NUM_THREADS") != nullptr &&
      std::getenv("OMP_THREAD_LIMIT") != nullptr) {
    return false;
  }
  setenv("HARAP_REEXECUTED_FOR_MEMORY_LIMIT", "1", 1);
  setenv("OPENBLAS_NUM_THREADS", "1", 0);
  setenv("OMP_THREAD_LIMIT", "1", 0);
  return true;
}

}  // namespace

void RestartWithProcessSettings(char** argv) {
  const bool memory_limit = SingleThreadedNativeLibrariesUnderMemoryLimit();
  const bool huge_pages = RequestHugePagesForMalloc();
  if (memory_limit || huge_pages) {
    execv("/proc/self/exe", argv);  // returns only if it failed: carry on as we are
  }
}

}  // namespace harap
