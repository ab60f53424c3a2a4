// SPDX-License-Identifier: MIT
#pragma once

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace harap::testing {

// The build's paths are compiled into build_paths.cpp alone, so that no other test object
// depends on where the checkout is (compiler caches then serve every checkout alike).

/// The shared data folder beside the repository (../shared), or $HARAP_SHARED if set.
std::filesystem::path SharedDir();
/// The repository's root folder.
std::filesystem::path SourceDir();
/// The harap executable of this build.
std::string HarapExecutable();

/// Path of a file under ../shared, or an empty path if the shared folder (or the file) is absent.
inline std::filesystem::path SharedFile(const std::string& relative) {
  std::filesystem::path path = SharedDir() / relative;
  return std::filesystem::exists(path) ? path : std::filesystem::path();
}

}  // namespace harap::testing

/// Skips the current test (with a clear message) when a shared file is missing.
#define HARAP_REQUIRE_SHARED(var, relative)                                              \
  const std::filesystem::path var = ::harap::testing::SharedFile(relative);              \
  if (var.empty()) {                                                                     \
    WARN("skipped: " << relative << " not found under " << ::harap::testing::SharedDir() \
                     << " (the shared data folder beside the repository)");              \
    return;                                                                              \
  }
