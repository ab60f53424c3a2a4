// SPDX-License-Identifier: MIT
#pragma once

#include <filesystem>
#include <string>
#include <vector>
#include <string_view>

#include "framework/mesh.h"

namespace harap {

/// Reads a mesh file. Triangle meshes: OBJ, PLY (ASCII and binary), OFF (ASCII), STL.
/// Tetrahedral meshes: TetGen `.node`/`.ele` (either file names the pair) and MEDIT `.mesh`
/// (see tet_mesh_io.h). Each optionally xz-compressed (`.obj.xz`, decompressed in memory). OBJ,
/// PLY and OFF are parsed by harap itself, keeping double coordinates exact (OpenMesh's readers
/// round them to float, see mesh_io.cpp); STL goes through OpenMesh's reader. Faces with more
/// than three vertices are fan-triangulated. The vertex order of the file is kept, unreferenced
/// vertices included. The result is never `planar` (that is the scenario's decision). Tetrahedra
/// come out positively oriented; `notes`, if given, receives a line when some were reoriented.
/// Thread-safe. Throws InputError naming the file, the line where there is one, and what is
/// wrong (missing, unreadable, unknown format, non-finite coordinates, indices out of range, no
/// faces, flat tetrahedra).
Mesh ReadMesh(const std::filesystem::path& file, std::vector<std::string>* notes = nullptr);

/// The vertex positions of a mesh file, e.g. a start configuration (a scenario's `initial`):
/// for a TetGen `.node` file the `.ele` file is not needed, and the tetrahedra of a MEDIT `.mesh`
/// file may be inverted or flat (a deformed state). Other formats as ReadMesh.
Positions ReadMeshVertices(const std::filesystem::path& file);

/// Parses mesh data held in memory, as ReadMesh does a file's contents: `name` (a file name) picks
/// the format by its extension (a trailing `.xz` means `data` is xz-compressed) and names the
/// data in error messages. For data that arrive without a file (and the fuzz harnesses).
Mesh ParseMesh(std::string_view data, const std::filesystem::path& name);

/// Writes binary little-endian PLY with double-precision coordinates (`property double x`) and
/// int triangle indices, in the given vertex order, so results can be compared exactly.
/// Tetrahedra (4 columns) are written as their boundary triangles, oriented outwards; every
/// vertex is still written, so the file lines up with the input vertex by vertex.
void WritePly(const std::filesystem::path& file, const Positions& vertices,
              const Elements& elements);

/// The boundary triangles of a tetrahedral mesh (faces of exactly one tetrahedron), oriented
/// outwards for positively oriented tetrahedra, in the order of their tetrahedra.
Elements BoundaryTriangles(const Elements& tetrahedra);

/// Reads the whole file, decompressing it in memory when the name ends in `.xz`.
std::string ReadFileMaybeXz(const std::filesystem::path& file);

}  // namespace harap
