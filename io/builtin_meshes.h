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
///   - `cylinder`: a tube along z (diameter 1, z in [0, aspect]), height/diameter = `aspect`
///     (default 4), with capped ends (`caps = true`) or open; `vertices` ≈ vertex count.
///     Near-equilateral triangles on the side, concentric rings on the caps.
///   - `plane`: the paper's "spike plane": a square grid on [0,1]^2 (z = 0) of about `vertices`
///     vertices with `spikes` (16) conical spikes of height `spike_height` (0.2) and base radius
///     `spike_radius` (0.02), placed by `seed` (1); lengths are fractions of the side.
///   - `disk` (planar): radius 0.5 about the origin in the xy-plane, concentric rings of
///     near-equilateral triangles like the cylinder's caps; `vertices` ≈ vertex count.
///   - `rectangle` (planar): [0, `aspect`] × [0, 1] in the xy-plane (aspect = width / height,
///     default 4), a grid of nearly square cells split by alternating diagonals; `vertices` ≈
///     vertex count.
/// Planar built-ins come with `Mesh::planar` set and counter-clockwise triangles (normals +z).
Mesh MakeBuiltinMesh(OptionReader parameters);
/// The same for a table read on its own (the record of its keys is new).
Mesh MakeBuiltinMesh(const ConfigNode& parameters);

std::vector<std::string> BuiltinMeshNames();

}  // namespace harap
