// SPDX-License-Identifier: MIT
// Tetrahedral mesh files: TetGen .node/.ele and MEDIT .mesh (ASCII), optionally xz-compressed.
// ReadMesh (mesh_io.h) dispatches to these by extension; they are public for callers that want
// one format explicitly.
#pragma once

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

#include "framework/mesh.h"

namespace harap {

/// Reads a TetGen mesh. `file` is either the `.node` or the `.ele` file (each optionally `.xz`);
/// the other one is the file beside it with the same stem (`x.node.xz` pairs with `x.ele.xz` or
/// `x.ele`). Numbering: the first point id of the `.node` file (0 or 1) is the base of every
/// index in both files, as TetGen and WRAPD read them; point ids must be consecutive, and the
/// `.ele` file must number its tetrahedra from the same base. Attributes and boundary markers
/// are skipped; 10-node (quadratic) tetrahedra are refused. The result has #T×4 elements, 0-based,
/// every tetrahedron positively oriented (see OrientTetrahedra; `notes`, if given, receives a
/// line when some were reoriented). Throws InputError naming the file and line of the problem:
/// missing companion file, malformed or truncated rows, ids out of sequence, indices out of range,
/// repeated corners, non-finite coordinates, zero-volume tetrahedra.
Mesh ReadTetGenMesh(const std::filesystem::path& file, std::vector<std::string>* notes = nullptr);

/// The points of a TetGen `.node` file only (no `.ele` needed), e.g. a start configuration.
Positions ReadTetGenNodes(const std::filesystem::path& node_file);

/// Reads a MEDIT `.mesh` file (ASCII, `Dimension 3`): its `Vertices` and `Tetrahedra` sections
/// (1-based, references ignored); the other standard sections (Edges, Triangles, Corners, Ridges,
/// Normals, ...) are parsed and skipped, an unknown keyword is an error. Orientation, notes and
/// errors as for ReadTetGenMesh.
Mesh ReadMeditMesh(const std::filesystem::path& file, std::vector<std::string>* notes = nullptr);

/// The vertices of a MEDIT `.mesh` file (its tetrahedra are range-checked but may be inverted or
/// flat, as in a deformed start configuration).
Positions ReadMeditVertices(const std::filesystem::path& file);

/// 6 × the signed volume of the tetrahedron (a, b, c, d): det([b − a, c − a, d − a]). Positive is
/// harap's orientation (TetGen's and WRAPD's too): d lies on the side of triangle (a, b, c) that
/// its counter-clockwise normal points to.
double TetrahedronDeterminant(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c, const Eigen::Vector3d& d);

/// What OrientTetrahedra found.
struct TetrahedronOrientation {
  Index reoriented = 0;              ///< Tetrahedra with negative volume, now swapped.
  std::vector<Index> degenerate;     ///< Flat tetrahedra (see OrientTetrahedra), ascending.
};

/// Makes every tetrahedron of `mesh` positively oriented by swapping its last two corners where
/// the signed volume is negative. The vertex order of a rest tetrahedron carries no meaning (the
/// per-tetrahedron energies are invariant under permuting its corners), so this only fixes the
/// convention later code relies on (inversion = negative volume relative to the rest state).
/// Tetrahedra that are flat to rounding precision, |det| ≤ 1e-12 · |b − a| |c − a| |d − a| (for
/// a regular tetrahedron the ratio is 0.71), have no orientation and no finite cotangent
/// weights; they are listed in `degenerate` and left unchanged. Triangle meshes: no-op.
TetrahedronOrientation OrientTetrahedra(Mesh& mesh);

}  // namespace harap
