// SPDX-License-Identifier: MIT
// Reading a mesh file in the format its name says: the dispatcher over the per-format readers
// (obj_reader.h, off_reader.h, ply_reader.h, stl_reader.h, tetgen_reader.h, medit_reader.h),
// with xz-compressed files read through file_reading.h. Writing: mesh_writers.h.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "framework/mesh.h"

namespace harap {

/// Reads a mesh file. Triangle meshes: OBJ, PLY (ASCII and binary), OFF (ASCII and binary), STL.
/// Tetrahedral meshes: TetGen `.node`/`.ele` (either file names the pair) and MEDIT `.mesh`.
/// Each optionally xz-compressed (`.obj.xz`, decompressed in memory). OBJ, PLY and OFF are parsed
/// by harap itself, keeping double coordinates exact (OpenMesh's readers round them to float);
/// STL goes through OpenMesh's reader. Faces with more than three vertices are
/// fan-triangulated. The vertex order of the file is kept, unreferenced vertices included. The
/// result is never `planar` (that is the scenario's decision). Tetrahedra come out positively
/// oriented; `notes`, if given, receives a line when some were reoriented. Thread-safe. Throws
/// InputError naming the file, the line where there is one, and what is wrong (missing,
/// unreadable, unknown format, non-finite coordinates, indices out of range, no faces, flat
/// tetrahedra).
Mesh ReadMesh(const std::filesystem::path& file, std::vector<std::string>* notes = nullptr);

/// The vertex positions of a mesh file, e.g. a start configuration (a scenario's `initial`):
/// for a TetGen `.node` file the `.ele` file is not needed, and the tetrahedra of a MEDIT `.mesh`
/// file may be inverted or flat (a deformed state). Other formats as ReadMesh.
Positions ReadMeshVertices(const std::filesystem::path& file);

/// Parses mesh data held in memory, as ReadMesh does a file's contents: `name` (a file name) picks
/// the format by its extension (a trailing `.xz` means `data` is xz-compressed) and names the
/// data in error messages. Surface formats only. For data that arrive without a file (and the
/// fuzz harnesses).
Mesh ParseMesh(std::string_view data, const std::filesystem::path& name);

}  // namespace harap
