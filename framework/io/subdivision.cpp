// SPDX-License-Identifier: MIT
#include "framework/io/subdivision.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

#include <cmath>
#include <limits>
#include <vector>

#include "framework/error.h"
#include "framework/io/openmesh_log.h"

namespace harap {

namespace {

// Double-precision points: OpenMesh's default traits store float positions.
struct DoubleTraits : public OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
using LoopMesh = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;

}  // namespace

// steps == 0 returns the mesh unchanged (unreferenced vertices included): only an actual
// subdivision goes through OpenMesh's halfedge structure, which cannot hold isolated vertices.
Mesh LoopSubdivide(const Mesh& mesh, int steps) {
  HARAP_CHECK(steps >= 0, "LoopSubdivide: steps must be >= 0, got {}", steps);
  if (steps == 0) return mesh;
  if (mesh.kind() != ElementKind::kTriangle || mesh.num_elements() == 0) {
    throw InputError("Loop subdivision needs a triangle mesh");
  }
  // Each round multiplies the counts by about 4 (vertices: V + E ~ 4V).
  const double growth = std::pow(4.0, steps);
  if (static_cast<double>(mesh.num_elements()) * growth >
      static_cast<double>(std::numeric_limits<Index>::max())) {
    throw InputError(fmt::format("Loop subdivision: {} rounds of a mesh with {} triangles would "
                                 "exceed {} triangles",
                                 steps, mesh.num_elements(), std::numeric_limits<Index>::max()));
  }

  io_internal::OpenMeshLogCapture capture;  // add_face reports refusals on omerr
  LoopMesh halfedge_mesh;
  const std::vector<bool> referenced = ReferencedVertices(mesh);
  std::vector<LoopMesh::VertexHandle> handle(mesh.num_vertices());
  halfedge_mesh.reserve(mesh.num_vertices(), 3 * mesh.num_elements() / 2, mesh.num_elements());
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (!referenced[v]) continue;
    handle[v] = halfedge_mesh.add_vertex(
        LoopMesh::Point(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2)));
  }
  Index refused = 0;
  Index first_refused = -1;
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    const auto face = halfedge_mesh.add_face(handle[mesh.elements(f, 0)],
                                             handle[mesh.elements(f, 1)],
                                             handle[mesh.elements(f, 2)]);
    if (!face.is_valid()) {
      if (refused == 0) first_refused = f;
      ++refused;
    }
  }
  if (refused > 0) {
    const std::string reason = capture.Errors();
    throw InputError(fmt::format(
        "Loop subdivision needs a manifold, consistently oriented triangle mesh, but this mesh is "
        "not manifold: OpenMesh refused {} of its {} triangles (first: triangle {} with vertices "
        "{} {} {}{})",
        refused, mesh.num_elements(), first_refused, mesh.elements(first_refused, 0),
        mesh.elements(first_refused, 1), mesh.elements(first_refused, 2),
        reason.empty() ? "" : fmt::format("; OpenMesh: {}", reason)));
  }

  OpenMesh::Subdivider::Uniform::LoopT<LoopMesh, double> loop;
  loop.attach(halfedge_mesh);
  const bool ok = loop(static_cast<size_t>(steps));
  loop.detach();
  if (!ok) {
    const std::string reason = capture.Errors();
    throw InputError(fmt::format("OpenMesh's Loop subdivision failed{}",
                                 reason.empty() ? "" : fmt::format(": {}", reason)));
  }

  // LoopT appends new vertices after the old ones and creates no holes in the index range (it
  // deletes nothing), so handles map to consecutive indices.
  Mesh result;
  result.vertices.resize(static_cast<Index>(halfedge_mesh.n_vertices()), 3);
  for (const auto vertex : halfedge_mesh.vertices()) {
    const auto& point = halfedge_mesh.point(vertex);
    result.vertices.row(vertex.idx()) << point[0], point[1], point[2];
  }
  result.elements.resize(static_cast<Index>(halfedge_mesh.n_faces()), 3);
  for (const auto face : halfedge_mesh.faces()) {
    int corner = 0;
    for (const auto vertex : halfedge_mesh.fv_range(face)) {
      HARAP_CHECK(corner < 3, "Loop subdivision produced a non-triangle face {}", face.idx());
      result.elements(face.idx(), corner++) = vertex.idx();
    }
  }
  return result;
}

}  // namespace harap
