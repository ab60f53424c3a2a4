// SPDX-License-Identifier: MIT
#pragma once

#include <catch2/catch.hpp>
#include <map>
#include <string>
#include <vector>

#include "api/builtins.h"
#include "api/component_factory.h"

namespace harap::testing {

/// Registries plus a parsed run config, kept alive together for a ComponentFactory.
struct TestSetup {
  explicit TestSetup(const std::string& toml = "")
      : registries(MakeBuiltinRegistries()),
        config(ConfigNode::Parse(toml, "test config")),
        factory(registries, config) {}
  std::unique_ptr<Optimizer> MakeOptimizer() const {
    return harap::MakeOptimizer(registries, config);
  }

  Registries registries;
  ConfigNode config;
  RegistryComponentFactory factory;
};

/// The per-element (`elements`) energy of positions `u` with rotations fitted to them: what an
/// optimizer should report for `u`.
inline double FittedElementEnergy(const Mesh& mesh, const Positions& u) {
  const std::unique_ptr<Energy> energy =
      MakeBuiltinRegistries().energies.Create("elements", ConfigNode());
  energy->Precompute(mesh, Context());
  Rotations rotations(energy->num_rotations(), Rotation::Identity());
  return energy->FitRotations(u, rotations, Context());
}

/// Energies reported through the iteration callback, per hierarchy level.
using EnergyTrace = std::map<int, std::vector<double>>;

/// Runs the setup's optimizer on `problem`, recording every iteration's energy in `energies`.
inline OptimizeResult OptimizeWithTrace(const TestSetup& setup, const DeformationProblem& problem,
                                        EnergyTrace& energies) {
  Context context;
  context.iteration_callback = [&](const IterationSummary& s) {
    energies[s.level].push_back(s.energy);
    return CallbackAction::kContinue;
  };
  return setup.MakeOptimizer()->Optimize(problem, setup.factory, context);
}

/// CHECKs that the energy never increases within a level (up to rounding).
inline void CheckEnergiesNeverIncrease(const EnergyTrace& energies) {
  for (const auto& [level, trace] : energies) {
    for (size_t i = 1; i < trace.size(); ++i) {
      INFO("level " << level << ", iteration " << i + 1);
      CHECK(trace[i] <= trace[i - 1] * (1.0 + 1e-12) + 1e-15);
    }
  }
}

}  // namespace harap::testing
