// SPDX-License-Identifier: MIT
// OFF triangle meshes (ASCII); ReadMesh (mesh_io.h) dispatches here by extension.
#pragma once

#include <string>
#include <string_view>

#include "framework/mesh.h"

namespace harap {

/// Parses ASCII OFF text: header `OFF` (or COFF, NOFF, STOFF, ...), counts `nv nf ne`, one vertex
/// per line (x y z, further values ignored), one face per line (n i1 ... in, 0-based), polygons
/// fan-triangulated. Binary OFF, 4OFF and nOFF are refused. Throws InputError naming `source`
/// and the line of the problem.
Mesh ParseOff(std::string_view data, const std::string& source);

}  // namespace harap
