// SPDX-License-Identifier: MIT
#include "spatial/surface_sampling.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "framework/error.h"

namespace harap {

namespace {

// A uniform double in [0, 1) from the generator's top 53 bits.
double Uniform(std::mt19937_64& random) { return static_cast<double>(random() >> 11) * 0x1.0p-53; }

// A uniform index in [0, size), by the same mapping (size far below 2^53).
Index UniformIndex(std::mt19937_64& random, Index size) {
  return std::min(size - 1, static_cast<Index>(Uniform(random) * static_cast<double>(size)));
}

// A standard normal variate (Box–Muller), for directions uniform on the sphere.
double Gaussian(std::mt19937_64& random) {
  const double u = 1.0 - Uniform(random);  // in (0, 1]: the logarithm stays finite
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * M_PI * Uniform(random));
}

}  // namespace

SampledPoints SampleSurface(const Mesh& mesh, Index count, std::uint64_t seed) {
  if (mesh.kind() != ElementKind::kTriangle) {
    throw InputError("surface sampling needs a triangle mesh (a tetrahedral one: its boundary)");
  }
  if (count < 0) throw InputError(fmt::format("cannot sample {} points", count));
  const Index faces = mesh.num_elements();
  // Cumulative areas: a triangle is picked by a binary search of a uniform value in them.
  std::vector<double> cumulative(static_cast<size_t>(faces));
  Positions normals(faces, 3);
  double total = 0.0;
  for (Index f = 0; f < faces; ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.elements(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.elements(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.elements(f, 2));
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    const double twice_area = cross.norm();
    normals.row(f) =
        twice_area > 0.0 ? Eigen::Vector3d(cross / twice_area) : Eigen::Vector3d::Zero();
    total += std::isfinite(twice_area) ? 0.5 * twice_area : 0.0;
    cumulative[static_cast<size_t>(f)] = total;
  }
  if (!(total > 0.0)) {
    throw InputError("cannot sample a surface without triangles of positive area");
  }
  std::mt19937_64 random(seed);
  SampledPoints sample;
  sample.points.resize(count, 3);
  sample.normals.resize(count, 3);
  for (Index k = 0; k < count; ++k) {
    const double pick = Uniform(random) * total;
    const Index f = std::min<Index>(
        faces - 1, static_cast<Index>(std::upper_bound(cumulative.begin(), cumulative.end(), pick) -
                                      cumulative.begin()));
    // Uniform in the triangle: the square-root warp of two uniforms (Osada et al. 2002).
    const double s = std::sqrt(Uniform(random)), t = Uniform(random);
    sample.points.row(k) = (1.0 - s) * mesh.vertices.row(mesh.elements(f, 0)) +
                           s * (1.0 - t) * mesh.vertices.row(mesh.elements(f, 1)) +
                           s * t * mesh.vertices.row(mesh.elements(f, 2));
    sample.normals.row(k) = normals.row(f);
  }
  return sample;
}

SampledPoints DamagePoints(const SampledPoints& sample, const PointDamage& damage,
                           std::uint64_t seed) {
  const Index n = sample.points.rows();
  if (n == 0) throw InputError("cannot damage an empty point sample");
  for (const auto& [name, value] :
       {std::pair{"removed", damage.removed}, std::pair{"outliers", damage.outliers},
        std::pair{"outlier_margin", damage.outlier_margin}}) {
    if (!(value >= 0.0 && value < 1.0)) {
      throw InputError(fmt::format("point damage: {} = {} must lie in [0, 1)", name, value));
    }
  }
  std::mt19937_64 random(seed);
  // The hole: the `removed` fraction of the points nearest a random one.
  const Eigen::Vector3d center = sample.points.row(UniformIndex(random, n));
  std::vector<Index> order(static_cast<size_t>(n));
  std::iota(order.begin(), order.end(), Index{0});
  std::vector<double> distance(static_cast<size_t>(n));
  for (Index k = 0; k < n; ++k) {
    distance[static_cast<size_t>(k)] = (sample.points.row(k).transpose() - center).squaredNorm();
  }
  // Ties broken by index, so the hole does not depend on the sort's algorithm.
  std::sort(order.begin(), order.end(), [&](Index a, Index b) {
    return std::pair(distance[static_cast<size_t>(a)], a) <
           std::pair(distance[static_cast<size_t>(b)], b);
  });
  const auto removed = static_cast<size_t>(damage.removed * static_cast<double>(n));
  std::vector<Index> kept(order.begin() + static_cast<std::ptrdiff_t>(removed), order.end());
  std::sort(kept.begin(), kept.end());
  const auto kept_count = static_cast<Index>(kept.size());
  const auto outliers = static_cast<Index>(damage.outliers * static_cast<double>(kept_count));

  SampledPoints damaged;
  damaged.points.resize(kept_count + outliers, 3);
  damaged.normals.resize(kept_count + outliers, 3);
  for (Index k = 0; k < kept_count; ++k) {
    damaged.points.row(k) = sample.points.row(kept[static_cast<size_t>(k)]);
    damaged.normals.row(k) = sample.normals.row(kept[static_cast<size_t>(k)]);
  }
  const Eigen::Vector3d low = damaged.points.topRows(kept_count).colwise().minCoeff();
  const Eigen::Vector3d high = damaged.points.topRows(kept_count).colwise().maxCoeff();
  const Eigen::Vector3d margin = damage.outlier_margin * (high - low);
  for (Index k = kept_count; k < kept_count + outliers; ++k) {
    for (int axis = 0; axis < 3; ++axis) {
      damaged.points(k, axis) =
          low[axis] - margin[axis] + Uniform(random) * (high[axis] - low[axis] + 2 * margin[axis]);
    }
    Eigen::Vector3d direction(Gaussian(random), Gaussian(random), Gaussian(random));
    damaged.normals.row(k) = direction / std::max(direction.norm(), 1e-300);
  }
  return damaged;
}

}  // namespace harap
