// SPDX-License-Identifier: MIT
#include "energies/kernels/cotangent_weights.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace harap {

namespace {

/// Fills one row of weights per element in parallel: `fill(e)` writes row e and returns false if
/// the element is degenerate (its row then zeroed). Returns the number of degenerate elements,
/// also into `num_degenerate` if given.
template <int Columns, class Fill>
Eigen::Matrix<double, Eigen::Dynamic, Columns> ElementWeights(Index num_elements,
                                                              Index* num_degenerate, Fill&& fill) {
  Eigen::Matrix<double, Eigen::Dynamic, Columns> weights(num_elements, Columns);
  const Index degenerate = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Index>(0, num_elements, 4096), Index{0},
      [&](const tbb::blocked_range<Index>& range, Index local) {
        for (Index e = range.begin(); e != range.end(); ++e) {
          if (!fill(weights, e)) {
            weights.row(e).setZero();
            ++local;
          }
        }
        return local;
      },
      std::plus<Index>());
  if (num_degenerate) *num_degenerate = degenerate;
  return weights;
}

}  // namespace

Eigen::Matrix<double, Eigen::Dynamic, 3> HalfCotangents(const Positions& vertices,
                                                        const Elements& triangles,
                                                        Index* num_degenerate) {
  auto fill = [&](auto& weights, Index f) {
    const Eigen::RowVector3d p[3] = {vertices.row(triangles(f, 0)), vertices.row(triangles(f, 1)),
                                     vertices.row(triangles(f, 2))};
    // Edge opposite corner a runs from corner a+1 to a+2.
    const Eigen::RowVector3d e[3] = {p[2] - p[1], p[0] - p[2], p[1] - p[0]};
    const double double_area = e[0].cross(e[1]).norm();
    const double longest = std::max({e[0].squaredNorm(), e[1].squaredNorm(), e[2].squaredNorm()});
    if (!(double_area > kDegenerateTriangleRatio * longest)) return false;
    // cot(angle at a) = (e_b · e_c) / |e_b × e_c| with e_b, e_c the other two edges
    // pointing away from a: −e_b · e_c / (2·area).
    for (int a = 0; a < 3; ++a) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      weights(f, a) = 0.5 * (-e[b].dot(e[c])) / double_area;
    }
    return true;
  };
  return ElementWeights<3>(static_cast<Index>(triangles.rows()), num_degenerate, fill);
}

Eigen::Matrix<double, Eigen::Dynamic, 6> TetrahedronCotangentWeights(const Positions& vertices,
                                                                     const Elements& tetrahedra,
                                                                     Index* num_degenerate) {
  auto fill = [&](auto& weights, Index t) {
    const Eigen::Vector3d p0 = vertices.row(tetrahedra(t, 0)).transpose();
    const Eigen::Vector3d e1 = vertices.row(tetrahedra(t, 1)).transpose() - p0;
    const Eigen::Vector3d e2 = vertices.row(tetrahedra(t, 2)).transpose() - p0;
    const Eigen::Vector3d e3 = vertices.row(tetrahedra(t, 3)).transpose() - p0;
    // With D = [e1 e2 e3], the rows of D⁻¹ are ∇φ_1..3 = (e2×e3, e3×e1, e1×e2)/det D and
    // ∇φ_0 = −Σ. So w_ab = −vol ∇φ_a·∇φ_b = −(c_a·c_b)/(6|det D|): the sign of det D (the
    // orientation) cancels.
    std::array<Eigen::Vector3d, 4> c;
    c[1] = e2.cross(e3);
    c[2] = e3.cross(e1);
    c[3] = e1.cross(e2);
    c[0] = -(c[1] + c[2] + c[3]);
    const double six_volume = std::abs(e1.dot(c[1]));
    const double longest = std::sqrt(
        std::max({e1.squaredNorm(), e2.squaredNorm(), e3.squaredNorm(), (e2 - e1).squaredNorm(),
                  (e3 - e1).squaredNorm(), (e3 - e2).squaredNorm()}));
    if (!(six_volume > kDegenerateTetrahedronRatio * longest * longest * longest)) return false;
    for (int edge = 0; edge < 6; ++edge) {
      const auto [a, b] = kTetrahedronEdges[edge];
      weights(t, edge) = -c[a].dot(c[b]) / (6.0 * six_volume);
    }
    return true;
  };
  return ElementWeights<6>(static_cast<Index>(tetrahedra.rows()), num_degenerate, fill);
}

}  // namespace harap
