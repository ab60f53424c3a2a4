// SPDX-License-Identifier: MIT
// MEDIT .mesh tetrahedral meshes (ASCII), optionally xz-compressed. ReadMesh (mesh_io.h)
// dispatches here by extension.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "framework/mesh.h"

namespace harap {

/// Reads a MEDIT `.mesh` file (ASCII, `Dimension 3`): its `Vertices` and `Tetrahedra` sections
/// (1-based, references ignored); the other standard sections (Edges, Triangles, Corners, Ridges,
/// Normals, ...) are parsed and skipped, an unknown keyword is an error. Orientation, notes and
/// errors as for ReadTetGenMesh.
Mesh ReadMeditMesh(const std::filesystem::path& file, std::vector<std::string>* notes = nullptr);

/// The vertices of a MEDIT `.mesh` file (its tetrahedra are range-checked but may be inverted or
/// flat, as in a deformed start configuration).
Positions ReadMeditVertices(const std::filesystem::path& file);

}  // namespace harap
