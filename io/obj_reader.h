// SPDX-License-Identifier: MIT
// OBJ triangle meshes (text); ReadMesh (mesh_io.h) dispatches here by extension.
#pragma once

#include <string>
#include <string_view>

#include "framework/mesh.h"

namespace harap {

/// Parses OBJ text: `v x y z` (further values ignored) and `f a b c ...` (a = i, i/t, i//n or
/// i/t/n; 1-based, negative = relative to the last vertex), polygons fan-triangulated; other
/// statements (vt, vn, g, usemtl, ...) are skipped. Coordinates stay exact doubles. Throws
/// InputError naming `source` and the line of the problem.
Mesh ParseObj(std::string_view data, const std::string& source);

}  // namespace harap
