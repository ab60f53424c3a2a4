// SPDX-License-Identifier: MIT
#pragma once

#include <filesystem>

#include "framework/mesh.h"

namespace harap {

/// Reads a triangle mesh: OBJ, PLY (ASCII and binary), OFF (ASCII), STL, also xz-compressed
/// (`.obj.xz`, decompressed in memory). OBJ, PLY and OFF are parsed by harap itself, keeping
/// double coordinates exact (OpenMesh's readers round them to float, see mesh_io.cpp); STL goes
/// through OpenMesh's reader. Faces with more than three vertices are fan-triangulated. The
/// vertex order of the file is kept, unreferenced vertices included. Thread-safe.
/// Throws InputError naming the file and what is wrong (missing, unreadable, unknown format,
/// non-finite coordinates, indices out of range, no faces).
Mesh ReadMesh(const std::filesystem::path& file);

/// Writes binary little-endian PLY with double-precision coordinates (`property double x`) and
/// int triangle indices, in the given vertex order, so results can be compared exactly.
void WritePly(const std::filesystem::path& file, const Positions& vertices,
              const Elements& elements);

/// Reads the whole file, decompressing it in memory when the name ends in `.xz`.
std::string ReadFileMaybeXz(const std::filesystem::path& file);

}  // namespace harap
