// SPDX-License-Identifier: MIT
// TetGen .node/.ele tetrahedral meshes (ASCII), optionally xz-compressed. ReadMesh (mesh_io.h)
// dispatches here by extension.
#pragma once

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

}  // namespace harap
