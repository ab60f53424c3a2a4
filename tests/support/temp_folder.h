// SPDX-License-Identifier: MIT
// A scratch folder for tests that write input files and run harap on them.
#pragma once

#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace harap::testing {

/// A fresh folder harap-`name`-<pid> under the system temp folder, removed with everything in
/// it at scope exit. `name` keeps test cases apart (give each its own), the pid concurrent runs.
struct TempFolder {
  explicit TempFolder(const std::string& name)
      : dir(std::filesystem::temp_directory_path() / fmt::format("harap-{}-{}", name, getpid())) {
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
  }
  ~TempFolder() {
    std::error_code ignore;
    std::filesystem::remove_all(dir, ignore);
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;

  /// Writes `text` to `name` in the folder; returns the file's path.
  std::string Write(const std::string& name, const std::string& text) const {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  }

  std::filesystem::path dir;
};

/// The whole of `file` ("" if it cannot be read).
inline std::string ReadText(const std::filesystem::path& file) {
  std::ifstream stream(file, std::ios::binary);
  std::stringstream buffer;
  buffer << stream.rdbuf();
  return buffer.str();
}

}  // namespace harap::testing
