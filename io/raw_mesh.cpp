// SPDX-License-Identifier: MIT
#include "io/raw_mesh.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "io/tetrahedra.h"
#include "io/text_scanning.h"

namespace harap::io_internal {

std::string RawMesh::Origin(size_t triangle) const {
  if (location.size() <= triangle) return fmt::format("{} {}", origin_kind, origin[triangle]);
  return fmt::format("{} {}: {} {}", location_kind, location[triangle], origin_kind,
                     origin[triangle]);
}

void RawMesh::AddPolygon(const std::vector<int64_t>& polygon, int64_t where) {
  // Fan triangulation (v0, vi, vi+1): exact for the triangles and convex polygons real files
  // contain; the format gives no geometry to do better with.
  for (size_t i = 1; i + 1 < polygon.size(); ++i) {
    corners.push_back(polygon[0]);
    corners.push_back(polygon[i]);
    corners.push_back(polygon[i + 1]);
    origin.push_back(where);
  }
}

Mesh BuildMesh(const RawMesh& raw, const std::string& what) {
  const int64_t num_vertices = static_cast<int64_t>(raw.xyz.size() / 3);
  const int64_t num_triangles = static_cast<int64_t>(raw.corners.size() / 3);
  if (num_vertices > std::numeric_limits<Index>::max() ||
      num_triangles > std::numeric_limits<Index>::max()) {
    Fail(what, fmt::format("too large: {} vertices and {} triangles (at most {} each)",
                           num_vertices, num_triangles, std::numeric_limits<Index>::max()));
  }
  if (num_vertices == 0) {
    Fail(what, num_triangles == 0 ? "the file contains no vertices and no faces"
                                  : "the file contains no vertices");
  }
  if (num_triangles == 0) {
    Fail(what, fmt::format("no faces: the file contains {} vertices but no faces", num_vertices));
  }
  Mesh mesh;
  mesh.vertices.resize(num_vertices, 3);
  for (int64_t v = 0; v < num_vertices; ++v) {
    for (int d = 0; d < 3; ++d) {
      const double value = raw.xyz[3 * v + d];
      if (!std::isfinite(value)) {
        Fail(what, fmt::format("non-finite coordinate: vertex {} (0-based) is ({}, {}, {})", v,
                               raw.xyz[3 * v], raw.xyz[3 * v + 1], raw.xyz[3 * v + 2]));
      }
      mesh.vertices(v, d) = value;
    }
  }
  mesh.elements.resize(num_triangles, 3);
  for (int64_t t = 0; t < num_triangles; ++t) {
    for (int a = 0; a < 3; ++a) {
      const int64_t v = raw.corners[3 * t + a];
      if (v < 0 || v >= num_vertices) {
        Fail(what, fmt::format("{}: vertex index out of range: {} (0-based), but the file has "
                               "{} vertices",
                               raw.Origin(t), v, num_vertices));
      }
      for (int b = 0; b < a; ++b) {
        if (raw.corners[3 * t + b] == v) {
          Fail(what, fmt::format("{}: degenerate face: it uses vertex {} (0-based) twice",
                                 raw.Origin(t), v));
        }
      }
      mesh.elements(t, a) = static_cast<Index>(v);
    }
  }
  ValidateMesh(mesh, what);
  return mesh;
}

Positions ToPositions(const std::vector<double>& xyz) {
  Positions positions(static_cast<Index>(xyz.size() / 3), 3);
  for (Index v = 0; v < positions.rows(); ++v) {
    for (int d = 0; d < 3; ++d) positions(v, d) = xyz[3 * static_cast<size_t>(v) + d];
  }
  return positions;
}

// The Mesh of `raw`, oriented; flat tetrahedra are errors naming their line. Every tetrahedron
// comes out positively oriented (OrientTetrahedra): a rest tetrahedron's corner order carries no
// meaning, so files written with the opposite convention are accepted (with a note). Flat
// tetrahedra are errors: no energy can use them.
Mesh BuildTetrahedralMesh(const RawTetrahedra& raw, std::vector<std::string>* notes) {
  Mesh mesh;
  mesh.vertices = ToPositions(raw.xyz);
  mesh.elements.resize(static_cast<Index>(raw.tets.size()), 4);
  for (Index t = 0; t < mesh.num_elements(); ++t) {
    for (int a = 0; a < 4; ++a) mesh.elements(t, a) = raw.tets[t][a];
  }
  const TetrahedronOrientation orientation = OrientTetrahedra(mesh);
  if (!orientation.degenerate.empty()) {
    const Index t = orientation.degenerate.front();
    Fail(raw.tets_file,
         fmt::format("line {}: tetrahedron {} (0-based; corners {}, 0-based) is flat (zero "
                     "volume){}; flat tetrahedra have no orientation and no finite "
                     "cotangent weights",
                     raw.lines[t], t, fmt::join(raw.tets[t], " "),
                     orientation.degenerate.size() > 1
                         ? fmt::format(", one of {} flat tetrahedra", orientation.degenerate.size())
                         : std::string()));
  }
  if (orientation.reoriented > 0 && notes) {
    notes->push_back(
        fmt::format("{}: {} of {} tetrahedra had negative signed volume and were "
                    "reoriented (last two corners swapped)",
                    raw.tets_file, orientation.reoriented, mesh.num_elements()));
  }
  ValidateMesh(mesh, raw.tets_file);
  return mesh;
}

size_t ReserveFor(int64_t count, size_t size, int64_t min_bytes, const std::string& what,
                  std::string_view items) {
  if (count > std::numeric_limits<Index>::max()) {
    Fail(what, fmt::format("{} {}: more than harap's limit of {}", count, items,
                           std::numeric_limits<Index>::max()));
  }
  return static_cast<size_t>(std::min<int64_t>(count, static_cast<int64_t>(size) / min_bytes + 1));
}

}  // namespace harap::io_internal
