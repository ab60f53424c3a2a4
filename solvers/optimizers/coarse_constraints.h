// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <vector>

#include "framework/constrained_system.h"
#include "framework/context.h"
#include "framework/energy.h"
#include "framework/hierarchy.h"
#include "framework/level_solver.h"
#include "framework/optimizer.h"

namespace harap {

/// Maps the finest-level constraints to level `level` through the hierarchy's vertex maps (the
/// paper's Section 4): the constrained coarse vertices with the mean target and the mean rest
/// offset of their finest-level members, so that target_c(R_c) = mean_target − R_c · mean_offset.
/// Soft constraints map to soft ones: a coarse vertex without hard members takes the summed
/// weight of its soft members and their weighted mean target.
/// The constrained vertices are listed in the order of `listing` (all vertices of the level),
/// ascending if it is null.
LevelConstraints MapConstraints(const MeshHierarchy& hierarchy, int level,
                                const Constraints& finest,
                                const std::vector<Index>* listing = nullptr);

/// Fills constraints.incident_elements from `mesh` (the elements around each constrained vertex,
/// in increasing order): what a per-element energy's coarse targets need (Eq. 11).
void FindIncidentElements(const Mesh& mesh, LevelConstraints& constraints);

/// Writes the target of every constrained vertex into `positions`: exact targets as they are;
/// coarse ones as target_c(R_c), R_c the vertex's rotation from `rotations` (for per-element
/// energies the projected mean of its incident elements' rotations, Eq. 11), or the identity if
/// `rotations` is null.
void PlaceConstrainedVertices(const LevelConstraints& constraints, RotationSite site,
                              const Rotations* rotations, Positions& positions);

/// Replaces the mean targets of `constraints` by `mean_target`, which must have one row per
/// constrained vertex (InternalError otherwise): a level solver's MoveTargets().
void MoveMeanTargets(LevelConstraints& constraints, const Positions& mean_target);

/// The factorization of a level solver's Constrain() for a new eliminated system (local_global
/// and the ADMM level solvers alike): `solver` becomes a new linear solver from `factory` for
/// level `level`, which factors system.system_matrix() (unless there are no unknowns); `rhs` and
/// `x` are sized num_unknowns()×3 for the solves, and the context's system callback sees the
/// matrix. Returns the summary of a full factorization with the seconds since `clock` started
/// (read before the callback).
ConstrainSummary FactorGlobalStep(const GlobalStepSystem& system, int level,
                                  const ComponentFactory& factory, const Context& context,
                                  const Stopwatch& clock, std::unique_ptr<LinearSolver>& solver,
                                  Eigen::MatrixXd& rhs, Eigen::MatrixXd& x);

/// The stiffness of coarse level `level` > 0 (framework/stiffness.h) from the input mesh's
/// per-element factors: each coarse vertex takes the mean of its input members' vertex factors
/// (VertexStiffness) and each element the mean of its vertices', so a stiff region stays stiff
/// where the clustering puts it (docs/energies.md, "Stiffness"). `input` and `input_stiffness`
/// are in the input's numbering, `input_to_level0` maps its vertices to the hierarchy's level 0
/// (the members are summed in the input's order). Empty in, empty out.
std::vector<double> LevelStiffness(const MeshHierarchy& hierarchy, int level, const Mesh& input,
                                   const std::vector<double>& input_stiffness,
                                   const std::vector<Index>& input_to_level0);

}  // namespace harap
