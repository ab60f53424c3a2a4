// SPDX-License-Identifier: MIT
// `harap register SOURCE TARGET`: non-rigid registration with ARAP as the regularizer
// (solvers/optimizers/registration.h; docs/registration.md), from files or from memory.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "framework/closest_points.h"
#include "framework/config.h"
#include "framework/context.h"
#include "framework/mesh.h"
#include "framework/optimizer.h"
#include "framework/registries.h"
#include "solvers/optimizers/registration.h"

namespace harap {

/// A registration target as read: a triangle mesh or a point cloud (normals optional).
struct RegistrationTarget {
  std::string name;  ///< the file, for messages and the report
  std::optional<Mesh> mesh;
  Positions points = Positions(0, 3);   ///< a point cloud (when `mesh` is empty)
  Positions normals = Positions(0, 3);  ///< the point cloud's, or none
  Index num_points() const { return mesh ? mesh->num_vertices() : points.rows(); }
};

/// Reads a target file: point-cloud files (.xyz, .pts, .txt, and PLY files that declare no faces;
/// HoldsPointCloud) as points, every other mesh file as a mesh (a tetrahedral one is searched on
/// its boundary). Throws InputError naming the file.
RegistrationTarget ReadRegistrationTarget(const std::filesystem::path& file);

/// Reads landmarks: one per line, `vertex x y z` (0-based source vertex and the target point);
/// `#` comments and blank lines skipped. Throws InputError naming the file and line.
Constraints ReadLandmarks(const std::filesystem::path& file);

struct RegisterOptions {
  int threads = 0;  ///< 0: all hardware threads.
  /// Every local/global iteration (level, energy, ...); kStop ends the run (e.g. on Ctrl-C).
  IterationCallback progress;
  PhaseCallback phase;
  Constraints landmarks;          ///< source vertex → target point (ReadLandmarks)
  std::vector<double> stiffness;  ///< per source element, or empty
};

/// Everything a registration produced.
struct RegisterOutcome {
  std::string mode;  ///< "hierarchical" or "flat" (`[optimizer] type`: hierarchical or classic)
  std::string energy_type, solver, hierarchy, upsampler;
  int threads = 0;
  RegistrationOptions options;
  RegistrationResult result;
  double target_seconds = 0.0;  ///< building the target's spatial index
  std::string resolved_config;
  bool interrupted = false;  ///< set by the caller (Ctrl-C)
};

/// The run config tables `harap register` reads: `[optimizer]` (type "hierarchical", the
/// default, or "classic" for one level; the local/global options: tolerance is per update),
/// `[energy]`, `[solver]`, `[hierarchy]`, `[upsampler]` and `[registration]`
/// (RegistrationOptions). Unknown tables and keys are rejected before any work.
RegisterOutcome RunRegister(const Registries& registries, const Mesh& source,
                            const RegistrationTarget& target, const ConfigNode& config,
                            const RegisterOptions& options);

/// The JSON report of a registration (docs/registration.md lists the keys).
std::string RegisterReportJson(const std::string& source_name, const Mesh& source,
                               const RegistrationTarget& target, const RegisterOutcome& outcome);

}  // namespace harap
