// SPDX-License-Identifier: MIT
// Energy fingerprints: a fixed list of runs whose final energies are recorded in
// tests/data/energy_fingerprints.txt. A refactoring of the optimizers, level solvers, energies or
// linear solvers must leave them unchanged, bit for bit.
//
// Bit-identical holds on the machine that recorded the file (one thread, the same BLAS kernel):
// run with HARAP_EXACT_ENERGIES=1 to require it. Elsewhere a different BLAS kernel (CHOLMOD's
// supernodal factorization calls dgemm/dsyrk) rounds differently, so the default check is a
// relative 1e-9 — still far below any change a real algorithmic difference makes (those move
// the energy in the 4th–6th digit after a capped number of iterations).
// Re-record after an intended change: HARAP_RECORD_FINGERPRINTS=<file> writes the current values.
// To check a change bit for bit on a machine other than the recording one, record the values of
// the build before the change there and compare against them:
// HARAP_EXACT_ENERGIES=1 HARAP_FINGERPRINTS=<that file>.
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "api/builtins.h"
#include "api/deform.h"
#include "io/scenario.h"
#include "tests/support/shared_data.h"

using namespace harap;

namespace {

struct FingerprintRun {
  std::string name;
  std::string scenario;                                      ///< Under ../shared/scenarios.
  std::vector<std::pair<std::string, std::string>> options;  ///< key, TOML value.
};

// Capped iteration counts keep the list fast (about 10 s in all) while every level, the Newton
// and Anderson paths and both ADMM variants do real work.
std::vector<FingerprintRun> Runs() {
  const std::vector<std::pair<std::string, std::string>> kCap = {
      {"optimizer.max_iterations", "25"}};
  auto with = [&](std::vector<std::pair<std::string, std::string>> extra) {
    auto all = kCap;
    all.insert(all.end(), extra.begin(), extra.end());
    return all;
  };
  std::vector<FingerprintRun> runs;
  for (const std::string scene : {"cow-stretch", "armadillo-bend-43k"}) {
    const std::string file = scene + ".toml";
    runs.push_back({scene + "/classic", file, with({{"optimizer.type", "\"classic\""}})});
    runs.push_back({scene + "/hierarchical", file, with({{"optimizer.type", "\"hierarchical\""}})});
    runs.push_back({scene + "/hierarchical-newton", file,
                    with({{"optimizer.type", "\"hierarchical\""}, {"optimizer.newton", "20"}})});
    runs.push_back({scene + "/classic-anderson", file,
                    with({{"optimizer.type", "\"classic\""}, {"optimizer.anderson", "5"}})});
  }
  runs.push_back(
      {"cow-stretch/hierarchical-smooth_arap", "cow-stretch.toml",
       with({{"optimizer.type", "\"hierarchical\""}, {"energy.type", "\"smooth_arap\""}})});
  const std::string tets = "tets/shear.toml";
  for (const std::string admm : {"wrapd", "admm_pd"}) {
    runs.push_back({"shear/" + admm, tets, with({{"optimizer.type", "\"" + admm + "\""}})});
    runs.push_back(
        {"shear/hierarchical-" + admm, tets,
         with({{"optimizer.type", "\"hierarchical\""}, {"optimizer.inner", "\"" + admm + "\""}})});
  }
  return runs;
}

std::map<std::string, double> ReadFingerprints(const std::filesystem::path& file) {
  std::map<std::string, double> values;
  std::ifstream in(file);
  std::string name, value;
  while (in >> name >> value) values[name] = std::stod(value);
  return values;
}

}  // namespace

TEST_CASE("Energy fingerprints: the fixed list of runs ends at the recorded energies",
          "[experiments][fingerprint]") {
  HARAP_REQUIRE_SHARED(scenarios, "scenarios");
  const char* recorded_file = std::getenv("HARAP_FINGERPRINTS");
  const auto recorded =
      ReadFingerprints(recorded_file ? std::filesystem::path(recorded_file)
                                     : testing::SourceDir() / "tests/data/energy_fingerprints.txt");
  const char* record_to = std::getenv("HARAP_RECORD_FINGERPRINTS");
  const bool exact = std::getenv("HARAP_EXACT_ENERGIES") != nullptr;
  const Registries registries = MakeBuiltinRegistries();
  std::string record;
  for (const FingerprintRun& run : Runs()) {
    const Scenario scenario = LoadScenario(scenarios / run.scenario);
    ConfigNode config;
    for (const auto& [key, value] : run.options) config.Set(key, value);
    DeformOptions options;
    options.threads = 1;  // one thread: the same summation order on every run
    const double energy = RunDeform(registries, scenario, config, options).result.energy;
    record += fmt::format("{} {:.17g}\n", run.name, energy);
    if (record_to) continue;
    INFO(run.name << ": energy " << fmt::format("{:.17g}", energy));
    REQUIRE(recorded.count(run.name) == 1);
    const double expected = recorded.at(run.name);
    if (exact) {
      CHECK(energy == expected);
    } else {
      CHECK(std::abs(energy - expected) <= 1e-9 * std::abs(expected));
    }
  }
  if (record_to) std::ofstream(record_to) << record;
}
