// SPDX-License-Identifier: MIT
#include <cstdlib>

#include "tests/support/shared_data.h"

namespace harap::testing {

std::filesystem::path SharedDir() {
  if (const char* env = std::getenv("HARAP_SHARED")) return env;
  return HARAP_SHARED_DIR;
}

std::filesystem::path SourceDir() { return HARAP_SOURCE_DIR; }

std::string HarapExecutable() { return HARAP_EXECUTABLE; }

}  // namespace harap::testing
