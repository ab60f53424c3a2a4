// SPDX-License-Identifier: MIT
// OFF triangle meshes (ASCII and binary); ReadMesh (mesh_io.h) dispatches here by extension.
#pragma once

#include <string>
#include <string_view>

#include "framework/mesh.h"

namespace harap {

/// Parses ASCII OFF text: header `OFF` (or COFF, NOFF, STOFF, ...), counts `nv nf ne`, one vertex
/// per line (x y z, further values ignored), one face per line (n i1 ... in, 0-based), polygons
/// fan-triangulated. Binary OFF (header `OFF BINARY`): int32 counts, float32 coordinates, int32
/// faces, little-endian without per-face colour counts or Geomview's big-endian with them; the
/// layout that reads the whole file is taken. 4OFF and nOFF are refused. Throws InputError naming
/// `source` and the line (or byte) of the problem.
Mesh ParseOff(std::string_view data, const std::string& source);

}  // namespace harap
