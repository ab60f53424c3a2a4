// SPDX-License-Identifier: MIT
#pragma once

#include <filesystem>

namespace harap::benchmarks {

/// Registers HierarchyBuild_<hierarchy>/<mesh>: Hierarchy::Build with default options, octree
/// against edge_collapse (the paper's Fig. 18), on a generated 170K-vertex cylinder and,
/// when present under `shared_dir`, the armadillo-bend and dragon-lift scenario meshes. Meshes are
/// loaded on first use, so filtered-out benchmarks cost nothing. Also IntrinsicDelaunay/<mesh>:
/// the intrinsic Delaunay triangulation and its cotangent weights on the same meshes.
void RegisterHierarchyBenchmarks(const std::filesystem::path& shared_dir);

}  // namespace harap::benchmarks
