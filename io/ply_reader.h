// SPDX-License-Identifier: MIT
// PLY triangle meshes (ASCII and binary); ReadMesh (mesh_io.h) dispatches here by
// extension.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "framework/mesh.h"
#include "io/point_cloud.h"

namespace harap {

/// Parses PLY data, ASCII or binary (either byte order): `vertex` with x y z of any scalar type
/// (kept exact, float64 included), `face` with a `vertex_indices` (or `vertex_index`) list,
/// polygons fan-triangulated; other elements and properties are skipped. Throws InputError
/// naming `source` and the header line, data line or byte offset of the problem.
Mesh ParsePly(std::string_view data, const std::string& source);

/// The `vertex` element of PLY data as a point cloud: x y z and, where all three are there, the
/// normals nx ny nz; faces and everything else are ignored. Errors as ParsePly's.
PointCloud ParsePlyPoints(std::string_view data, const std::string& source);

/// A scalar property of a PLY mesh's vertices or faces.
struct PlyMeshProperty {
  std::string element;         ///< "vertex" or "face"
  std::vector<double> values;  ///< per vertex, or per triangle of ParsePly's mesh (a polygon's
                               ///< value on each triangle of its fan)
};

/// Reads the scalar property `name` of the `vertex` or `face` element of PLY data that ParsePly
/// reads as a mesh (same vertex and triangle order). Throws InputError naming `source` when
/// neither element (or both) has a scalar property of that name, listing those there are.
PlyMeshProperty ParsePlyMeshProperty(std::string_view data, const std::string& source,
                                     const std::string& name);

/// Whether PLY data's header declares a non-empty `face` element (a mesh rather than a point
/// cloud). Throws InputError for a malformed header.
bool PlyDeclaresFaces(std::string_view data, const std::string& source);

}  // namespace harap
