// SPDX-License-Identifier: MIT
#pragma once

#include <string>
#include <vector>

#include "framework/config.h"
#include "framework/mesh.h"

namespace harap {

/// Generates a built-in mesh from a table such as `{ builtin = "cylinder", vertices = 480000 }`,
/// deterministic for the same parameters; unknown names or keys throw ConfigError listing the
/// valid ones. Built-ins:
///   - `cylinder`: a tube along z, height/diameter = `aspect` (default 4), with capped ends
///     (`caps = true`) or open; `vertices` ≈ vertex count.
///   - `plane`: the paper's "spike plane": a square grid in the xy-plane of about `vertices`
///     vertices with `spikes` sharp bumps of height `spike_height` (fractions of the side).
Mesh MakeBuiltinMesh(const ConfigNode& parameters);

std::vector<std::string> BuiltinMeshNames();

}  // namespace harap
