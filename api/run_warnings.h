// SPDX-License-Identifier: MIT
// Warnings about runs that finish but whose numbers probably do not mean what the user thinks
// (shown in the `harap deform` summary and in the report's `warnings` array).
#pragma once

#include <string>
#include <vector>

#include "framework/optimizer.h"
#include "io/mesh_repair.h"
#include "io/scenario.h"

namespace harap {

/// Whether `checks` describe a triangle soup: many components, most of them one or two elements
/// (a file that stores every triangle with its own corners, or a mesh torn into pieces).
bool LooksLikeTriangleSoup(const MeshCheckReport& checks);

/// What a run's warnings are computed from.
struct RunWarningInput {
  const Scenario* scenario = nullptr;
  const MeshCheckReport* input_checks = nullptr;   ///< Checks of the input mesh.
  const MeshCheckReport* solved_checks = nullptr;  ///< Checks of the solved (repaired) mesh.
  const OptimizeResult* result = nullptr;
  bool hierarchical = false;  ///< The optimizer built a hierarchy.
};

/// One sentence per problem, each saying what happened and what to change:
///   - a triangle soup (LooksLikeTriangleSoup on the solved mesh; suggests mesh.weld_duplicates
///     when the input has duplicate vertices);
///   - handles that share vertices (the first handle's target wins);
///   - handles that leave no vertex free (nothing was solved, "0 iterations" mean nothing);
///   - a hierarchical run whose hierarchy has a single level (it ran as classic ARAP);
///   - levels whose energy has negative edge weights that take it out of the sum-of-squares
///     form (EnergyWeights::can_be_negative), and a final energy below zero.
std::vector<std::string> RunWarnings(const RunWarningInput& input);

}  // namespace harap
