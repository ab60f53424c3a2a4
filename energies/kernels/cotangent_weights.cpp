// SPDX-License-Identifier: MIT
#include "energies/kernels/cotangent_weights.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>

namespace harap {

Eigen::Matrix<double, Eigen::Dynamic, 3> HalfCotangents(const Positions& vertices,
                                                        const Elements& triangles,
                                                        Index* num_degenerate) {
  const Index num_faces = static_cast<Index>(triangles.rows());
  Eigen::Matrix<double, Eigen::Dynamic, 3> weights(num_faces, 3);
  const Index degenerate = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Index>(0, num_faces, 4096), Index{0},
      [&](const tbb::blocked_range<Index>& range, Index local) {
        for (Index f = range.begin(); f != range.end(); ++f) {
          const Eigen::RowVector3d p[3] = {vertices.row(triangles(f, 0)),
                                           vertices.row(triangles(f, 1)),
                                           vertices.row(triangles(f, 2))};
          // Edge opposite corner a runs from corner a+1 to a+2.
          const Eigen::RowVector3d e[3] = {p[2] - p[1], p[0] - p[2], p[1] - p[0]};
          const double double_area = e[0].cross(e[1]).norm();
          const double longest = std::max({e[0].squaredNorm(), e[1].squaredNorm(),
                                            e[2].squaredNorm()});
          if (!(double_area > kDegenerateTriangleRatio * longest)) {
            weights.row(f).setZero();
            ++local;
            continue;
          }
          // cot(angle at a) = (e_b · e_c) / |e_b × e_c| with e_b, e_c the other two edges
          // pointing away from a: −e_b · e_c / (2·area).
          for (int a = 0; a < 3; ++a) {
            const int b = (a + 1) % 3, c = (a + 2) % 3;
            weights(f, a) = 0.5 * (-e[b].dot(e[c])) / double_area;
          }
        }
        return local;
      },
      std::plus<Index>());
  if (num_degenerate) *num_degenerate = degenerate;
  return weights;
}

}  // namespace harap
