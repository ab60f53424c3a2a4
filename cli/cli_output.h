// SPDX-License-Identifier: MIT
// What `harap` prints: the `harap deform` summary, `harap list [KIND]` and `--version`.
#pragma once

#include <string>

#include "api/deform.h"
#include "io/scenario.h"

namespace harap {

/// The summary `harap deform` prints after a run (stdout): the pieces in use, iterations (a
/// hierarchical run: finest level / all levels), energy, timings, per level the linear solves
/// (direct solvers say so instead of showing iterations and a residual they did not measure),
/// the mesh checks (and, after a repair, those of the repaired mesh), notes and warnings.
void PrintDeformSummary(const Scenario& scenario, const DeformOutcome& outcome);

/// The summary's timings: the phases and the total in seconds, with a remark when the phases
/// add up to more than the total (a hierarchical run sets levels up while others solve).
std::string TimingsLine(const PhaseTimings& timings);

/// `harap list [KIND]`: every registered piece with its options, or only those of one KIND
/// (optimizers, energies, solvers, hierarchies, upsamplers, mesh, builtins; singular names
/// too). An unknown KIND throws ConfigError listing the valid ones.
int ListPieces(const std::string& kind);

/// `harap --version`: "harap VERSION (git DESCRIBE)" from CMake's project() version and
/// `git describe` at configure time (omitted when the source was no git checkout).
std::string VersionString();

}  // namespace harap
