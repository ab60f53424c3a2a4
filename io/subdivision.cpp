// SPDX-License-Identifier: MIT
#include "io/subdivision.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <tuple>
#include <utility>
#include <vector>

#include "framework/disjoint_sets.h"
#include "framework/error.h"
#include "io/openmesh_log.h"

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
Mesh LoopSubdivide(const Mesh& mesh, int steps, std::string* note) {
  HARAP_CHECK(steps >= 0, "LoopSubdivide: steps must be >= 0, got {}", steps);
  if (steps == 0) return mesh;
  if (mesh.kind() != ElementKind::kTriangle || mesh.num_elements() == 0) {
    throw InputError("Loop subdivision needs a triangle mesh");
  }
  // Each round multiplies the counts by about 4 (vertices: V + E ~ 4V).
  const double growth = std::pow(4.0, steps);
  if (static_cast<double>(mesh.num_elements()) * growth >
      static_cast<double>(std::numeric_limits<Index>::max())) {
    throw InputError(
        fmt::format("Loop subdivision: {} rounds of a mesh with {} triangles would "
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
    const auto face = halfedge_mesh.add_face(
        handle[mesh.elements(f, 0)], handle[mesh.elements(f, 1)], handle[mesh.elements(f, 2)]);
    if (!face.is_valid()) {
      if (refused == 0) first_refused = f;
      ++refused;
    }
  }
  if (refused > 0) {
    // Not a halfedge mesh: the crease variant refines it on the indexed triangles instead.
    const std::string reason = capture.Errors();
    Index edges = 0, vertices = 0;
    Mesh result = LoopSubdivideCreased(mesh, steps, &edges, &vertices);
    if (note) {
      *note = fmt::format(
          "refine: the mesh is not a manifold, consistently oriented surface (OpenMesh refused {} "
          "of its {} triangles, first: triangle {} with vertices {} {} {}{}), so it was refined "
          "with harap's Loop variant that keeps {} non-manifold edge{} (3 or more triangles) and "
          "the boundary as creases and {} {} where separate fans meet in place "
          "(docs/input.md)",
          refused, mesh.num_elements(), first_refused, mesh.elements(first_refused, 0),
          mesh.elements(first_refused, 1), mesh.elements(first_refused, 2),
          reason.empty() ? "" : fmt::format("; OpenMesh: {}", reason), edges, edges == 1 ? "" : "s",
          vertices, vertices == 1 ? "vertex" : "vertices");
    }
    return result;
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

namespace {

// The undirected edges of a triangle mesh: each edge's vertices and the range of its triangle
// sides in `sides` (sorted by (min, max, face), so each edge's faces are consecutive).
struct EdgeTable {
  struct Side {
    Index a, b, face, opposite;
  };
  std::vector<Side> sides;
  std::vector<std::pair<Index, Index>> edges;
  std::vector<std::pair<size_t, size_t>> ranges;

  explicit EdgeTable(const Mesh& mesh) {
    const Index f_count = mesh.num_elements();
    sides.reserve(3 * static_cast<size_t>(f_count));
    for (Index f = 0; f < f_count; ++f) {
      for (int k = 0; k < 3; ++k) {
        const Index u = mesh.elements(f, k), v = mesh.elements(f, (k + 1) % 3);
        sides.push_back({std::min(u, v), std::max(u, v), f, mesh.elements(f, (k + 2) % 3)});
      }
    }
    std::sort(sides.begin(), sides.end(), [](const Side& x, const Side& y) {
      return std::tie(x.a, x.b, x.face) < std::tie(y.a, y.b, y.face);
    });
    for (size_t i = 0; i < sides.size();) {
      size_t j = i;
      while (j < sides.size() && sides[j].a == sides[i].a && sides[j].b == sides[i].b) ++j;
      edges.emplace_back(sides[i].a, sides[i].b);
      ranges.emplace_back(i, j);
      i = j;
    }
  }
  Index size() const { return static_cast<Index>(edges.size()); }
  Index Find(Index u, Index v) const {
    const std::pair<Index, Index> key(std::min(u, v), std::max(u, v));
    return static_cast<Index>(std::lower_bound(edges.begin(), edges.end(), key) - edges.begin());
  }
};

// Per vertex, how many fans its faces form (connected through the two-triangle edges at the
// vertex): 1 on a manifold vertex.
std::vector<Index> FanCounts(const Mesh& mesh, const EdgeTable& table) {
  const Index n = mesh.num_vertices();
  const Index f_count = mesh.num_elements();
  // Union the faces at a vertex across its two-triangle edges; count components per vertex.
  DisjointSets<size_t> fans(3 * static_cast<size_t>(f_count));  // corners (f, k) = 3f + k
  auto corner_of = [&](Index f, Index v) {
    for (int k = 0; k < 3; ++k) {
      if (mesh.elements(f, k) == v) return static_cast<size_t>(3 * f + k);
    }
    return static_cast<size_t>(3 * f);
  };
  for (Index e = 0; e < table.size(); ++e) {
    const auto [first, last] = table.ranges[e];
    if (last - first != 2) continue;
    for (const Index v : {table.edges[e].first, table.edges[e].second}) {
      fans.Unite(corner_of(table.sides[first].face, v), corner_of(table.sides[first + 1].face, v));
    }
  }
  std::vector<Index> fan_count(n, 0);
  std::vector<std::vector<size_t>> roots(n);
  for (Index f = 0; f < f_count; ++f) {
    for (int k = 0; k < 3; ++k)
      roots[mesh.elements(f, k)].push_back(fans.Find(static_cast<size_t>(3 * f + k)));
  }
  for (Index v = 0; v < n; ++v) {
    std::sort(roots[v].begin(), roots[v].end());
    fan_count[v] =
        static_cast<Index>(std::unique(roots[v].begin(), roots[v].end()) - roots[v].begin());
  }
  return fan_count;
}

// One round of the crease variant on a mesh whose vertices are all referenced.
Mesh CreasedRound(const Mesh& mesh, Index* non_manifold_edges, Index* non_manifold_vertices) {
  const Index n = mesh.num_vertices();
  const Index f_count = mesh.num_elements();
  const EdgeTable table(mesh);
  const auto& sides = table.sides;
  const auto& edges = table.edges;
  const auto& ranges = table.ranges;
  const Index e_count = table.size();

  // Per vertex: neighbours (through edges), crease edges, and whether its faces form one fan.
  std::vector<std::vector<Index>> neighbours(n), crease_neighbours(n);
  Index counted_edges = 0;
  for (Index e = 0; e < e_count; ++e) {
    const auto [u, v] = edges[e];
    if (u == v) continue;  // a degenerate triangle's repeated corner
    neighbours[u].push_back(v);
    neighbours[v].push_back(u);
    const size_t faces = ranges[e].second - ranges[e].first;
    if (faces != 2) {
      crease_neighbours[u].push_back(v);
      crease_neighbours[v].push_back(u);
    }
    counted_edges += faces > 2;
  }
  const std::vector<Index> fan_count = FanCounts(mesh, table);

  Mesh result;
  result.vertices.resize(n + e_count, 3);
  Index counted_vertices = 0;
  for (Index v = 0; v < n; ++v) {
    const Eigen::RowVector3d p = mesh.vertices.row(v);
    const auto& ring = neighbours[v];
    const auto& creases = crease_neighbours[v];
    counted_vertices += creases.empty() && fan_count[v] > 1;
    if (creases.empty() && fan_count[v] == 1 && !ring.empty()) {
      // Loop's weights (Loop 1987), as OpenMesh's LoopT.
      const double valence = static_cast<double>(ring.size());
      const double c = 3.0 / 8.0 + 0.25 * std::cos(2.0 * std::numbers::pi / valence);
      const double beta = (5.0 / 8.0 - c * c) / valence;
      Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
      for (const Index u : ring) sum += mesh.vertices.row(u);
      result.vertices.row(v) = (1.0 - valence * beta) * p + beta * sum;
    } else if (creases.size() == 2) {
      result.vertices.row(v) =
          0.75 * p + 0.125 * (mesh.vertices.row(creases[0]) + mesh.vertices.row(creases[1]));
    } else {
      result.vertices.row(v) = p;  // corner, crossing creases, several fans
    }
  }
  for (Index e = 0; e < e_count; ++e) {
    const auto [u, v] = edges[e];
    const auto [first, last] = ranges[e];
    Eigen::RowVector3d point = 0.5 * (mesh.vertices.row(u) + mesh.vertices.row(v));
    if (last - first == 2 && u != v) {
      point = 0.375 * (mesh.vertices.row(u) + mesh.vertices.row(v)) +
              0.125 * (mesh.vertices.row(sides[first].opposite) +
                       mesh.vertices.row(sides[first + 1].opposite));
    }
    result.vertices.row(n + e) = point;
  }
  // Each triangle (a, b, c) becomes four with the same orientation.
  result.elements.resize(4 * f_count, 3);
  for (Index f = 0; f < f_count; ++f) {
    const Index a = mesh.elements(f, 0), b = mesh.elements(f, 1), c = mesh.elements(f, 2);
    const Index ab = n + table.Find(a, b), bc = n + table.Find(b, c), ca = n + table.Find(c, a);
    result.elements.row(4 * f) << a, ab, ca;
    result.elements.row(4 * f + 1) << ab, b, bc;
    result.elements.row(4 * f + 2) << ca, bc, c;
    result.elements.row(4 * f + 3) << ab, bc, ca;
  }
  if (non_manifold_edges) *non_manifold_edges = counted_edges;
  if (non_manifold_vertices) *non_manifold_vertices = counted_vertices;
  return result;
}

}  // namespace

Mesh LoopSubdivideCreased(const Mesh& mesh, int steps, Index* non_manifold_edges,
                          Index* non_manifold_vertices) {
  HARAP_CHECK(steps >= 0, "LoopSubdivideCreased: steps must be >= 0, got {}", steps);
  if (non_manifold_edges) *non_manifold_edges = 0;
  if (non_manifold_vertices) *non_manifold_vertices = 0;
  if (steps == 0) return mesh;
  if (mesh.kind() != ElementKind::kTriangle || mesh.num_elements() == 0) {
    throw InputError("Loop subdivision needs a triangle mesh");
  }
  // Drop unreferenced vertices (as the OpenMesh path does), keeping the order of the others.
  const std::vector<bool> referenced = ReferencedVertices(mesh);
  std::vector<Index> renumber(mesh.num_vertices(), -1);
  Mesh current;
  Index kept = 0;
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (referenced[v]) renumber[v] = kept++;
  }
  current.vertices.resize(kept, 3);
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (referenced[v]) current.vertices.row(renumber[v]) = mesh.vertices.row(v);
  }
  current.elements.resize(mesh.num_elements(), 3);
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    for (int k = 0; k < 3; ++k) current.elements(f, k) = renumber[mesh.elements(f, k)];
  }
  for (int step = 0; step < steps; ++step) {
    current = step == 0 ? CreasedRound(current, non_manifold_edges, non_manifold_vertices)
                        : CreasedRound(current, nullptr, nullptr);
  }
  return current;
}

}  // namespace harap
