// SPDX-License-Identifier: MIT
#include "energies/kernels/cotangent_weights.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
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

Eigen::VectorXd MixedVoronoiAreas(const Positions& vertices, const Elements& triangles) {
  const Index num_faces = static_cast<Index>(triangles.rows());
  // Corner areas per face in parallel, then a serial scatter (vertices are shared by faces).
  Eigen::Matrix<double, Eigen::Dynamic, 3> corner(num_faces, 3);
  tbb::parallel_for(
      tbb::blocked_range<Index>(0, num_faces, 4096), [&](const tbb::blocked_range<Index>& range) {
        for (Index f = range.begin(); f != range.end(); ++f) {
          const Eigen::RowVector3d p[3] = {vertices.row(triangles(f, 0)),
                                           vertices.row(triangles(f, 1)),
                                           vertices.row(triangles(f, 2))};
          // Edge opposite corner a runs from corner a+1 to a+2 (as in HalfCotangents).
          const Eigen::RowVector3d e[3] = {p[2] - p[1], p[0] - p[2], p[1] - p[0]};
          const double double_area = e[0].cross(e[1]).norm();
          const double squared[3] = {e[0].squaredNorm(), e[1].squaredNorm(), e[2].squaredNorm()};
          if (!(double_area > kDegenerateTriangleRatio *
                                  std::max({squared[0], squared[1], squared[2]}))) {
            corner.row(f).setZero();
            continue;
          }
          // −e_b·e_c is |e_b||e_c| cos(angle at a): negative at an obtuse corner.
          double cot[3];
          int obtuse = -1;
          for (int a = 0; a < 3; ++a) {
            const double dot = -e[(a + 1) % 3].dot(e[(a + 2) % 3]);
            cot[a] = dot / double_area;
            if (dot < 0.0) obtuse = a;
          }
          const double area = 0.5 * double_area;
          for (int a = 0; a < 3; ++a) {
            if (obtuse >= 0) {
              corner(f, a) = a == obtuse ? 0.5 * area : 0.25 * area;
            } else {
              // The two edges at corner a are e_b and e_c (opposite corners b and c).
              const int b = (a + 1) % 3, c = (a + 2) % 3;
              corner(f, a) = 0.125 * (squared[b] * cot[b] + squared[c] * cot[c]);
            }
          }
        }
      });
  Eigen::VectorXd areas = Eigen::VectorXd::Zero(vertices.rows());
  for (Index f = 0; f < num_faces; ++f) {
    for (int a = 0; a < 3; ++a) areas(triangles(f, a)) += corner(f, a);
  }
  return areas;
}

}  // namespace harap
