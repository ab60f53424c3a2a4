// SPDX-License-Identifier: MIT
// STL triangle meshes (ASCII and binary) through OpenMesh's reader; ReadMesh (mesh_io.h)
// dispatches here by extension.
#pragma once

#include <string>
#include <string_view>

#include "framework/mesh.h"

namespace harap {

/// Parses STL data, binary (recognized by its size: 84 + 50 bytes per triangle) or ASCII
/// (`solid ...`), through OpenMesh's reader, which welds the corners of equal float coordinates
/// into shared vertices. Throws InputError naming `source` and the problem (truncation,
/// non-finite or unparsable coordinates, what OpenMesh reported).
Mesh ParseStl(std::string_view data, const std::string& source);

}  // namespace harap
