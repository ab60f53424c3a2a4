// SPDX-License-Identifier: MIT
#pragma once

#include <atomic>
#include <initializer_list>
#include <map>
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

/// The ComponentFactory of a run: each piece is made by the `type` of its table in the run's
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
///
/// Every table is parsed and validated once, by the constructor, into recipes (Recipe): option
/// errors surface there, before any work, and the Make* calls read no configuration, so they may
/// run on several threads at once (the ComponentFactory contract). A `[hierarchy]` or
/// `[upsampler]` table the config does not have resolves to its default; if the registries lack
/// that default, the error waits until a run asks for the piece.
class RegistryComponentFactory final : public ComponentFactory {
 public:
  RegistryComponentFactory(const Registries& registries, const ConfigNode& root,
                           DefaultComponents defaults = {});

  std::unique_ptr<Energy> MakeEnergy() const override;
  std::unique_ptr<LinearSolver> MakeLinearSolver(int level, Index num_unknowns) const override;
  std::unique_ptr<Hierarchy> MakeHierarchy() const override;
  std::unique_ptr<Upsampler> MakeUpsampler() const override;

  /// The registry name each table resolves to; solver_name() is `[solver]`'s, whatever the
  /// small-system rule says.
  const std::string& energy_name() const { return energy_.name(); }
  const std::string& solver_name() const { return solver_.recipe.name(); }
  /// The solver a reduced system of `num_unknowns` unknowns gets (on a level without a
  /// `[solver.level_<l>]` table).
  const std::string& solver_name_for(Index num_unknowns) const;
  /// The solver level `level` gets, and what it used: for "adaptive", "adaptive:cholmod" or
  /// "adaptive:cg" once the level factored (else the table's type).
  const std::string& solver_name_for(int level, Index num_unknowns) const;
  std::string solver_used(int level, Index num_unknowns) const;
  /// Whether level `level`'s solver was direct: what an adaptive solver chose, else the kind of
  /// the table's solver.
  bool solver_direct(int level, Index num_unknowns) const;
  const std::string& hierarchy_name() const { return hierarchy_.name(); }
  const std::string& upsampler_name() const { return upsampler_.name(); }
  /// Whether an optimizer asked for a hierarchy / an up-sampler, so a summary names exactly the
  /// pieces a run used.
  bool made_hierarchy() const { return made_hierarchy_; }
  bool made_upsampler() const { return made_upsampler_; }

 private:
  /// One resolved solver table and whether its solver is direct (before any factorization).
  struct SolverTable {
    Recipe<LinearSolver> recipe;
    bool direct = false;
  };
  SolverTable ResolveSolverTable(const Registries& registries, OptionReader table) const;
  /// The table whose solver a system of `num_unknowns` unknowns gets on level `level` (-1: any
  /// level without its own table).
  const SolverTable& SolverTableFor(int level, Index num_unknowns) const;

  DefaultComponents defaults_;
  Recipe<Energy> energy_;
  SolverTable solver_;  ///< `[solver]`
  /// `[solver.small_systems]`: its size limit (0: no such table) and solver.
  Index small_systems_limit_ = 0;
  SolverTable small_systems_;
  std::map<int, SolverTable> level_tables_;  ///< `[solver.level_<l>]` by l
  Recipe<Hierarchy> hierarchy_;
  Recipe<Upsampler> upsampler_;
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
/// constructor resolves their tables), and the pieces checked against each other
/// (Optimizer::CheckComponents). Every error in the config surfaces here, before work.
struct ResolvedRunConfig {
  ResolvedRunConfig(const Registries& registries, const ConfigNode& config, const Mesh& mesh);

  DefaultComponents defaults;
  Recipe<Optimizer> optimizer_recipe;  ///< `[optimizer]` resolved
  std::string optimizer_name;          ///< `[optimizer] type`, or the default.
  std::unique_ptr<Optimizer> optimizer;
  RegistryComponentFactory factory;
};

/// Creates the optimizer named by the `[optimizer]` table.
std::unique_ptr<Optimizer> MakeOptimizer(const Registries& registries, const ConfigNode& root,
                                         const DefaultComponents& defaults = {});

/// The options of the `[solver.small_systems]` table (drives `harap list`).
std::vector<OptionInfo> DescribeSmallSystemsOptions();

/// Rejects unknown top-level tables/keys of a run config, listing the valid ones: the pieces'
/// tables (optimizer, energy, solver, hierarchy, upsampler) and the command's own, `mesh` for
/// `harap deform` (`registration` for `harap register`).
void ValidateRunConfig(const ConfigNode& root,
                       std::initializer_list<const char*> command_tables = {"mesh"});

}  // namespace harap
