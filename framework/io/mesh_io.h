// SPDX-License-Identifier: MIT
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

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

/// Parses mesh data held in memory, as ReadMesh does a file's contents: `name` (a file name) picks
/// the format by its extension (a trailing `.xz` means `data` is xz-compressed) and names the
/// data in error messages. For data that arrive without a file (and the fuzz harnesses).
Mesh ParseMesh(std::string_view data, const std::filesystem::path& name);

/// Writes binary little-endian PLY with double-precision coordinates (`property double x`) and
/// int triangle indices, in the given vertex order, so results can be compared exactly.
void WritePly(const std::filesystem::path& file, const Positions& vertices,
              const Elements& elements);

/// Reads the whole file, decompressing it in memory when the name ends in `.xz`.
std::string ReadFileMaybeXz(const std::filesystem::path& file);

}  // namespace harap
