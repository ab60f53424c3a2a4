// SPDX-License-Identifier: MIT
#include "energies/kernels/cotangent_weights.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace harap {

namespace {

// One triangle's edges (edge a is opposite corner a and runs from corner a+1 to a+2), twice its
// area, and whether it is degenerate (area ≤ kDegenerateTriangleRatio · longest edge²).
struct TriangleGeometry {
  TriangleGeometry(const Positions& vertices, const Elements& triangles, Index f) {
    const Eigen::RowVector3d p[3] = {vertices.row(triangles(f, 0)), vertices.row(triangles(f, 1)),
                                     vertices.row(triangles(f, 2))};
    edge[0] = p[2] - p[1];
    edge[1] = p[0] - p[2];
    edge[2] = p[1] - p[0];
    double_area = edge[0].cross(edge[1]).norm();
    const double longest =
        std::max({edge[0].squaredNorm(), edge[1].squaredNorm(), edge[2].squaredNorm()});
    degenerate = !(double_area > kDegenerateTriangleRatio * longest);
  }
  // −e_b · e_c = |e_b| |e_c| cos(angle at a), e_b and e_c the two edges at corner a.
  double CornerDot(int a) const { return -edge[(a + 1) % 3].dot(edge[(a + 2) % 3]); }

  Eigen::RowVector3d edge[3];
  double double_area;
  bool degenerate;
};

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
    const TriangleGeometry triangle(vertices, triangles, f);
    if (triangle.degenerate) return false;
    // cot(angle at a) = cos / sin = (−e_b · e_c) / (2·area).
    for (int a = 0; a < 3; ++a) weights(f, a) = 0.5 * triangle.CornerDot(a) / triangle.double_area;
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

Eigen::VectorXd MixedVoronoiAreas(const Positions& vertices, const Elements& triangles) {
  const Index num_faces = static_cast<Index>(triangles.rows());
  // Corner areas per face in parallel, then a serial scatter (vertices are shared by faces).
  Eigen::Matrix<double, Eigen::Dynamic, 3> corner(num_faces, 3);
  tbb::parallel_for(tbb::blocked_range<Index>(0, num_faces, 4096),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index f = range.begin(); f != range.end(); ++f) {
                        const TriangleGeometry triangle(vertices, triangles, f);
                        if (triangle.degenerate) {
                          corner.row(f).setZero();
                          continue;
                        }
                        double cot[3], squared[3];
                        int obtuse = -1;
                        for (int a = 0; a < 3; ++a) {
                          const double dot = triangle.CornerDot(a);  // negative at an obtuse corner
                          cot[a] = dot / triangle.double_area;
                          squared[a] = triangle.edge[a].squaredNorm();
                          if (dot < 0.0) obtuse = a;
                        }
                        const double area = 0.5 * triangle.double_area;
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
