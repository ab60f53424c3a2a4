// SPDX-License-Identifier: MIT
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "framework/context.h"
#include "framework/types.h"

namespace harap {

/// Where the closest point of a registration target lies (docs/registration.md).
enum class ClosestFeature {
  kFace,      ///< inside a triangle (or a point of a point cloud)
  kEdge,      ///< on an interior edge
  kVertex,    ///< on a vertex that is not on the boundary
  kBoundary,  ///< on a boundary edge or a boundary vertex of the target mesh
};

/// The closest point of a target to one query point.
struct ClosestPoint {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  /// Unit normal of the target there (the triangle's for a mesh, the point's for a point cloud
  /// with normals), or zero where the target has none.
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double distance = 0.0;
  ClosestFeature feature = ClosestFeature::kFace;
  /// The target's triangle (mesh) or point (point cloud) the closest point belongs to.
  Index element = kNoVertex;
};

/// A registration target: a surface mesh or a point cloud that answers closest-point queries.
/// Built once, then const and thread-safe: queries run in parallel inside the context's arena.
/// Implementations use a spatial index from a library (spatial/ module); the registration
/// driver (solvers/optimizers/registration.h) only sees this interface.
class ClosestPointSearch {
 public:
  virtual ~ClosestPointSearch() = default;
  /// out[i] = the closest point of the target to points.row(i) (out is resized).
  virtual void FindClosest(const Positions& points, std::vector<ClosestPoint>& out,
                           const Context& context) const = 0;
  /// Whether ClosestPoint::normal is set.
  virtual bool has_normals() const = 0;
  /// Whether the target is a mesh (closest points on triangles, kBoundary possible) rather
  /// than a point cloud.
  virtual bool is_mesh() const = 0;
  virtual Index num_points() const = 0;  ///< target vertices or points
  /// The target's vertices or points (num_points() rows).
  virtual const Positions& points() const = 0;
  /// Unit normals of points() (a mesh's: area-weighted vertex normals), or none (0 rows).
  virtual const Positions& point_normals() const = 0;

 protected:
  ClosestPointSearch() = default;
};

/// Makes a search over a set of points without normals (a registration looks up the source's
/// vertices nearest to the target's points with it).
using PointSearchFactory = std::function<std::unique_ptr<ClosestPointSearch>(const Positions&)>;

}  // namespace harap
