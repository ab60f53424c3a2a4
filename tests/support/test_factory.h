// SPDX-License-Identifier: MIT
#pragma once

#include <string>

#include "experiments/builtins.h"
#include "experiments/component_factory.h"

namespace harap::testing {

/// Registries plus a parsed run config, kept alive together for a ComponentFactory.
struct TestSetup {
  explicit TestSetup(const std::string& toml = "")
      : registries(MakeBuiltinRegistries()),
        config(ConfigNode::Parse(toml, "test config")),
        factory(registries, config) {}
  std::unique_ptr<Optimizer> MakeOptimizer() const { return harap::MakeOptimizer(registries, config); }

  Registries registries;
  ConfigNode config;
  RegistryComponentFactory factory;
};

}  // namespace harap::testing
