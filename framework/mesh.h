// SPDX-License-Identifier: MIT
#pragma once

#include <string>
#include <string_view>

#include "framework/types.h"

namespace harap {

/// A triangle with 2·area ≤ kDegenerateTriangleRatio · (longest edge)² has no well-defined angles
/// (its cotangents would be ±inf or NaN): the energies give it zero weight, so it contributes
/// nothing to the energy, and the mesh checks report it as degenerate. See docs/energies.md.
inline constexpr double kDegenerateTriangleRatio = 1e-12;

enum class ElementKind { kTriangle, kTetrahedron };

/// The rest state of a simplicial mesh: positions and elements, nothing derived. Triangles in 3D
/// (surfaces), triangles in the plane (`planar`, z = 0) or tetrahedra. Vertices referenced by no
/// element are allowed (real meshes have them); optimizers keep them at their rest positions.
struct Mesh {
  Positions vertices;  ///< #V×3 rest positions.
  Elements elements;   ///< #F×3 triangles or #T×4 tetrahedra, 0-based.
  bool planar =
      false;  ///< Triangles in the xy-plane, deformed in the plane (per-simplex 2D energies).

  Index num_vertices() const { return static_cast<Index>(vertices.rows()); }
  Index num_elements() const { return static_cast<Index>(elements.rows()); }
  int simplex_size() const { return static_cast<int>(elements.cols()); }
  ElementKind kind() const {
    return elements.cols() == 4 ? ElementKind::kTetrahedron : ElementKind::kTriangle;
  }
};

/// Throws InputError naming `what` (e.g. the file) if the mesh has a non-finite coordinate, an
/// element index out of range, an element with a repeated index, or an unsupported element size.
void ValidateMesh(const Mesh& mesh, std::string_view what);

/// Length of the diagonal of the axis-aligned bounding box of the vertices referenced by elements
/// (all vertices if none is referenced).
double BoundingBoxDiagonal(const Mesh& mesh);

/// For each vertex: true if some element references it.
std::vector<bool> ReferencedVertices(const Mesh& mesh);

}  // namespace harap
