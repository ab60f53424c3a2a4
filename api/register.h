// SPDX-License-Identifier: MIT
// `harap register SOURCE TARGET`: non-rigid registration with ARAP as the regularizer
// (solvers/optimizers/registration.h; docs/registration.md), from files or from memory.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "api/run_options.h"
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

/// The threads and callbacks (RunOptions: `progress` gets every local/global iteration), and:
struct RegisterOptions : RunOptions {
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

/// How far registered positions are from the answer, per vertex |u_v − U_v|, absolute and
/// relative to the rest mesh's bounding-box diagonal.
struct AnswerErrors {
  double mean = 0.0, max = 0.0, rms = 0.0;
  double diagonal = 0.0;
  Index worst_vertex = -1;
};

/// Throws InputError when the row counts differ (`what` names the answer in the message).
AnswerErrors CompareWithAnswer(const Positions& registered, const Positions& answer,
                               double diagonal, const std::string& what);

/// A known answer the registration is compared with (`harap register --answer`).
struct AnswerComparison {
  std::string file;
  AnswerErrors errors;
};

/// Checks a `harap register` run config (the tables RunRegister reads) against the registries
/// without a mesh: unknown tables, keys and names are a ConfigError. For experiment configs.
void CheckRegisterConfig(const Registries& registries, const ConfigNode& config);

/// The JSON report of a registration (docs/registration.md lists the keys).
/// `answer`: adds the report's `answer` object (errors against a known answer).
std::string RegisterReportJson(const std::string& source_name, const Mesh& source,
                               const RegistrationTarget& target, const RegisterOutcome& outcome,
                               const AnswerComparison* answer = nullptr);

}  // namespace harap
