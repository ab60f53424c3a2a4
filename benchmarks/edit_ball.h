// SPDX-License-Identifier: MIT
// What the session and handle-edit benchmarks share: their scenario, registration and the ball
// of vertices an edit adds.
#pragma once

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <numeric>
#include <string>
#include <vector>

#include "framework/mesh.h"

namespace harap {

/// The scenario the session and handle-edit benchmarks run on (armadillo-bend, 173K vertices,
/// from the shared data folder beside the repository; the benchmarks register nothing without it).
inline const std::filesystem::path& ArmadilloBendScenario() {
  static const std::filesystem::path path =
      std::filesystem::path(HARAP_SHARED_DIR) / "scenarios/armadillo-bend.toml";
  return path;
}

/// Registers `function(state, args...)` as "<name>/armadillo-bend", timed in milliseconds of
/// wall-clock time (the solves use more than one thread).
template <class Function, class... Args>
void RegisterArmadilloBendBenchmark(const std::string& name, Function function, Args... args) {
  benchmark::RegisterBenchmark((name + "/armadillo-bend").c_str(), function, args...)
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
}

/// The handle-edit benchmarks' ball: the `fraction` of the mesh's vertices nearest to a free
/// vertex on the surface halfway up the mesh (largest x at mid height), without the vertices in
/// `handles`; sorted.
inline std::vector<Index> EditBall(const Mesh& mesh, const std::vector<Index>& handles,
                                   double fraction) {
  const Index n = mesh.num_vertices();
  std::vector<char> handle(n, 0);
  for (Index v : handles) handle[v] = 1;
  const Positions& p = mesh.vertices;
  const double low = p.col(1).minCoeff(), high = p.col(1).maxCoeff();
  Index centre = -1;
  for (Index v = 0; v < n; ++v) {
    if (handle[v] || std::abs(p(v, 1) - 0.5 * (low + high)) > 0.02 * (high - low)) continue;
    if (centre < 0 || p(v, 0) > p(centre, 0)) centre = v;
  }
  std::vector<Index> order(n);
  std::iota(order.begin(), order.end(), 0);
  const auto distance = [&](Index v) { return (p.row(v) - p.row(centre)).squaredNorm(); };
  const size_t size = static_cast<size_t>(fraction * static_cast<double>(n));
  std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(size), order.end(),
                   [&](Index x, Index y) { return distance(x) < distance(y); });
  std::vector<Index> ball;
  for (size_t k = 0; k < size; ++k) {
    if (!handle[order[k]]) ball.push_back(order[k]);
  }
  std::sort(ball.begin(), ball.end());
  return ball;
}

}  // namespace harap
