// SPDX-License-Identifier: MIT
#pragma once

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace harap::testing {

/// The shared data folder beside the repository (../shared), or $HARAP_SHARED if set.
inline std::filesystem::path SharedDir() {
  if (const char* env = std::getenv("HARAP_SHARED")) return env;
  return HARAP_SHARED_DIR;
}

/// Path of a file under ../shared, or an empty path if the shared folder (or the file) is absent.
inline std::filesystem::path SharedFile(const std::string& relative) {
  std::filesystem::path path = SharedDir() / relative;
  return std::filesystem::exists(path) ? path : std::filesystem::path();
}

inline std::filesystem::path SourceDir() { return HARAP_SOURCE_DIR; }

}  // namespace harap::testing

/// Skips the current test (with a clear message) when a shared file is missing.
#define HARAP_REQUIRE_SHARED(var, relative)                                              \
  const std::filesystem::path var = ::harap::testing::SharedFile(relative);              \
  if (var.empty()) {                                                                     \
    WARN("skipped: " << relative << " not found under " << ::harap::testing::SharedDir() \
                     << " (the shared data folder beside the repository)");              \
    return;                                                                              \
  }
