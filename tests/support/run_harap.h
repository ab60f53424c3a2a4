// SPDX-License-Identifier: MIT
#pragma once

#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <string>

#include "tests/support/shared_data.h"

namespace harap::testing {

struct CommandResult {
  int status = -1;     ///< Exit status; 128 + N if killed by signal N.
  std::string output;  ///< stdout and stderr together.
};

/// Runs a shell command and collects its exit status and output (stderr included).
inline CommandResult RunCommand(const std::string& command) {
  CommandResult result;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  REQUIRE(pipe);
  char buffer[4096];
  while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) result.output.append(buffer, n);
  const int status = pclose(pipe);
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}

/// Runs the harap executable of this build with `arguments`.
inline CommandResult RunHarap(const std::string& arguments) {
  return RunCommand(::harap::testing::HarapExecutable() + " " + arguments);
}

}  // namespace harap::testing
