// SPDX-License-Identifier: MIT
// Point clouds: the targets of `harap register` that are not meshes (docs/registration.md).
#pragma once

#include <filesystem>

#include "framework/types.h"

namespace harap {

/// Points and, optionally, their normals.
struct PointCloud {
  Positions points = Positions(0, 3);
  Positions normals = Positions(0, 3);  ///< none (0 rows) or one per point
};

/// Whether the file name says point cloud: .xyz, .pts or .txt (optionally .xz-compressed).
bool IsPointCloudFile(const std::filesystem::path& file);

/// Whether `file` holds a point cloud rather than a mesh: a point-cloud extension, or a PLY file
/// (optionally .xz) whose header declares no faces (the file is read for that). Throws InputError
/// for a missing file or a malformed PLY header.
bool HoldsPointCloud(const std::filesystem::path& file);

/// Reads a point cloud: text files (.xyz, .pts, .txt: one point per line, `x y z` or
/// `x y z nx ny nz`, the first point line fixing the column count; `#` comments and blank lines
/// skipped) or the vertices of a PLY file (normals where it has nx ny nz; faces ignored), each
/// optionally .xz-compressed. Throws InputError naming the file and the line (text) or the
/// point for a missing file, an unknown extension, no points, a wrong column count or a
/// non-finite value.
PointCloud ReadPointCloud(const std::filesystem::path& file);

/// Parses the text format of ReadPointCloud; `what` names the data in errors.
PointCloud ParsePointCloudText(std::string_view data, const std::string& what);

}  // namespace harap
