// SPDX-License-Identifier: MIT
#pragma once

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

  /// The registry name each table resolves to.
  std::string energy_name() const;
  std::string solver_name() const;
  std::string hierarchy_name() const;
  std::string upsampler_name() const;

 private:
  const Registries& registries_;
  ConfigNode root_;
  DefaultComponents defaults_;
};

/// Creates the optimizer named by the `[optimizer]` table.
std::unique_ptr<Optimizer> MakeOptimizer(const Registries& registries, const ConfigNode& root,
                                         const DefaultComponents& defaults = {});

/// Rejects unknown top-level tables/keys of a run config, listing the valid ones.
void ValidateRunConfig(const ConfigNode& root);

}  // namespace harap
