// SPDX-License-Identifier: MIT
// TargetSearch (spatial/target_search.h): closest points on meshes and point clouds, checked
// against brute force over every triangle or point.
#include "spatial/target_search.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "framework/error.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

// The closest point of triangle abc to p by minimizing over a fine barycentric grid and then
// over the three edges exactly: an independent, slow reference.
Eigen::Vector3d ReferenceClosestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                           const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  // Inside: the projection onto the plane, if its barycentric coordinates are all >= 0.
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const Eigen::Vector3d q = p - n * (n.dot(p - a) / n.squaredNorm());
  const double area = n.norm();
  const double wa = (b - q).cross(c - q).dot(n) / (area * area);
  const double wb = (c - q).cross(a - q).dot(n) / (area * area);
  const double wc = 1.0 - wa - wb;
  if (wa >= 0.0 && wb >= 0.0 && wc >= 0.0) return q;
  // Otherwise on an edge: the closest of the three clamped edge projections.
  Eigen::Vector3d best = a;
  for (const auto& [s, t] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
    const double u = std::clamp((p - s).dot(t - s) / (t - s).squaredNorm(), 0.0, 1.0);
    const Eigen::Vector3d e = s + u * (t - s);
    if ((p - e).norm() < (p - best).norm()) best = e;
  }
  return best;
}

double BruteForceDistance(const Mesh& mesh, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    const Eigen::Vector3d q = ReferenceClosestOnTriangle(p, mesh.vertices.row(mesh.elements(f, 0)),
                                                         mesh.vertices.row(mesh.elements(f, 1)),
                                                         mesh.vertices.row(mesh.elements(f, 2)));
    best = std::min(best, (p - q).norm());
  }
  return best;
}

Positions RandomPoints(int count, double spread, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> uniform(-spread, spread);
  Positions points(count, 3);
  for (Index i = 0; i < count; ++i) {
    for (int d = 0; d < 3; ++d) points(i, d) = uniform(random);
  }
  return points;
}

}  // namespace

TEST_CASE("closest points on a mesh are exact", "[spatial]") {
  const Mesh sphere = Jittered(Icosphere(2), 1000, 0.05, 7);
  const std::unique_ptr<TargetSearch> search = TargetSearch::FromMesh(sphere);
  CHECK(search->is_mesh());
  CHECK(search->has_normals());
  CHECK(search->num_points() == sphere.num_vertices());
  // Near the surface, far from it and inside.
  const Positions queries = RandomPoints(300, 1.6, 3);
  std::vector<ClosestPoint> found;
  search->FindClosest(queries, found, Context::WithThreads(2));
  REQUIRE(found.size() == 300u);
  for (Index q = 0; q < queries.rows(); ++q) {
    const Eigen::Vector3d p = queries.row(q).transpose();
    INFO("query " << q);
    CHECK(found[q].distance == Approx(BruteForceDistance(sphere, p)).margin(1e-12));
    CHECK((found[q].point - p).norm() == Approx(found[q].distance).margin(1e-12));
    CHECK(found[q].feature != ClosestFeature::kBoundary);  // a closed surface
    CHECK(found[q].normal.norm() == Approx(1.0));
    // The point lies on the triangle it names.
    const Eigen::Vector3d a = sphere.vertices.row(sphere.elements(found[q].element, 0));
    CHECK(std::abs((found[q].point - a).dot(found[q].normal)) < 1e-12);
  }
}

TEST_CASE("closest points name the feature they lie on", "[spatial]") {
  const Mesh grid = Grid(3, 3);  // the unit square in z = 0, open; (0.5, 0.5) is a vertex
  const std::unique_ptr<TargetSearch> search = TargetSearch::FromMesh(grid);
  Positions queries(4, 3);
  queries << 0.37, 0.41, 0.5,  // above the interior
      1.5, 0.43, 0.0,          // beyond the edge x = 1
      -0.5, -0.5, 0.2,         // beyond a corner
      0.5, 0.5, -0.1;          // below the interior, at a grid vertex
  std::vector<ClosestPoint> found;
  search->FindClosest(queries, found, Context());
  CHECK(found[0].feature != ClosestFeature::kBoundary);
  CHECK(found[0].distance == Approx(0.5));
  CHECK(std::abs(found[0].normal.z()) == Approx(1.0));
  CHECK(found[1].feature == ClosestFeature::kBoundary);
  CHECK(found[1].point.isApprox(Eigen::Vector3d(1.0, 0.43, 0.0)));
  CHECK(found[2].feature == ClosestFeature::kBoundary);
  CHECK(found[2].point.isApprox(Eigen::Vector3d(0.0, 0.0, 0.0)));
  CHECK(found[3].feature == ClosestFeature::kVertex);
  CHECK(found[3].distance == Approx(0.1));
}

TEST_CASE("closest points in a point cloud, with and without normals", "[spatial]") {
  const Positions points = RandomPoints(500, 1.0, 11);
  const Positions queries = RandomPoints(200, 1.5, 12);
  Positions normals = RandomPoints(500, 1.0, 13);
  const std::unique_ptr<TargetSearch> plain = TargetSearch::FromPoints(points, Positions(0, 3));
  const std::unique_ptr<TargetSearch> with_normals = TargetSearch::FromPoints(points, normals);
  CHECK_FALSE(plain->is_mesh());
  CHECK_FALSE(plain->has_normals());
  CHECK(with_normals->has_normals());
  std::vector<ClosestPoint> found, found_with_normals;
  plain->FindClosest(queries, found, Context::WithThreads(2));
  with_normals->FindClosest(queries, found_with_normals, Context());
  for (Index q = 0; q < queries.rows(); ++q) {
    Index nearest = 0;
    const double distance =
        std::sqrt((points.rowwise() - queries.row(q)).rowwise().squaredNorm().minCoeff(&nearest));
    CHECK(found[q].element == nearest);
    CHECK(found[q].distance == Approx(distance).margin(1e-15));
    CHECK(found[q].normal.isZero());
    CHECK(found_with_normals[q].normal.isApprox(normals.row(nearest).normalized().transpose()));
  }
}

TEST_CASE("bad targets are refused naming the problem", "[spatial]") {
  SECTION("no points") {
    CHECK_THROWS_WITH(TargetSearch::FromPoints(Positions(0, 3), Positions(0, 3)),
                      Catch::Contains("no points"));
  }
  SECTION("a NaN point") {
    Positions points = RandomPoints(10, 1.0, 1);
    points(4, 1) = std::nan("");
    CHECK_THROWS_WITH(TargetSearch::FromPoints(points, Positions(0, 3)),
                      Catch::Contains("point 4 is not finite"));
  }
  SECTION("normals for other points") {
    CHECK_THROWS_WITH(TargetSearch::FromPoints(RandomPoints(10, 1.0, 1), RandomPoints(9, 1.0, 2)),
                      Catch::Contains("10 points but 9 normals"));
  }
  SECTION("a mesh without area") {
    Mesh flat = Grid(2, 2);
    flat.vertices.col(1).setZero();
    flat.vertices.col(2).setZero();
    CHECK_THROWS_WITH(TargetSearch::FromMesh(flat), Catch::Contains("non-zero area"));
  }
  SECTION("tetrahedra") {
    CHECK_THROWS_WITH(TargetSearch::FromMesh(TetBox(1, 1, 1)),
                      Catch::Contains("boundary triangles"));
  }
  SECTION("a query at NaN") {
    Positions queries = RandomPoints(5, 1.0, 3);
    queries(2, 2) = std::nan("");
    std::vector<ClosestPoint> found;
    CHECK_THROWS_WITH(TargetSearch::FromMesh(Grid(2, 2))->FindClosest(queries, found, Context()),
                      Catch::Contains("query point 2 is not finite"));
  }
  SECTION("an infinite vertex") {
    Mesh grid = Grid(2, 2);
    grid.vertices(3, 0) = std::numeric_limits<double>::infinity();
    CHECK_THROWS_WITH(TargetSearch::FromMesh(grid), Catch::Contains("vertex 3 is not finite"));
  }
}
