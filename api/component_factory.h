// SPDX-License-Identifier: MIT
#pragma once

#include <atomic>
#include <memory>
#include <string>

#include "framework/config.h"
#include "framework/optimizer.h"
#include "framework/registries.h"

namespace harap {

/// Default registry names when a config table has no `type`.
struct DefaultComponents {
  std::string optimizer = "classic";
  std::string energy = "spokes_and_rims";
  std::string solver = "cholmod";
  std::string hierarchy = "octree";
  std::string upsampler = "rotations";
};

/// The ComponentFactory of a run: creates each piece by the `type` of its table in the run's
/// config (`[energy]`, `[solver]`, `[hierarchy]`, `[upsampler]`) with that table's options.
///
/// Per-level solver choice: an optional `[solver.small_systems]` table names a second solver
/// (its `type`, default the default solver, and its options) for every reduced system with at
/// most `max_unknowns` unknowns; larger systems use `[solver]`. This is the paper's suggestion
/// (Section 5.2) to factor the levels that fit and iterate on the ones that do not:
///
///   [solver]
///   type = "cg"               # levels with more than 50000 unknowns
///   max_iterations = 30
///   [solver.small_systems]
///   max_unknowns = 50000      # levels (classic: the mesh) up to this size
///   type = "cholmod"
///
/// A `[solver.level_<l>]` table (l = 0 is the input mesh, the finest level) names the solver of
/// level l itself, before the size rule. With type = "adaptive" (AdaptiveSolver) the choice
/// between factoring and iterating is made per level from CHOLMOD's analysis; the factory
/// records what each level used (solver_used()).
class RegistryComponentFactory final : public ComponentFactory {
 public:
  /// Validates the energy and solver tables (and hierarchy/upsampler tables if present) at once,
  /// so configuration errors surface before any work.
  RegistryComponentFactory(const Registries& registries, const ConfigNode& root,
                           DefaultComponents defaults = {});

  std::unique_ptr<Energy> MakeEnergy() const override;
  std::unique_ptr<LinearSolver> MakeLinearSolver(int level, Index num_unknowns) const override;
  std::unique_ptr<Hierarchy> MakeHierarchy() const override;
  std::unique_ptr<Upsampler> MakeUpsampler() const override;

  /// The registry name each table resolves to; solver_name() is `[solver]`'s, whatever the
  /// small-system rule says.
  std::string energy_name() const;
  std::string solver_name() const;
  /// The solver a reduced system of `num_unknowns` unknowns gets (on a level without a
  /// `[solver.level_<l>]` table).
  std::string solver_name_for(Index num_unknowns) const;
  /// The solver level `level` gets, and what it used: for "adaptive", "adaptive:cholmod" or
  /// "adaptive:cg" once the level factored (else the table's type).
  std::string solver_name_for(int level, Index num_unknowns) const;
  std::string solver_used(int level, Index num_unknowns) const;
  /// Whether level `level`'s solver was direct: what an adaptive solver chose, else the kind of
  /// the table's solver.
  bool solver_direct(int level, Index num_unknowns) const;
  std::string hierarchy_name() const;
  std::string upsampler_name() const;
  /// Whether an optimizer asked for a hierarchy / an up-sampler (the checks of the constructor
  /// do not count), so a summary names exactly the pieces a run used.
  bool made_hierarchy() const { return made_hierarchy_; }
  bool made_upsampler() const { return made_upsampler_; }

 private:
  /// The table whose solver a system of `num_unknowns` unknowns gets on level `level` (-1: any
  /// level without its own table).
  ConfigNode SolverTableFor(int level, Index num_unknowns) const;

  const Registries& registries_;
  ConfigNode root_;
  DefaultComponents defaults_;
  /// What the adaptive solvers chose, by level (shared with the solvers' callbacks, which may
  /// outlive the factory).
  struct Choices;
  std::shared_ptr<Choices> choices_;
  mutable std::atomic<bool> made_hierarchy_{false};
  mutable std::atomic<bool> made_upsampler_{false};
};

/// The defaults of a run on `mesh`: eigen_ldlt when CHOLMOD is not built; the per-element
/// energy for tetrahedral and planar meshes (FORMAT.md: "Its energy is the per-tetrahedron ARAP
/// energy"), which the surface energies would refuse.
DefaultComponents DefaultComponentsFor(const Registries& registries, const Mesh& mesh);

/// A run config resolved once for one mesh: validated (ValidateRunConfig), the defaults that
/// suit the mesh, the optimizer created and named, and the factory of the other pieces (whose
/// constructor validates their tables). Every error in the config surfaces here, before work.
struct ResolvedRunConfig {
  ResolvedRunConfig(const Registries& registries, const ConfigNode& config, const Mesh& mesh);

  DefaultComponents defaults;
  std::string optimizer_name;  ///< `[optimizer] type`, or the default.
  std::unique_ptr<Optimizer> optimizer;
  RegistryComponentFactory factory;
};

/// Creates the optimizer named by the `[optimizer]` table.
std::unique_ptr<Optimizer> MakeOptimizer(const Registries& registries, const ConfigNode& root,
                                         const DefaultComponents& defaults = {});

/// The options of the `[solver.small_systems]` table (drives `harap list`).
std::vector<OptionInfo> DescribeSmallSystemsOptions();

/// Rejects unknown top-level tables/keys of a run config, listing the valid ones.
void ValidateRunConfig(const ConfigNode& root);

}  // namespace harap
