// SPDX-License-Identifier: MIT
// What the mesh parsers produce before validation, and its checked conversion to a Mesh: shared
// by the per-format readers (obj_reader, off_reader, ply_reader, stl_reader for triangles;
// tetgen_reader, medit_reader for tetrahedra). Internal to harap::io.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "framework/mesh.h"

namespace harap::io_internal {

/// Triangles as parsed: coordinates and 0-based corners not yet checked, with where each
/// triangle came from for error messages.
struct RawMesh {
  std::vector<double> xyz;       ///< 3 per vertex
  std::vector<int64_t> corners;  ///< 3 per triangle, 0-based, not yet range checked
  /// Per triangle: where it came from, for error messages ("line 12", "face 7").
  std::vector<int64_t> origin;
  const char* origin_kind = "line";
  /// Optionally, per triangle, where its face starts in the file (PLY: the line, or the byte
  /// offset in binary files), when `origin` is a face number.
  std::vector<int64_t> location;
  const char* location_kind = "";

  /// "line 12", "face 7" or "byte 345: face 7".
  std::string Origin(size_t triangle) const;
  /// Appends `polygon` fan-triangulated (v0, vi, vi+1), each triangle from `where`.
  void AddPolygon(const std::vector<int64_t>& polygon, int64_t where);
};

/// Turns the raw lists into a Mesh, checking what ValidateMesh checks but with the file position
/// of the offending face in the message (InputError prefixed by `what`): no vertices, no faces,
/// non-finite coordinates, indices out of range, a vertex used twice by one face.
Mesh BuildMesh(const RawMesh& raw, const std::string& what);

/// Tetrahedra as read: 0-based corners (range-checked by the parser) and the line of each.
struct RawTetrahedra {
  std::vector<double> xyz;                 ///< 3 per vertex
  std::vector<std::array<Index, 4>> tets;  ///< 0-based
  std::vector<size_t> lines;               ///< per tetrahedron
  std::string tets_file;                   ///< where the tetrahedra were read (for messages)
};

/// The Mesh of `raw`, every tetrahedron positively oriented (OrientTetrahedra); flat tetrahedra
/// are errors naming their line; `notes`, if given, receives a line when some were reoriented.
Mesh BuildTetrahedralMesh(const RawTetrahedra& raw, std::vector<std::string>* notes);

/// Coordinates (3 per vertex) as a #V×3 matrix.
Positions ToPositions(const std::vector<double>& xyz);

/// Memory to reserve for `count` declared items of at least `min_bytes` each in `size` bytes of
/// data: a corrupt header must not trigger a huge allocation (a truncated file is then reported
/// where it ends). Counts beyond the Index range are errors naming `what` and `items`.
size_t ReserveFor(int64_t count, size_t size, int64_t min_bytes, const std::string& what,
                  std::string_view items);

}  // namespace harap::io_internal
