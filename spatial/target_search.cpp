// SPDX-License-Identifier: MIT
#include "spatial/target_search.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <nanoflann.hpp>
#include <utility>

#include "framework/error.h"
#include "framework/vertex_normals.h"

namespace harap {

namespace {

// nanoflann's view of the rows of a #N×3 matrix.
struct RowsAdaptor {
  const Positions* rows = nullptr;
  size_t kdtree_get_point_count() const { return static_cast<size_t>(rows->rows()); }
  double kdtree_get_pt(size_t index, size_t dimension) const {
    return (*rows)(static_cast<Index>(index), static_cast<Index>(dimension));
  }
  template <class Box>
  bool kdtree_get_bbox(Box& /*box*/) const {
    return false;  // let nanoflann compute it
  }
};

using KdTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, RowsAdaptor>,
                                        RowsAdaptor, 3, uint32_t>;

void CheckFinite(const Positions& rows, const char* what) {
  for (Index i = 0; i < rows.rows(); ++i) {
    if (!rows.row(i).allFinite()) {
      throw InputError(fmt::format("registration target: {} {} is not finite ({}, {}, {})", what, i,
                                   rows(i, 0), rows(i, 1), rows(i, 2)));
    }
  }
}

// Triangles in CGAL's AABB tree: double coordinates, no exact predicates (distances only).
using Kernel = CGAL::Simple_cartesian<double>;
using CgalTriangles = std::vector<Kernel::Triangle_3>;
using TrianglePrimitive = CGAL::AABB_triangle_primitive<Kernel, CgalTriangles::const_iterator>;
using TriangleTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, TrianglePrimitive>>;

Kernel::Point_3 ToPoint(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace

// A point cloud's k-d tree (nanoflann), or a mesh's bounding-box tree of triangles (CGAL).
struct TargetSearch::Tree {
  RowsAdaptor adaptor;
  std::unique_ptr<KdTree> points;
  CgalTriangles triangles;
  std::unique_ptr<TriangleTree> mesh;
};

TargetSearch::TargetSearch() = default;
TargetSearch::~TargetSearch() = default;

std::unique_ptr<TargetSearch> TargetSearch::FromPoints(Positions points, Positions normals) {
  if (points.rows() == 0) throw InputError("registration target: the point cloud has no points");
  CheckFinite(points, "point");
  if (normals.rows() > 0) {
    if (normals.rows() != points.rows()) {
      throw InputError(fmt::format("registration target: {} points but {} normals", points.rows(),
                                   normals.rows()));
    }
    CheckFinite(normals, "normal of point");
    for (Index i = 0; i < normals.rows(); ++i) {
      const double norm = normals.row(i).norm();
      if (norm > 0.0) normals.row(i) /= norm;
    }
  }
  std::unique_ptr<TargetSearch> search(new TargetSearch());
  search->points_ = std::move(points);
  search->normals_ = std::move(normals);
  search->tree_ = std::make_unique<Tree>();
  search->tree_->adaptor.rows = &search->points_;
  search->tree_->points = std::make_unique<KdTree>(3, search->tree_->adaptor);
  return search;
}

std::unique_ptr<TargetSearch> TargetSearch::FromMesh(const Mesh& mesh) {
  if (mesh.kind() != ElementKind::kTriangle) {
    throw InputError(
        "registration target: closest points are searched on triangles; give a tetrahedral "
        "mesh's boundary triangles");
  }
  CheckFinite(mesh.vertices, "vertex");
  std::unique_ptr<TargetSearch> search(new TargetSearch());
  search->points_ = mesh.vertices;
  std::vector<Index> kept;
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.elements(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.elements(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.elements(f, 2));
    // A triangle without area is covered by its neighbours' edges; its normal is undefined.
    if ((b - a).cross(c - a).squaredNorm() > 0.0) kept.push_back(f);
  }
  if (kept.empty()) {
    throw InputError(fmt::format(
        "registration target: the mesh has no triangle with a non-zero area (of {} triangles)",
        mesh.num_elements()));
  }
  search->triangles_.resize(static_cast<Index>(kept.size()), 3);
  for (size_t t = 0; t < kept.size(); ++t) {
    search->triangles_.row(static_cast<Index>(t)) = mesh.elements.row(kept[t]);
  }
  search->triangle_source_ = std::move(kept);
  search->BuildTriangleData();
  search->BuildTriangleTree();
  return search;
}

void TargetSearch::BuildTriangleData() {
  const Index count = triangles_.rows();
  triangle_normals_.resize(count, 3);
  normals_ = VertexNormals(points_, triangles_);
  // Edges as (smaller, larger) vertex pairs, to count how many triangles use each.
  std::vector<std::pair<Index, Index>> edges;
  edges.reserve(static_cast<size_t>(count) * 3);
  for (Index t = 0; t < count; ++t) {
    const Eigen::Vector3d a = points_.row(triangles_(t, 0)), b = points_.row(triangles_(t, 1)),
                          c = points_.row(triangles_(t, 2));
    triangle_normals_.row(t) = (b - a).cross(c - a).normalized().transpose();
    for (int k = 0; k < 3; ++k) {
      const Index i = triangles_(t, k), j = triangles_(t, (k + 1) % 3);
      edges.emplace_back(std::min(i, j), std::max(i, j));
    }
  }
  // An edge used by one triangle is on the boundary.
  std::sort(edges.begin(), edges.end());
  const auto uses = [&](Index i, Index j) {
    const std::pair<Index, Index> key(std::min(i, j), std::max(i, j));
    const auto range = std::equal_range(edges.begin(), edges.end(), key);
    return range.second - range.first;
  };
  boundary_edge_.assign(count, {false, false, false});
  boundary_vertex_.assign(points_.rows(), 0);
  for (Index t = 0; t < count; ++t) {
    for (int k = 0; k < 3; ++k) {
      const Index i = triangles_(t, k), j = triangles_(t, (k + 1) % 3);
      if (uses(i, j) == 1) {
        boundary_edge_[t][k] = true;
        boundary_vertex_[i] = boundary_vertex_[j] = 1;
      }
    }
  }
}

void TargetSearch::BuildTriangleTree() {
  tree_ = std::make_unique<Tree>();
  tree_->triangles.reserve(triangles_.rows());
  for (Index t = 0; t < triangles_.rows(); ++t) {
    tree_->triangles.emplace_back(ToPoint(points_.row(triangles_(t, 0)).transpose()),
                                  ToPoint(points_.row(triangles_(t, 1)).transpose()),
                                  ToPoint(points_.row(triangles_(t, 2)).transpose()));
  }
  tree_->mesh = std::make_unique<TriangleTree>(tree_->triangles.begin(), tree_->triangles.end());
  tree_->mesh->build();
  // Built now, not lazily by the first query, so that queries may run on several threads.
  tree_->mesh->accelerate_distance_queries();
}

ClosestPoint TargetSearch::ClosestPointOfTriangle(const Eigen::Vector3d& p, Index t) const {
  // The Voronoi regions of the triangle's corners, edges and face, tested with dot products of
  // the edges and the query's offsets from the corners (barycentric coordinates unnormalized).
  const Eigen::Vector3d a = points_.row(triangles_(t, 0));
  const Eigen::Vector3d b = points_.row(triangles_(t, 1));
  const Eigen::Vector3d c = points_.row(triangles_(t, 2));
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  ClosestPoint result;
  result.element = triangle_source_[t];
  result.normal = triangle_normals_.row(t).transpose();
  const auto at_corner = [&](int k, const Eigen::Vector3d& corner) {
    result.point = corner;
    result.feature =
        boundary_vertex_[triangles_(t, k)] ? ClosestFeature::kBoundary : ClosestFeature::kVertex;
  };
  const auto on_edge = [&](int k, const Eigen::Vector3d& point) {
    result.point = point;
    result.feature = boundary_edge_[t][k] ? ClosestFeature::kBoundary : ClosestFeature::kEdge;
  };
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  const double vc = d1 * d4 - d3 * d2;  // ∝ the barycentric coordinate of c
  const double vb = d5 * d2 - d1 * d6;  // of b
  const double va = d3 * d6 - d5 * d4;  // of a
  if (d1 <= 0.0 && d2 <= 0.0) {
    at_corner(0, a);
  } else if (d3 >= 0.0 && d4 <= d3) {
    at_corner(1, b);
  } else if (d6 >= 0.0 && d5 <= d6) {
    at_corner(2, c);
  } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    on_edge(0, a + (d1 / (d1 - d3)) * ab);
  } else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    on_edge(1, b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b));
  } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    on_edge(2, a + (d2 / (d2 - d6)) * ac);
  } else {
    const double scale = 1.0 / (va + vb + vc);
    result.point = a + ab * (vb * scale) + ac * (vc * scale);
    result.feature = ClosestFeature::kFace;
  }
  result.distance = (p - result.point).norm();
  return result;
}

ClosestPoint TargetSearch::ClosestOnMesh(const Eigen::Vector3d& query) const {
  // The tree finds the closest triangle; the point and its feature are computed here again, so
  // that they are exactly those of ClosestPointOfTriangle.
  const auto hit = tree_->mesh->closest_point_and_primitive(ToPoint(query));
  return ClosestPointOfTriangle(query, static_cast<Index>(hit.second - tree_->triangles.cbegin()));
}

ClosestPoint TargetSearch::ClosestInCloud(const Eigen::Vector3d& query) const {
  uint32_t nearest = 0;
  double squared = 0.0;
  tree_->points->knnSearch(query.data(), 1, &nearest, &squared);
  ClosestPoint result;
  result.element = static_cast<Index>(nearest);
  result.point = points_.row(result.element).transpose();
  result.distance = (query - result.point).norm();
  if (normals_.rows() > 0) result.normal = normals_.row(result.element).transpose();
  return result;
}

void TargetSearch::FindClosest(const Positions& points, std::vector<ClosestPoint>& out,
                               const Context& context) const {
  // The trees' traversals assume finite coordinates.
  if (!points.allFinite()) {
    Index bad = 0;
    while (points.row(bad).allFinite()) ++bad;
    throw InputError(fmt::format("closest points: query point {} is not finite ({}, {}, {})", bad,
                                 points(bad, 0), points(bad, 1), points(bad, 2)));
  }
  out.resize(points.rows());
  context.Run([&] {
    tbb::parallel_for(tbb::blocked_range<Index>(0, points.rows(), 256),
                      [&](const tbb::blocked_range<Index>& range) {
                        for (Index i = range.begin(); i != range.end(); ++i) {
                          const Eigen::Vector3d query = points.row(i).transpose();
                          out[i] = is_mesh() ? ClosestOnMesh(query) : ClosestInCloud(query);
                        }
                      });
  });
}

}  // namespace harap
