// SPDX-License-Identifier: MIT
// Registration cases whose answer is known (docs/registration.md, "Known answers"): a deformation
// scenario solved by `harap deform` gives the answer U; the target is made from U (its mesh, or
// points sampled on it, or those points damaged); registering the rest mesh to the target
// without correspondences should find U again.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "api/register.h"
#include "framework/config.h"
#include "framework/mesh.h"
#include "framework/registries.h"
#include "io/scenario.h"
#include "spatial/surface_sampling.h"

namespace harap {

/// What a known-answer case registers to.
enum class KnownAnswerTarget {
  kMesh,     ///< the deformed mesh itself (closest points on its triangles)
  kPoints,   ///< points sampled uniformly on the deformed surface, with normals
  kDamaged,  ///< those points with a hole and outliers (PointDamage)
};

/// "mesh", "points", "damaged".
std::string_view KnownAnswerTargetName(KnownAnswerTarget target);
/// The names above, in that order.
std::vector<std::string> KnownAnswerTargetNames();
/// Throws ConfigError listing the valid names.
KnownAnswerTarget ParseKnownAnswerTarget(std::string_view name);

struct KnownAnswerOptions {
  KnownAnswerTarget target = KnownAnswerTarget::kPoints;
  /// Points sampled per source vertex (points and damaged targets).
  double points_per_vertex = 2.0;
  PointDamage damage;      ///< damaged targets: the hole and the outliers
  std::uint64_t seed = 1;  ///< of the sampling and the damage
  int threads = 0;         ///< of the answer's solve; 0: all hardware threads
  /// Throws ConfigError naming the first value out of range.
  void Validate() const;
};

/// A registration case with its answer.
struct KnownAnswerCase {
  Mesh source;                     ///< the scenario's mesh at rest
  Positions answer;                ///< its vertices deformed by `harap deform SCENARIO`
  RegistrationTarget target;       ///< made from `answer`
  std::string answer_description;  ///< how the answer was solved, for reports
};

/// Solves `scenario` with the run config `answer_config` (`harap deform`'s tables; empty:
/// its defaults) and makes the target (of a tetrahedral mesh: from its boundary). Throws
/// InputError for a planar mesh or when the scenario's solve does not give one position per mesh
/// vertex (a mesh that repair would weld).
KnownAnswerCase MakeKnownAnswerCase(const Registries& registries, const Scenario& scenario,
                                    const ConfigNode& answer_config,
                                    const KnownAnswerOptions& options);

/// The files of a case in a folder: source (the rest mesh) and answer (the deformed mesh), as
/// .ply for a triangle mesh and as MEDIT .mesh for a tetrahedral one (PLY would keep only its
/// boundary), and target.ply (the deformed surface, or the points with their normals as a PLY
/// without faces, which `harap register` reads as a point cloud).
struct KnownAnswerFiles {
  std::filesystem::path source, target, answer;
  static KnownAnswerFiles In(const std::filesystem::path& folder, ElementKind kind);
  /// The files of a case written in `folder` (either kind), or nothing when it holds none.
  static std::optional<KnownAnswerFiles> Find(const std::filesystem::path& folder);
};

/// Writes the case's files into `folder` (created if missing). Throws InputError naming a file
/// that cannot be written.
KnownAnswerFiles WriteKnownAnswerCase(const KnownAnswerCase& known,
                                      const std::filesystem::path& folder);

}  // namespace harap
