// SPDX-License-Identifier: MIT
#pragma once

// harap as a library: the entry points, besides RunDeform (deform.h), that programs embedding
// harap call — the Python module (python/) and C++ consumers of the installed package. Each is a
// thin composition of the registries and framework/ pieces, so `harap list`, `harap hierarchy`
// and these calls read and validate options the same way.

#include <string>
#include <vector>

#include "framework/config.h"
#include "framework/hierarchy.h"
#include "framework/mesh.h"
#include "framework/registries.h"

namespace harap {

/// One registered piece: its kind ("optimizer", "energy", "solver", "hierarchy", "upsampler"),
/// name, description and options (key without the table prefix, default as a TOML literal, help).
struct ComponentDescription {
  std::string kind;
  std::string name;
  std::string description;
  std::vector<OptionInfo> options;  ///< Without `type`.
};

/// Everything `harap list` prints, structured.
struct ComponentCatalog {
  std::vector<ComponentDescription> components;   ///< Registry order: optimizers, energies, ...
  std::vector<OptionInfo> small_systems_options;  ///< The `[solver.small_systems]` table.
  std::vector<OptionInfo> mesh_options;           ///< The `[mesh]` table (MeshRepairOptions).
  /// The `[registration]` table of `harap register` (RegistrationOptions).
  std::vector<OptionInfo> registration_options;
  std::vector<std::string> builtin_meshes;
};

ComponentCatalog DescribeComponents(const Registries& registries);

/// Builds the hierarchy named by `config`'s `[hierarchy]` table (`type`, default octree, and its
/// options; other tables are rejected) for `mesh`, as `harap hierarchy` does. `threads`: 0 = all.
MeshHierarchy BuildHierarchy(const Registries& registries, const Mesh& mesh,
                             const ConfigNode& config, int threads);

/// The value and gradient of an energy at deformed positions `u` of `rest`.
struct EnergyEvaluation {
  double value = 0.0;  ///< min over rotations of E(u, R) (the local step's fit).
  /// ∂E/∂u = 2 (A u − B(R)) at the fitted rotations (#V×3; the rotations' own variation drops
  /// out because they minimize E, see framework/energy.h).
  Positions gradient;
  /// The fitted rotations, one per rotation site (vertex or element, see `per_element`).
  Rotations rotations;
  bool per_element = false;
};

/// Evaluates the energy named by `config`'s `[energy]` table (`type` required, and its options;
/// other tables are rejected) on the rest mesh `rest` at positions `u` (#V×3, finite; checked).
EnergyEvaluation EvaluateEnergy(const Registries& registries, const Mesh& rest, const Positions& u,
                                const ConfigNode& config, int threads);

/// For a program that owns its process (the `harap` command), called at its start, before
/// anything uses BLAS: joins the idle worker threads of the BLAS behind CHOLMOD, which otherwise
/// spin beside the run's threads (CholmodSolver::StopIdleNativeThreads; docs/solvers.md, "Why
/// native_threads = 1"). Must not run while any thread is inside BLAS (a factorization, or a host
/// program using the same BLAS).
void StopIdleNativeThreads();

}  // namespace harap
