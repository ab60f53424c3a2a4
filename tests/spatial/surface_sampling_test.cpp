// SPDX-License-Identifier: MIT
// Points sampled on a surface and damaged: where they lie, how many, how they are spread, and
// that a seed reproduces them.
#include "spatial/surface_sampling.h"

#include <catch2/catch.hpp>

#include "framework/error.h"

namespace harap {
namespace {

// Two triangles in the plane z = 1 with areas 1/2 (x in [0, 1]) and 3/2 (x in [1, 4]).
Mesh TwoTriangles() {
  Mesh mesh;
  mesh.vertices.resize(6, 3);
  mesh.vertices << 0, 0, 1, 1, 0, 1, 0, 1, 1,  //
      1, 0, 1, 4, 0, 1, 1, 1, 1;
  mesh.elements.resize(2, 3);
  mesh.elements << 0, 1, 2, 3, 4, 5;
  return mesh;
}

TEST_CASE("surface samples lie on the triangles, spread by area, with unit normals",
          "[spatial][sampling]") {
  const Mesh mesh = TwoTriangles();
  const Index count = 40000;
  const SampledPoints sample = SampleSurface(mesh, count, 7);
  REQUIRE(sample.points.rows() == count);
  REQUIRE(sample.normals.rows() == count);
  Index in_second = 0;
  for (Index k = 0; k < count; ++k) {
    const double x = sample.points(k, 0), y = sample.points(k, 1);
    CHECK(sample.points(k, 2) == Approx(1.0));
    CHECK(sample.normals.row(k).isApprox(Eigen::RowVector3d(0, 0, 1)));
    if (x <= 1.0 && x + y <= 1.0 + 1e-12) continue;  // inside the first triangle
    // Inside the second: x in [1, 4], under its hypotenuse y = 1 - (x - 1) / 3.
    CHECK(x >= 1.0 - 1e-12);
    CHECK(y <= 1.0 - (x - 1.0) / 3.0 + 1e-12);
    CHECK(y >= -1e-12);
    ++in_second;
  }
  // Three quarters of the area: binomial standard deviation about 0.002 of the count.
  CHECK(static_cast<double>(in_second) / count == Approx(0.75).margin(0.01));
  // Uniform inside a triangle: the mean of the first triangle's points is its centroid.
  Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
  Index in_first = 0;
  for (Index k = 0; k < count; ++k) {
    if (sample.points(k, 0) < 1.0 && sample.points(k, 0) + sample.points(k, 1) <= 1.0) {
      mean += sample.points.row(k);
      ++in_first;
    }
  }
  mean /= static_cast<double>(in_first);
  CHECK(mean.isApprox(Eigen::RowVector3d(1.0 / 3.0, 1.0 / 3.0, 1.0), 0.02));
}

TEST_CASE("a seed reproduces the sample and its damage; another seed does not",
          "[spatial][sampling]") {
  const Mesh mesh = TwoTriangles();
  const SampledPoints a = SampleSurface(mesh, 500, 3), b = SampleSurface(mesh, 500, 3);
  const SampledPoints c = SampleSurface(mesh, 500, 4);
  CHECK(a.points == b.points);
  CHECK_FALSE(a.points == c.points);
  const SampledPoints da = DamagePoints(a, {}, 9), db = DamagePoints(a, {}, 9);
  CHECK(da.points == db.points);
  CHECK(da.normals == db.normals);
}

TEST_CASE("damage removes one patch of nearest points and adds outliers in the grown box",
          "[spatial][sampling]") {
  const SampledPoints sample = SampleSurface(TwoTriangles(), 1000, 5);
  PointDamage damage;
  damage.removed = 0.2;
  damage.outliers = 0.05;
  const SampledPoints damaged = DamagePoints(sample, damage, 11);
  const Index kept = 1000 - 200, outliers = 40;
  REQUIRE(damaged.points.rows() == kept + outliers);
  REQUIRE(damaged.normals.rows() == kept + outliers);
  // The kept points are the sample's, in order; the removed ones are a ball around one of
  // them: for some removed point, every removed point is at least as near to it as every kept.
  std::vector<bool> is_kept(1000, false);
  Index next = 0;
  for (Index k = 0; k < kept; ++k) {
    while (next < 1000 && !(sample.points.row(next) == damaged.points.row(k))) ++next;
    REQUIRE(next < 1000);
    is_kept[static_cast<size_t>(next)] = true;
    ++next;
  }
  bool some_center = false;
  for (Index c = 0; c < 1000 && !some_center; ++c) {
    if (is_kept[static_cast<size_t>(c)]) continue;
    double farthest_removed = 0.0, nearest_kept = 1e300;
    for (Index k = 0; k < 1000; ++k) {
      const double d = (sample.points.row(k) - sample.points.row(c)).squaredNorm();
      if (is_kept[static_cast<size_t>(k)]) {
        nearest_kept = std::min(nearest_kept, d);
      } else {
        farthest_removed = std::max(farthest_removed, d);
      }
    }
    some_center = farthest_removed <= nearest_kept;
  }
  CHECK(some_center);
  // The outliers lie in the kept points' box grown by 10% per side, with unit normals.
  const Eigen::RowVector3d low = damaged.points.topRows(kept).colwise().minCoeff();
  const Eigen::RowVector3d high = damaged.points.topRows(kept).colwise().maxCoeff();
  for (Index k = kept; k < kept + outliers; ++k) {
    for (int axis = 0; axis < 3; ++axis) {
      const double margin = 0.1 * (high[axis] - low[axis]);
      CHECK(damaged.points(k, axis) >= low[axis] - margin - 1e-12);
      CHECK(damaged.points(k, axis) <= high[axis] + margin + 1e-12);
    }
    CHECK(damaged.normals.row(k).norm() == Approx(1.0));
  }
}

TEST_CASE("sampling and damage refuse what they cannot do", "[spatial][sampling]") {
  Mesh flat = TwoTriangles();
  flat.vertices.col(1).setZero();  // every triangle degenerate
  CHECK_THROWS_WITH(SampleSurface(flat, 10, 1), Catch::Contains("positive area"));
  CHECK_THROWS_AS(SampleSurface(TwoTriangles(), -1, 1), InputError);
  CHECK_THROWS_WITH(DamagePoints(SampledPoints{}, {}, 1), Catch::Contains("empty"));
  PointDamage bad;
  bad.removed = 1.0;
  CHECK_THROWS_WITH(DamagePoints(SampleSurface(TwoTriangles(), 10, 1), bad, 1),
                    Catch::Contains("removed"));
}

}  // namespace
}  // namespace harap
