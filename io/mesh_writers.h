// SPDX-License-Identifier: MIT
// Writing meshes in the format their file name asks for (`harap deform --out result.obj`).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "framework/mesh.h"

namespace harap {

/// One value per vertex under a name: a PLY vertex property (e.g. `distance`).
struct VertexValues {
  std::string name;
  std::vector<double> values;
};

/// Writes binary little-endian PLY with double-precision coordinates (`property double x`) and
/// int triangle indices, in the given vertex order, so results can be compared exactly.
/// Tetrahedra (4 columns) are written as their boundary triangles, oriented outwards; every
/// vertex is still written, so the file lines up with the input vertex by vertex. `values` become
/// `property double NAME` of the vertices, after x y z (names without spaces, one value per
/// vertex). Throws Error when the file cannot be written.
void WritePly(const std::filesystem::path& file, const Positions& vertices,
              const Elements& elements, const std::vector<VertexValues>& values = {});

/// The extensions WriteMesh accepts for meshes of `kind`, with what each writes, for messages:
/// triangle meshes .ply .obj .off .stl; tetrahedral meshes the same four (their boundary
/// triangles, every vertex still written) plus .mesh (MEDIT) and .node/.ele (TetGen pair).
std::string MeshOutputFormats(ElementKind kind);

/// Throws InputError naming `file` and the valid extensions (MeshOutputFormats) unless WriteMesh
/// can write a mesh of `kind` there. Only the name is looked at; call it before a long run so a
/// wrong extension fails at once (with kTetrahedron, before the mesh is known: it accepts every
/// extension some mesh can be written as).
void CheckMeshOutputFormat(const std::filesystem::path& file, ElementKind kind);

/// The files WriteMesh(file, ...) creates: `file`, or for TetGen both `stem.node` and `stem.ele`.
std::vector<std::filesystem::path> MeshOutputFiles(const std::filesystem::path& file);

/// Writes the mesh in the format of `file`'s extension (case-insensitive), keeping the vertex
/// order so the file lines up with the input vertex by vertex (STL excepted: it stores corners
/// per triangle, in float32, so its readers weld them anew):
///   .ply   binary PLY, double coordinates (WritePly)
///   .obj   text, coordinates in shortest round-trip decimal (exact), 1-based faces
///   .off   text, as .obj
///   .stl   binary STL (float32, per-face normals)
///   .mesh  MEDIT text, Vertices and Tetrahedra (tetrahedral meshes only)
///   .node  TetGen .node and .ele beside it, 0-based (tetrahedral meshes only; .ele names the
///          same pair)
/// Tetrahedral meshes written as .ply/.obj/.off/.stl give their boundary triangles. Throws
/// InputError for an unsupported extension and Error when a file cannot be written.
void WriteMesh(const std::filesystem::path& file, const Positions& vertices,
               const Elements& elements);

}  // namespace harap
