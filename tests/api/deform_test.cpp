// SPDX-License-Identifier: MIT
// The `harap` command and the deform runner end to end, on built-in meshes (no data needed).
#include "api/deform.h"

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "api/builtins.h"
#include "api/presets.h"
#include "io/mesh_io.h"
#include "tests/support/run_harap.h"
#include "tests/support/shared_data.h"
#include "tests/support/test_files.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using harap::testing::CommandResult;
using harap::testing::RunHarap;
namespace fs = std::filesystem;

namespace {

const std::string kScenario =
    testing::CylinderScenario(testing::CylinderMesh(3000), 0.03, 60.0, "[0.0, 0.2, -0.1]");

fs::path TempDir() {
  fs::path dir = fs::temp_directory_path() / fmt::format("harap-test-{}", getpid());
  fs::create_directories(dir);
  return dir;
}

}  // namespace

TEST_CASE("RunDeform: report has every documented key, trace times increase", "[experiments]") {
  const Registries registries = MakeBuiltinRegistries();
  const Scenario scenario = ParseScenario(kScenario, "inline", ".");
  for (const char* optimizer : {"classic", "hierarchical"}) {
    DYNAMIC_SECTION(optimizer) {
      ConfigNode config;
      config.Set("optimizer.type", fmt::format("\"{}\"", optimizer));
      const DeformOutcome outcome = RunDeform(registries, scenario, config, {});
      const auto report = nlohmann::json::parse(DeformReportJson(scenario, outcome, true));
      for (const char* key : {"optimizer", "energy_type", "solver", "energy", "iterations",
                              "converged", "peak_memory_bytes", "levels", "trace"}) {
        CHECK(report.contains(key));
      }
      CHECK(report["mesh"]["vertices"] == scenario.mesh.num_vertices());
      CHECK(report["mesh"]["faces"] == scenario.mesh.num_elements());
      for (const char* key : {"hierarchy", "precompute", "constrain", "solve", "total"}) {
        CHECK(report["timings"].contains(key));
      }
      CHECK(report["optimizer"] == optimizer);
      CHECK(report["energy_type"] == "spokes_and_rims");
      const auto& trace = report["trace"];
      REQUIRE(trace.size() == static_cast<size_t>(outcome.result.total_iterations));
      for (size_t i = 1; i < trace.size(); ++i) CHECK(trace[i]["t"] >= trace[i - 1]["t"]);
      CHECK(trace.back()["level"] == 0);
      CHECK(outcome.result.converged);
    }
  }
}

TEST_CASE("RunDeform: min_time repeats the run and keeps the median repetition", "[experiments]") {
  // The hierarchical optimizer: its repetitions each build the hierarchy and set the levels up
  // on the background thread again.
  ConfigNode config;
  config.Set("optimizer.type", "\"hierarchical\"");
  const Scenario scenario = ParseScenario(kScenario, "inline", ".");
  const Registries registries = MakeBuiltinRegistries();
  const DeformOutcome once = RunDeform(registries, scenario, config, {});
  CHECK(once.repetitions.count == 1);
  CHECK(once.repetitions.fastest_total == once.result.timings.total);
  CHECK(once.repetitions.slowest_total == once.result.timings.total);

  DeformOptions options;
  options.min_time = 3600.0;  // never reached: the cap counts
  options.max_repetitions = 4;
  int iterations_seen = 0;
  options.progress = [&](const IterationSummary&) {
    ++iterations_seen;
    return CallbackAction::kContinue;
  };
  const DeformOutcome repeated = RunDeform(registries, scenario, config, options);
  CHECK(repeated.repetitions.count == 4);
  CHECK(iterations_seen == 4 * once.result.total_iterations);
  // The same problem solved four times: the same result; only the timings differ.
  CHECK(repeated.result.energy == once.result.energy);
  CHECK(repeated.result.positions == once.result.positions);
  CHECK(repeated.trace.size() == static_cast<size_t>(once.result.total_iterations));
  CHECK(repeated.repetitions.fastest_total <= repeated.result.timings.total);
  CHECK(repeated.result.timings.total <= repeated.repetitions.slowest_total);
  CHECK(repeated.trace.back().t <= repeated.result.timings.total);
  const auto report = nlohmann::json::parse(DeformReportJson(scenario, repeated, false));
  CHECK(report["repetitions"]["count"] == 4);

  // A run stopped by its callback is not repeated; a repetition stopped after complete ones is
  // dropped.
  options.progress = [](const IterationSummary&) { return CallbackAction::kStop; };
  CHECK(RunDeform(registries, scenario, config, options).repetitions.count == 1);
  int seen = 0;
  options.progress = [&](const IterationSummary&) {
    return ++seen > 2 * once.result.total_iterations ? CallbackAction::kStop
                                                     : CallbackAction::kContinue;
  };
  const DeformOutcome stopped = RunDeform(registries, scenario, config, options);
  CHECK(stopped.repetitions.count == 2);
  CHECK_FALSE(stopped.result.stopped_by_callback);
  CHECK(stopped.result.energy == once.result.energy);
}

TEST_CASE(
    "RunDeform: tetrahedral and planar meshes default to the elements energy and report "
    "energy_wrapd",
    "[experiments]") {
  const Registries registries = MakeBuiltinRegistries();
  for (bool planar : {false, true}) {
    DYNAMIC_SECTION((planar ? "planar" : "tetrahedra")) {
      Scenario scenario;
      scenario.mesh_source = "generated";
      scenario.mesh = planar ? testing::PlanarGrid(20, 8) : testing::TetBox(12, 4, 4, 5);
      ScenarioHandle fixed{"fixed", {}, {}, {}, {}}, moved{"moved", {}, {}, {}, {}};
      for (Index v = 0; v < scenario.mesh.num_vertices(); ++v) {
        const double x = scenario.mesh.vertices(v, 0);
        if (x == 0.0) fixed.vertices.push_back(v);
        if (x == 1.0) moved.vertices.push_back(v);
      }
      fixed.targets = scenario.mesh.vertices(fixed.vertices, Eigen::all);
      moved.targets = scenario.mesh.vertices(moved.vertices, Eigen::all);
      moved.targets.col(1).array() += 0.3;
      scenario.handles = {fixed, moved};
      for (const char* optimizer : {"classic", "hierarchical"}) {
        ConfigNode config;
        config.Set("optimizer.type", fmt::format("\"{}\"", optimizer));
        config.Set("hierarchy.min_vertices", "30");
        const DeformOutcome outcome = RunDeform(registries, scenario, config, {});
        const auto report = nlohmann::json::parse(DeformReportJson(scenario, outcome, true));
        CHECK(report["energy_type"] == "elements");
        CHECK(report["mesh"]["element_kind"] == (planar ? "triangle" : "tetrahedron"));
        REQUIRE(report.contains("energy_wrapd"));
        CHECK(report["energy_wrapd"].get<double>() ==
              Approx(0.5 * report["energy"].get<double>()).epsilon(1e-9));
        CHECK(outcome.result.converged);
      }
    }
  }
}

TEST_CASE("harap deform: writes an exact PLY and a report, errors exit non-zero", "[experiments]") {
  const fs::path dir = TempDir();
  const fs::path scenario = dir / "scenario.toml";
  std::ofstream(scenario) << kScenario;
  const fs::path ply = dir / "out.ply", json = dir / "report.json";
  const CommandResult ok = RunHarap(fmt::format("deform {} --out {} --report {} --trace -q",
                                                scenario.string(), ply.string(), json.string()));
  INFO(ok.output);
  REQUIRE(ok.status == 0);
  const Mesh result = ReadMesh(ply);
  std::ifstream report_file(json);
  const auto report = nlohmann::json::parse(report_file);
  CHECK(result.num_vertices() == report["mesh"]["vertices"].get<int>());
  CHECK(report["trace"].size() == report["iterations"].get<size_t>());

  CHECK(RunHarap("deform /nonexistent.toml").status != 0);
  const CommandResult unknown = RunHarap(fmt::format("deform {} --energy nope", scenario.string()));
  CHECK(unknown.status == 1);
  CHECK_THAT(unknown.output, Catch::Contains("spokes_and_rims") && Catch::Contains("nope"));
  const CommandResult bad_set =
      RunHarap(fmt::format("deform {} --set energy.lambda=0.5", scenario.string()));
  CHECK(bad_set.status == 1);
  CHECK_THAT(bad_set.output, Catch::Contains("lambda"));
  const CommandResult bad_table =
      RunHarap(fmt::format("deform {} --set solvr.mode=x", scenario.string()));
  CHECK(bad_table.status == 1);
  CHECK_THAT(bad_table.output, Catch::Contains("solvr") && Catch::Contains("solver"));
  fs::remove_all(dir);
}

TEST_CASE("harap list names every registered piece", "[experiments]") {
  const CommandResult list = RunHarap("list");
  REQUIRE(list.status == 0);
  const Registries registries = MakeBuiltinRegistries();
  for (const auto& name : registries.energies.Names())
    CHECK_THAT(list.output, Catch::Contains(name));
  for (const auto& name : registries.linear_solvers.Names()) {
    CHECK_THAT(list.output, Catch::Contains(name));
  }
  for (const auto& name : registries.optimizers.Names())
    CHECK_THAT(list.output, Catch::Contains(name));
  CHECK_THAT(list.output, Catch::Contains("optimizer.tolerance"));
  CHECK_THAT(list.output, Catch::Contains("registration.max_distance = 0.1"));
  // Presets with what they set, and when.
  const CommandResult presets = RunHarap("list presets");
  REQUIRE(presets.status == 0);
  for (const Preset& preset : Presets()) CHECK_THAT(presets.output, Catch::Contains(preset.name));
  CHECK_THAT(presets.output,
             Catch::Contains("optimizer.anderson = 5  (hierarchical optimizer, local_global"));
}

TEST_CASE("every shared surface scenario loads and converges (small ones)", "[experiments]") {
  HARAP_REQUIRE_SHARED(cactus, "scenarios/cactus-small.toml");
  const Registries registries = MakeBuiltinRegistries();
  for (const char* name : {"cactus-small.toml", "bunny-ears.toml", "cow-stretch.toml"}) {
    const Scenario scenario = LoadScenario(cactus.parent_path() / name);
    for (const char* optimizer : {"classic", "hierarchical"}) {
      DYNAMIC_SECTION(name << " " << optimizer) {
        ConfigNode config;
        config.Set("optimizer.type", fmt::format("\"{}\"", optimizer));
        const DeformOutcome outcome = RunDeform(registries, scenario, config, {});
        CHECK(outcome.result.converged);
        CHECK(std::isfinite(outcome.result.energy));
        CHECK(outcome.result.positions.allFinite());
      }
    }
  }
}

TEST_CASE("RunDeform: the report shows each level's weights and warns about negative ones",
          "[experiments]") {
  const Registries registries = MakeBuiltinRegistries();
  const Scenario scenario = ParseScenario(kScenario, "inline", ".");
  auto run = [&](const std::string& weights, const std::string& coarse_weights) {
    ConfigNode config;
    config.Set("optimizer.type", "\"hierarchical\"");
    config.Set("energy.type", "\"spokes\"");
    if (!weights.empty()) config.Set("energy.weights", fmt::format("\"{}\"", weights));
    if (!coarse_weights.empty()) {
      config.Set("energy.coarse_weights", fmt::format("\"{}\"", coarse_weights));
    }
    const DeformOutcome outcome = RunDeform(registries, scenario, config, {});
    return std::make_pair(outcome,
                          nlohmann::json::parse(DeformReportJson(scenario, outcome, false)));
  };
  auto weight_warnings = [](const DeformOutcome& outcome) {
    int count = 0;
    for (const auto& warning : outcome.warnings) {
      count += warning.find("negative edge weights") != std::string::npos;
    }
    return count;
  };
  SECTION("defaults: intrinsic Delaunay on every level, nothing negative, no warning") {
    const auto [outcome, report] = run("", "");
    REQUIRE(report["levels"].size() >= 2);
    for (const auto& level : report["levels"]) {
      CHECK(level["weights"] == "intrinsic_delaunay");
      CHECK(level["negative_weights"] == 0);
      CHECK(level["energy_can_be_negative"] == false);
    }
    CHECK(weight_warnings(outcome) == 0);
    CHECK(outcome.result.energy >= 0.0);
  }
  SECTION("raw cotangents on every level: the coarse clusters have negative weights, warned") {
    const auto [outcome, report] = run("cotan", "same");
    Index negative = 0;
    for (const auto& level : report["levels"]) {
      CHECK(level["weights"] == "cotan");
      negative += level["negative_weights"].get<Index>();
      CHECK(level["energy_can_be_negative"] == (level["negative_weights"].get<Index>() > 0));
    }
    REQUIRE(negative > 0);
    CHECK(weight_warnings(outcome) == 1);
  }
}
