// SPDX-License-Identifier: MIT
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "framework/closest_points.h"
#include "framework/mesh.h"

namespace harap {

/// Closest points on a registration target (docs/registration.md says why these libraries). A
/// point cloud: the nearest point, from a k-d tree (nanoflann). A mesh: the exact closest point
/// on its triangles (a tetrahedral mesh: pass its boundary triangles), from a bounding-box tree
/// (CGAL's AABB tree), with the feature it lies on (face, edge, vertex, boundary). Built once;
/// queries are const, thread-safe and run in parallel.
class TargetSearch final : public ClosestPointSearch {
 public:
  /// Throws InputError for a mesh that is not made of triangles, has no non-degenerate
  /// triangle or has non-finite coordinates (naming the vertex).
  static std::unique_ptr<TargetSearch> FromMesh(const Mesh& mesh);
  /// `normals`: none (0 rows) or one per point (normalized here; a zero normal stays zero).
  /// Throws InputError for no points, non-finite values (naming the point) or a normal count
  /// that differs from the point count.
  static std::unique_ptr<TargetSearch> FromPoints(Positions points, Positions normals);
  ~TargetSearch() override;

  /// Throws InputError naming the first query point that is not finite.
  void FindClosest(const Positions& points, std::vector<ClosestPoint>& out,
                   const Context& context) const override;
  bool has_normals() const override { return normals_.rows() > 0; }
  bool is_mesh() const override { return triangles_.rows() > 0; }
  Index num_points() const override { return static_cast<Index>(points_.rows()); }
  const Positions& points() const override { return points_; }
  const Positions& point_normals() const override { return normals_; }

 private:
  TargetSearch();
  void BuildTriangleData();
  void BuildTriangleTree();
  ClosestPoint ClosestOnMesh(const Eigen::Vector3d& query) const;
  ClosestPoint ClosestInCloud(const Eigen::Vector3d& query) const;
  ClosestPoint ClosestPointOfTriangle(const Eigen::Vector3d& query, Index triangle) const;

  struct Tree;                          // the k-d tree (nanoflann stays out of this header)
  Positions points_;                    // target vertices or points
  Positions normals_;                   // point normals, or none
  Elements triangles_;                  // #T×3, non-degenerate ones only; empty for a point cloud
  std::vector<Index> triangle_source_;  // triangles_ row → the mesh's element
  Positions triangle_normals_;
  std::vector<std::array<bool, 3>> boundary_edge_;  // edge k: corner k → corner k+1
  std::vector<char> boundary_vertex_;
  std::unique_ptr<Tree> tree_;
};

}  // namespace harap
