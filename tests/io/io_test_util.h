// SPDX-License-Identifier: MIT
// Utilities shared by the io tests: scratch directories, file writing, topology checks.
#pragma once

#include <unistd.h>

#include <Eigen/Geometry>
#include <atomic>
#include <catch2/catch.hpp>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "framework/error.h"
#include "framework/mesh.h"

namespace harap::testing {

/// A fresh directory under the system temp folder, removed with everything in it at scope exit.
class ScratchDir {
 public:
  ScratchDir() {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("harap_io_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::filesystem::path& path() const { return path_; }

  /// Writes `bytes` to `name` inside the directory and returns the full path.
  std::filesystem::path Write(const std::string& name, std::string_view bytes) const {
    const std::filesystem::path file = path_ / name;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream stream(file, std::ios::binary | std::ios::trunc);
    stream.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    REQUIRE(stream.good());
    return file;
  }

 private:
  std::filesystem::path path_;
};

inline std::string ReadBytes(const std::filesystem::path& file) {
  std::ifstream stream(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>());
}

/// splitmix64, for reproducible test data independent of the standard library.
inline uint64_t NextRandom(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/// Applies one to four random edits to `bytes` (for robustness tests of the readers): overwrite a
/// byte with a random one or with a character that matters to text formats, truncate, or
/// duplicate a chunk.
inline void Mutate(std::string& bytes, uint64_t& state) {
  const int edits = 1 + static_cast<int>(NextRandom(state) % 4);
  for (int edit = 0; edit < edits && !bytes.empty(); ++edit) {
    const size_t at = NextRandom(state) % bytes.size();
    switch (NextRandom(state) % 4) {
      case 0:  // overwrite a byte
        bytes[at] = static_cast<char>(NextRandom(state));
        break;
      case 1:  // overwrite with a character that matters to the text formats
        bytes[at] = "0123456789-+.e /\n#nanif"[NextRandom(state) % 23];
        break;
      case 2:  // truncate
        bytes.resize(at);
        break;
      default:  // duplicate a chunk
        bytes.insert(at, bytes.substr(at, NextRandom(state) % 16));
        break;
    }
  }
}

/// Runs `run` and expects an InputError whose message contains every phrase.
template <class Run>
void ExpectInputError(Run run, const std::vector<std::string>& phrases) {
  try {
    run();
    FAIL("no exception");
  } catch (const InputError& error) {
    const std::string message = error.what();
    INFO("message: " << message);
    for (const std::string& phrase : phrases)
      CHECK_THAT(message, Catch::Matchers::Contains(phrase));
  }
}

/// Undirected edge -> number of incident triangles, and directed edge -> count.
struct EdgeCounts {
  std::map<std::pair<Index, Index>, int> undirected;
  std::map<std::pair<Index, Index>, int> directed;
};

inline EdgeCounts CountEdges(const Mesh& mesh) {
  EdgeCounts counts;
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    for (int a = 0; a < 3; ++a) {
      const Index u = mesh.elements(f, a);
      const Index v = mesh.elements(f, (a + 1) % 3);
      ++counts.undirected[{std::min(u, v), std::max(u, v)}];
      ++counts.directed[{u, v}];
    }
  }
  return counts;
}

/// Smallest interior angle (degrees) over all triangles.
inline double MinAngleDegrees(const Mesh& mesh) {
  double smallest = 180.0;
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d p = mesh.vertices.row(mesh.elements(f, a)).transpose();
      const Eigen::Vector3d q = mesh.vertices.row(mesh.elements(f, (a + 1) % 3)).transpose();
      const Eigen::Vector3d r = mesh.vertices.row(mesh.elements(f, (a + 2) % 3)).transpose();
      const double cosine = (q - p).normalized().dot((r - p).normalized());
      smallest = std::min(smallest, std::acos(std::clamp(cosine, -1.0, 1.0)) * 180.0 / M_PI);
    }
  }
  return smallest;
}

/// Smallest triangle area.
inline double MinArea(const Mesh& mesh) {
  double smallest = std::numeric_limits<double>::infinity();
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    const Eigen::Vector3d p = mesh.vertices.row(mesh.elements(f, 0)).transpose();
    const Eigen::Vector3d q = mesh.vertices.row(mesh.elements(f, 1)).transpose();
    const Eigen::Vector3d r = mesh.vertices.row(mesh.elements(f, 2)).transpose();
    smallest = std::min(smallest, 0.5 * (q - p).cross(r - p).norm());
  }
  return smallest;
}

/// Signed enclosed volume (positive for a closed surface with outward normals).
inline double SignedVolume(const Mesh& mesh) {
  double volume = 0.0;
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    const Eigen::Vector3d p = mesh.vertices.row(mesh.elements(f, 0)).transpose();
    const Eigen::Vector3d q = mesh.vertices.row(mesh.elements(f, 1)).transpose();
    const Eigen::Vector3d r = mesh.vertices.row(mesh.elements(f, 2)).transpose();
    volume += p.dot(q.cross(r)) / 6.0;
  }
  return volume;
}

}  // namespace harap::testing
