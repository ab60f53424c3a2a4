// SPDX-License-Identifier: MIT
#pragma once

#include <vector>

#include "framework/constrained_system.h"
#include "framework/context.h"
#include "framework/energy.h"
#include "framework/linear_solver.h"
#include "framework/types.h"

namespace harap {

/// The finest level's global step of a preview straight from the coarsest level (the paper's
/// coarse approximation, Fig. 15; LevelSolver::GlobalStepFromGathered): the rotations are not
/// written out per site but gathered from a few coarse ones. The same arithmetic as a global
/// step on the gathered rotations. Vertex rotation sites only.
///
/// The right-hand side B(R) is linear in the rotations and, for the ARAP energies, of the form
/// B_j = Σ_s R_s c_js over the sites s near vertex j; with the rotations gathered from a few
/// coarse ones that is B_j = Σ_c R_c w_jc with one or two clusters c per vertex. The first call
/// with a `source` finds the w_jc by probing Energy::AssembleRhs() (one probe per color of a
/// coloring of the clusters in which no vertex sees two clusters of one color) and verifies them
/// against AssembleRhs() on random matrices; if they agree (to rounding), later calls evaluate B
/// from w (a few entries per vertex, cache-resident coarse rotations) instead of gathering one
/// rotation per site and assembling from the energy's full coupling: the same right-hand side up
/// to rounding. Otherwise every call gathers and assembles.
///
/// Keeps its buffers and the map between calls (a session's preview frames). Not thread-safe.
class GatheredPreviewStep {
 public:
  /// The level it solves on (a LocalGlobalSolver's parts, constrained and factored).
  struct Level {
    const Energy& energy;
    GlobalStepSystem& system;
    LinearSolver& solver;
    int level = 0;  ///< for error messages
  };

  /// Rotation site (vertex) s takes coarse[source[s]] (kNoVertex: the identity; one per site);
  /// the fixed rows take `handles`' `targets` and, for the other fixed (pinned) vertices, their
  /// rows of `positions`; the free rows of `positions` receive the solution.
  SolveSummary Run(const Level& level, const std::vector<Index>& source, const Rotations& coarse,
                   const std::vector<Index>& handles, const Positions& targets,
                   Positions& positions, const Context& context);

  /// Whether Run() evaluates its right-hand side from the probed linear map (false before its
  /// first call or when the probe did not reproduce AssembleRhs()).
  bool rhs_is_linear() const { return rhs_map_.linear; }

 private:
  void BuildRhsMap(const Level& level, const std::vector<Index>& source, Index num_coarse,
                   const Context& context);

  // The right-hand side as a linear map of the coarse rotations: per vertex the
  // entries [offset[j], offset[j+1]) of (cluster, w); cluster num_coarse stands for the identity
  // (sites without a source).
  struct RhsMap {
    std::vector<Index> source;  ///< what it was built for
    Index num_coarse = -1;
    bool linear = false;  ///< the probed map reproduced AssembleRhs()
    std::vector<Index> offset, cluster;
    std::vector<Eigen::Vector3d> weight;
    Rotations coarse;  ///< per call: the coarse rotations and the identity
  };
  RhsMap rhs_map_;
  // Per-call buffers.
  Positions rhs_;
  Rotations rotations_;
  Eigen::MatrixXd reduced_rhs_, reduced_x_;
};

}  // namespace harap
