// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "framework/closest_points.h"
#include "framework/config.h"
#include "framework/context.h"
#include "framework/level_solver.h"
#include "framework/mesh.h"
#include "framework/optimizer.h"

namespace harap {

/// The options of a registration (the run config's `[registration]` table; docs/registration.md).
struct RegistrationOptions {
  /// The data weight λ, per unit of vertex mass (a vertex's area over the squared bounding-box
  /// diagonal), rises geometrically from `data_weight_start` to `data_weight_end` over `stages`
  /// stages: a soft fit first (ARAP dominates, large motions stay rigid), a close one at the end.
  /// Each stage factors the global step at least once.
  double data_weight_start = 10.0;
  double data_weight_end = 1e4;
  int stages = 3;
  /// Hierarchical runs: the coarsest level runs every stage (the alignment of the whole shape);
  /// each finer level starts from the up-sampled result and runs only the last `refine_stages`.
  int refine_stages = 1;
  /// Correspondence updates per stage and level at most; a stage ends earlier when an update
  /// moved the vertices by less than `tolerance` (RMS, relative to the bounding-box diagonal).
  int max_updates = 30;
  double tolerance = 5e-5;
  /// Local/global iterations between two correspondence updates.
  int inner_iterations = 2;
  /// Point-to-plane: a vertex is pulled to its projection onto the target's tangent plane at its
  /// closest point (where the target has normals), a point target recomputed at every update, so
  /// the data term keeps the n×n form; false: to the closest point itself (point-to-point).
  bool point_to_plane = true;
  /// Symmetric correspondences: besides its closest point on the target, each vertex is pulled
  /// towards the mean of the target points whose nearest source vertex it is (needs
  /// RegistrationProblem::make_point_search). Parts of the target that no vertex has as its
  /// closest point, such as a stretched limb, then pull too.
  bool symmetric = true;
  /// Rejected correspondences keep their data weight and pull their vertex to where it is (a
  /// proximal term, no refactoring); once the kept ones differ from those the system was
  /// factored with in more than this fraction of the vertices, it is factored anew with full
  /// weights on the kept ones only.
  double refactor_fraction = 0.05;
  /// A correspondence farther than this (relative to the source's bounding-box diagonal) is
  /// rejected.
  double max_distance = 0.1;
  /// A correspondence whose target normal differs from the vertex normal by more than this
  /// (degrees) is rejected (targets with normals only; 180: never).
  double max_normal_angle = 60.0;
  /// Reject correspondences on the target mesh's boundary (where a partial scan ends).
  bool reject_boundary = true;
  /// The weight of a landmark's pull, relative to the final data weight.
  double landmark_weight = 10.0;
  /// false: register the input mesh alone (one level, the flat baseline); true: the hierarchy's
  /// levels from the coarsest down, each starting from the up-sampled result of the coarser.
  /// Not read by FromConfig: `harap register` takes it from the optimizer's type.
  bool hierarchical = true;

  /// The data weight of stage s (0-based).
  double DataWeight(int stage) const;
  static RegistrationOptions FromConfig(OptionReader node);
};

/// What to register: the source mesh (a triangle surface) onto a target.
struct RegistrationProblem {
  const Mesh* source = nullptr;
  const ClosestPointSearch* target = nullptr;
  /// Landmarks: source vertex indices[k] is pulled towards targets.row(k) with the landmark
  /// weight (weights are ignored). Indices are unique.
  Constraints landmarks;
  /// Builds a search over the source's current vertices (symmetric correspondences); empty: none.
  PointSearchFactory make_point_search;
  /// Per-element stiffness of `source` (framework/stiffness.h); empty: 1 everywhere.
  std::vector<double> stiffness;
};

/// Why correspondences were rejected, counted at the end of a registration (finest level).
struct CorrespondenceCounts {
  Index kept = 0;
  Index too_far = 0;
  Index normal_angle = 0;
  Index boundary = 0;
};

struct RegistrationResult {
  /// positions (the registered source), levels (finest first; per level the measures
  /// "correspondence_updates", "kept_fraction", "residual_rms"), timings, iterations, stops.
  /// `energy` is the objective ARAP + data term of the last update.
  OptimizeResult run;
  double arap_energy = 0.0;  ///< the ARAP energy of the result alone
  /// Per source vertex: distance to the target's closest point after registration.
  std::vector<double> distance;
  /// Over the kept correspondences of the result: RMS and largest distance.
  double residual_rms = 0.0;
  double residual_max = 0.0;
  CorrespondenceCounts correspondences;
  int correspondence_updates = 0;  ///< summed over levels and stages
};

/// Deforms `problem.source` onto `problem.target` with ARAP as the regularizer (non-rigid ICP,
/// docs/registration.md). Each update finds every vertex's closest point on the target, rejects
/// outliers (distance, normal angle, target boundary), and runs `inner_iterations` local/global
/// iterations of the objective
///
///     E(U, R) = E_ARAP(U, R) + Σ_v λ m_v ‖u_v − c_v‖² + landmark terms,
///
/// (m_v: the input vertices v stands for on a coarse level; c_v the closest point). The data
/// term is point-to-point, the coupled form of every energy (framework/data_term.h), so a
/// factorization serves every update until the set of kept correspondences changes much
/// (RegistrationOptions::refactor_fraction): until then a rejected vertex keeps its weight and
/// is pulled to where it is (a proximal term that vanishes at a fixed point), so rejections
/// change only the right-hand side. `level_solver` (a prototype: local_global) solves each level;
/// `factory` makes its pieces and the hierarchy. Reports iterations through the context's callback,
/// which may stop the run; never prints. Throws InputError for a source that is not a triangle
/// surface, a landmark out of range, or an empty target.
RegistrationResult Register(const RegistrationProblem& problem, const RegistrationOptions& options,
                            const LevelSolver& level_solver, const ComponentFactory& factory,
                            const Context& context);

}  // namespace harap
