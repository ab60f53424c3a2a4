// SPDX-License-Identifier: MIT
// Deformation scenarios made from a mesh alone, for datasets that come without any: two handles
// at the ends of the mesh's longest principal axis, one held, one moved by a kind of motion.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "framework/mesh.h"

namespace harap {

/// The motion of the moved handle (the other one is held in place). Axes are the principal axes
/// of the handles' component: a1 the longest (the handles sit at its two ends), a2, a3 = a1 × a2.
enum class ScenarioKind {
  kBend,     ///< rotated 60° about a3 (about its centroid): the shape bends in the a1–a2 plane
  kTwist,    ///< rotated 90° about a1 (about its centroid): the shape twists about its length
  kLift,     ///< shifted by a quarter of the length along a2: a shear across the length
  kStretch,  ///< shifted by a fifth of the length along a1, away from the held end
};

/// "bend", "twist", "lift", "stretch", in the enum's order.
const std::vector<std::string>& ScenarioKindNames();
/// The kind named `name`; ConfigError listing the valid names otherwise.
ScenarioKind ParseScenarioKind(std::string_view name);

struct ScenarioGeneratorOptions {
  ScenarioKind kind = ScenarioKind::kBend;
  /// Vertices per handle, as a fraction of the handles' component (at least 3 vertices each).
  double handle_fraction = 0.05;
  /// Loop subdivision rounds written into the scenario (`refine`); the handles are chosen on
  /// the refined mesh, so they are as dense as the mesh that is solved.
  int refine = 0;
};

/// The scenario file text for `mesh` (already refined `options.refine` times), which the scenario
/// names as `mesh_reference`. Deterministic: the same mesh gives the same text. The handles lie
/// on the mesh's largest connected component (other components are pinned as in any scenario):
/// each is the vertices nearest, along the mesh's edges, to one extreme vertex of the longest
/// principal axis. Throws InputError naming `what` when the mesh cannot hold two such handles
/// (no triangles, fewer than 12 vertices, a degenerate shape).
std::string GenerateScenarioToml(const Mesh& mesh, const std::string& mesh_reference,
                                 const ScenarioGeneratorOptions& options, const std::string& what);

/// Reads `mesh_file`, refines it, and returns the scenario text (GenerateScenarioToml), the mesh
/// named by `mesh_reference`. Unreadable or unusable meshes are InputErrors naming the file.
std::string GenerateScenarioForFile(const std::filesystem::path& mesh_file,
                                    const std::string& mesh_reference,
                                    const ScenarioGeneratorOptions& options);

}  // namespace harap
