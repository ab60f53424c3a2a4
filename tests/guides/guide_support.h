// SPDX-License-Identifier: MIT
#pragma once

// What the guide tests share: reading the example regions the guides quote, and one run through
// the normal machinery (a run config, the component factory, a registered optimizer).

#include <catch2/catch.hpp>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "api/component_factory.h"
#include "framework/config.h"
#include "framework/registries.h"
#include "tests/support/shared_data.h"

namespace harap::testing {

inline std::string ReadSourceFile(const std::string& relative_path) {
  std::ifstream file(::harap::testing::SourceDir().string() + "/" + relative_path);
  REQUIRE(file.good());
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

/// The lines of `relative_path` between "// [guide:<name>]" and "// [/guide:<name>]".
inline std::string GuideRegion(const std::string& relative_path, const std::string& name) {
  const std::string text = ReadSourceFile(relative_path);
  const std::string open = "// [guide:" + name + "]\n", close = "// [/guide:" + name + "]";
  const size_t begin = text.find(open);
  REQUIRE(begin != std::string::npos);
  size_t end = text.find(close, begin);
  REQUIRE(end != std::string::npos);
  end = text.rfind('\n', end) + 1;  // the close marker's line, indentation included, is out
  return text.substr(begin + open.size(), end - begin - open.size());
}

/// CHECKs that the guide `doc` quotes the region `name` of `example` word for word, so a guide
/// whose example changed (or whose quote was edited alone) fails.
inline void CheckGuideQuotes(const std::string& doc, const std::string& example,
                             const std::string& name) {
  const std::string region = GuideRegion(example, name);
  INFO(doc << " must quote region '" << name << "' of " << example << " exactly:\n" << region);
  CHECK(ReadSourceFile(doc).find(region) != std::string::npos);
}

/// Runs the optimizer of the run config `toml` on `problem` with the pieces it names, created
/// from `registries` as `harap deform` does; records each level's energies in `energies`.
inline OptimizeResult RunConfigured(const Registries& registries, const DeformationProblem& problem,
                                    const std::string& toml,
                                    std::map<int, std::vector<double>>* energies = nullptr) {
  const ConfigNode config = ConfigNode::Parse(toml, "guide test");
  const ResolvedRunConfig run(registries, config, *problem.mesh);
  Context context;
  context.iteration_callback = [&](const IterationSummary& summary) {
    if (energies) (*energies)[summary.level].push_back(summary.energy);
    return CallbackAction::kContinue;
  };
  return run.optimizer->Optimize(problem, run.factory, context);
}

/// True if no level's energy ever increases (relative slack 1e-12 for rounding).
inline bool MonotonePerLevel(const std::map<int, std::vector<double>>& energies) {
  for (const auto& [level, trace] : energies) {
    for (size_t i = 1; i < trace.size(); ++i) {
      if (trace[i] > trace[i - 1] * (1.0 + 1e-12) + 1e-15) return false;
    }
  }
  return true;
}

}  // namespace harap::testing
