// SPDX-License-Identifier: MIT
#include "energies/kernels/intrinsic_delaunay.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "framework/mesh.h"

namespace harap {

namespace {

constexpr Index kNoSide = -1;

// Flip only edges whose cot α + cot β is below this (dimensionless) bound, so round-off in an
// exactly Delaunay configuration (cot α + cot β = 0: four points on a circle) cannot make two
// flips undo each other forever.
constexpr double kDelaunayTolerance = 1e-10;

// Twice the area of a triangle with side lengths a, b, c (Kahan's formulation of Heron's formula,
// accurate for needle-shaped triangles); 0 when the lengths violate the triangle inequality.
double DoubleArea(double a, double b, double c) {
  if (a < b) std::swap(a, b);
  if (a < c) std::swap(a, c);
  if (b < c) std::swap(b, c);
  const double product = (a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c));
  return product > 0.0 ? 0.5 * std::sqrt(product) : 0.0;
}

bool Degenerate(double double_area, double a, double b, double c) {
  const double longest = std::max({a, b, c});
  return !(double_area > kDegenerateTriangleRatio * longest * longest);
}

// cot of the angle opposite the side of length `opposite`, between sides b and c.
double Cotangent(double opposite, double b, double c, double double_area) {
  return (b * b + c * c - opposite * opposite) / (2.0 * double_area);
}

// Side s = 3f + k of face f is the side opposite corner k; it runs from corner k + 1 to k + 2.
Index SideOf(Index face, int corner) { return 3 * face + corner; }
int Next(int corner) { return (corner + 1) % 3; }
int Prev(int corner) { return (corner + 2) % 3; }

class Flipper {
 public:
  Flipper(const Positions& vertices, const Elements& triangles)
      : triangles_(triangles),
        lengths_(triangles.rows(), 3),
        cot_(triangles.rows(), 3),
        degenerate_(static_cast<size_t>(triangles.rows()), 0) {
    const Index num_faces = static_cast<Index>(triangles.rows());
    for (Index f = 0; f < num_faces; ++f) {
      for (int k = 0; k < 3; ++k) {
        lengths_(f, k) =
            (vertices.row(triangles(f, Next(k))) - vertices.row(triangles(f, Prev(k)))).norm();
      }
      UpdateCotangents(f);
    }
    FindTwins(triangles.rows() > 0 ? triangles.maxCoeff() + 1 : 0);
  }

  IntrinsicTriangulation Run() {
    const Index num_sides = 3 * static_cast<Index>(triangles_.rows());
    std::vector<Index> queue;
    std::vector<char> queued(num_sides, 0);
    for (Index s = 0; s < num_sides; ++s) {
      queue.push_back(s);
      queued[s] = 1;
    }
    IntrinsicTriangulation result;
    // Each flip strictly lowers the Dirichlet energy, so the loop ends; the bound only guards
    // against round-off cycles the tolerance does not catch.
    const Index max_flips = 20 * num_sides + 1000;
    while (!queue.empty()) {
      const Index s = queue.back();
      queue.pop_back();
      queued[s] = 0;
      if (twin_[s] == kNoSide || CotangentSum(s) >= -kDelaunayTolerance) continue;
      if (result.flips >= max_flips || !Flip(s)) continue;
      ++result.flips;
      // The four sides around the new edge may have stopped being Delaunay.
      for (const Index f : {s / 3, twin_[s] / 3}) {
        for (int k = 0; k < 3; ++k) {
          const Index side = SideOf(f, k);
          if (!queued[side]) {
            queue.push_back(side);
            queued[side] = 1;
          }
        }
      }
    }
    // The faces' cotangents are current (UpdateCotangents after every flip): the same values
    // HalfCotangentsFromLengths(lengths_) computes.
    result.half_cot = 0.5 * cot_;
    for (Index f = 0; f < static_cast<Index>(degenerate_.size()); ++f) {
      if (degenerate_[f]) ++result.degenerate;
    }
    // Each edge once (a side without twin, or the smaller of two twins): weights that stay
    // negative are set to zero.
    for (Index s = 0; s < num_sides; ++s) {
      const Index t = twin_[s];
      if (t != kNoSide && t < s) continue;
      double& w_s = result.half_cot(s / 3, static_cast<int>(s % 3));
      if (t == kNoSide) {
        if (w_s < 0.0) {
          w_s = 0.0;
          ++result.zeroed_edges;
        }
        continue;
      }
      double& w_t = result.half_cot(t / 3, static_cast<int>(t % 3));
      if (w_s + w_t < 0.0) {
        w_s = w_t = 0.0;
        ++result.zeroed_edges;
      }
    }
    result.triangles = std::move(triangles_);
    result.lengths = std::move(lengths_);
    return result;
  }

 private:
  double Length(Index side) const { return lengths_(side / 3, static_cast<int>(side % 3)); }
  double& Length(Index side) { return lengths_(side / 3, static_cast<int>(side % 3)); }
  Index Corner(Index face, int k) const { return triangles_(face, k); }

  // The cotangents of face f's corners from its side lengths (zero, and the face marked
  // degenerate, if it has no defined angles): computed once per face and after each flip instead
  // of twice per side test.
  void UpdateCotangents(Index f) {
    const double l[3] = {lengths_(f, 0), lengths_(f, 1), lengths_(f, 2)};
    const double double_area = DoubleArea(l[0], l[1], l[2]);
    degenerate_[static_cast<size_t>(f)] = Degenerate(double_area, l[0], l[1], l[2]);
    for (int k = 0; k < 3; ++k) {
      cot_(f, k) = degenerate_[static_cast<size_t>(f)]
                       ? 0.0
                       : Cotangent(l[k], l[Next(k)], l[Prev(k)], double_area);
    }
  }

  // Pairs each side with the one side of the neighbouring face that runs the opposite way along
  // the same edge; sides on boundaries, at non-manifold edges or between faces of opposite
  // orientation keep kNoSide and are never flipped.
  void FindTwins(Index num_vertices) {
    const Index num_sides = 3 * static_cast<Index>(triangles_.rows());
    struct Key {
      Index low, high, side;
    };
    // Sorted by (low, high, side): a counting sort by the lower vertex (sides in order within a
    // bucket), then each bucket (a vertex's few edges) by the higher one.
    std::vector<Index> bucket_start(static_cast<size_t>(num_vertices) + 1, 0);
    const auto ends = [&](Index s) {
      const Index f = s / 3;
      const int k = static_cast<int>(s % 3);
      const Index from = Corner(f, Next(k)), to = Corner(f, Prev(k));
      return std::pair{std::min(from, to), std::max(from, to)};
    };
    for (Index s = 0; s < num_sides; ++s) ++bucket_start[static_cast<size_t>(ends(s).first) + 1];
    for (size_t v = 1; v < bucket_start.size(); ++v) bucket_start[v] += bucket_start[v - 1];
    std::vector<Key> keys(static_cast<size_t>(num_sides));
    std::vector<Index> fill(bucket_start.begin(), bucket_start.end() - 1);
    for (Index s = 0; s < num_sides; ++s) {
      const auto [low, high] = ends(s);
      keys[static_cast<size_t>(fill[static_cast<size_t>(low)]++)] = {low, high, s};
    }
    for (size_t v = 0; v + 1 < bucket_start.size(); ++v) {
      // Stable: equal ends keep the sides' order.
      std::stable_sort(keys.begin() + bucket_start[v], keys.begin() + bucket_start[v + 1],
                       [](const Key& x, const Key& y) { return x.high < y.high; });
    }
    twin_.assign(num_sides, kNoSide);
    for (size_t begin = 0; begin < keys.size();) {
      size_t end = begin + 1;
      while (end < keys.size() && keys[end].low == keys[begin].low &&
             keys[end].high == keys[begin].high) {
        ++end;
      }
      if (end - begin == 2) {
        const Index s = keys[begin].side, t = keys[begin + 1].side;
        // Opposite directions: s runs from `from` to `to`, t from `to` to `from`.
        const Index s_from = Corner(s / 3, Next(static_cast<int>(s % 3)));
        const Index t_from = Corner(t / 3, Next(static_cast<int>(t % 3)));
        if (s_from != t_from && s / 3 != t / 3) {
          twin_[s] = t;
          twin_[t] = s;
        }
      }
      begin = end;
    }
  }

  // cot α + cot β of the edge of side s (α, β the angles opposite it; cot α alone for a side
  // without twin); 0 next to a degenerate triangle, whose weights are zero.
  double CotangentSum(Index s) const {
    double sum = 0.0;
    for (const Index side : {s, twin_[s]}) {
      if (side == kNoSide) continue;
      const Index f = side / 3;
      if (degenerate_[static_cast<size_t>(f)]) return 0.0;
      sum += cot_(f, static_cast<int>(side % 3));
    }
    return sum;
  }

  // Replaces the edge of side s by the other diagonal of its two triangles. Face f1 = (a, b, c)
  // with s opposite a (the edge b→c), face f2 = (d, c, b) with its twin t opposite d; they become
  // f1 = (a, b, d) and f2 = (d, c, a). Returns false (and changes nothing) if the flip would join
  // a vertex to itself or leave a degenerate triangle.
  bool Flip(Index s) {
    const Index t = twin_[s];
    const Index f1 = s / 3, f2 = t / 3;
    const int k1 = static_cast<int>(s % 3), k2 = static_cast<int>(t % 3);
    const Index a = Corner(f1, k1), b = Corner(f1, Next(k1)), c = Corner(f1, Prev(k1));
    const Index d = Corner(f2, k2);
    if (a == d) return false;
    const Index side_ca = SideOf(f1, Next(k1)), side_ab = SideOf(f1, Prev(k1));
    const Index side_bd = SideOf(f2, Next(k2)), side_dc = SideOf(f2, Prev(k2));
    const double l_bc = Length(s), l_ca = Length(side_ca), l_ab = Length(side_ab),
                 l_bd = Length(side_bd), l_dc = Length(side_dc);
    // Unfold: b at the origin, c on the positive x-axis, a above and d below it.
    const double area_abc = DoubleArea(l_bc, l_ca, l_ab), area_dcb = DoubleArea(l_bc, l_dc, l_bd);
    const double x_a = (l_ab * l_ab - l_ca * l_ca + l_bc * l_bc) / (2.0 * l_bc);
    const double y_a = area_abc / l_bc;
    const double x_d = (l_bd * l_bd - l_dc * l_dc + l_bc * l_bc) / (2.0 * l_bc);
    const double y_d = -area_dcb / l_bc;
    const double l_ad = std::hypot(x_a - x_d, y_a - y_d);
    const double area_abd = DoubleArea(l_bd, l_ad, l_ab), area_dca = DoubleArea(l_ca, l_ad, l_dc);
    if (Degenerate(area_abd, l_bd, l_ad, l_ab) || Degenerate(area_dca, l_ca, l_ad, l_dc)) {
      return false;
    }
    const Index twin_ca = twin_[side_ca], twin_ab = twin_[side_ab];
    const Index twin_bd = twin_[side_bd], twin_dc = twin_[side_dc];
    // f1 = (a, b, d): opposite a the side b→d, opposite b the new side d→a, opposite d a→b.
    triangles_.row(f1) << a, b, d;
    // f2 = (d, c, a): opposite d the side c→a, opposite c the new side a→d, opposite a d→c.
    triangles_.row(f2) << d, c, a;
    lengths_.row(f1) << l_bd, l_ad, l_ab;
    lengths_.row(f2) << l_ca, l_ad, l_dc;
    UpdateCotangents(f1);
    UpdateCotangents(f2);
    auto link = [&](Index side, Index other) {
      twin_[side] = other;
      if (other != kNoSide) twin_[other] = side;
    };
    link(SideOf(f1, 0), twin_bd);
    link(SideOf(f1, 1), SideOf(f2, 1));
    link(SideOf(f1, 2), twin_ab);
    link(SideOf(f2, 0), twin_ca);
    link(SideOf(f2, 2), twin_dc);
    return true;
  }

  Elements triangles_;
  Eigen::Matrix<double, Eigen::Dynamic, 3> lengths_;
  Eigen::Matrix<double, Eigen::Dynamic, 3> cot_;  ///< cot of each corner's angle (0: degenerate)
  std::vector<char> degenerate_;                  ///< per face
  std::vector<Index> twin_;
};

}  // namespace

IntrinsicTriangulation IntrinsicDelaunayTriangulation(const Positions& vertices,
                                                      const Elements& triangles) {
  return Flipper(vertices, triangles).Run();
}

Eigen::Matrix<double, Eigen::Dynamic, 3> HalfCotangentsFromLengths(
    const Eigen::Matrix<double, Eigen::Dynamic, 3>& lengths, Index* num_degenerate) {
  Eigen::Matrix<double, Eigen::Dynamic, 3> half_cot(lengths.rows(), 3);
  Index degenerate = 0;
  for (Index f = 0; f < lengths.rows(); ++f) {
    const double l[3] = {lengths(f, 0), lengths(f, 1), lengths(f, 2)};
    const double double_area = DoubleArea(l[0], l[1], l[2]);
    if (Degenerate(double_area, l[0], l[1], l[2])) {
      half_cot.row(f).setZero();
      ++degenerate;
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      half_cot(f, k) = 0.5 * Cotangent(l[k], l[Next(k)], l[Prev(k)], double_area);
    }
  }
  if (num_degenerate) *num_degenerate = degenerate;
  return half_cot;
}

}  // namespace harap
