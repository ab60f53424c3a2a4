// SPDX-License-Identifier: MIT
// `harap run` / `harap report`: grid expansion, sharding, resume, failures, determinism, and two
// GNU parallel shards merged against one unsharded run. Built-in meshes of a few hundred
// vertices keep every sweep well under a second per run.
#include "runner/runner.h"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "framework/error.h"
#include "runner/experiment.h"
#include "tests/support/shared_data.h"
#include "tests/support/temp_folder.h"
#include "tests/support/test_files.h"

using namespace harap;
namespace fs = std::filesystem;
using testing::ReadText;

namespace {

struct Workspace : testing::TempFolder {
  explicit Workspace(const std::string& name) : TempFolder("runner-" + name) {
    Write("cylinder.toml", testing::kCylinderBendScenario);
    Write("plane.toml", R"(
mesh = { builtin = "plane", vertices = 500 }
[[handle]]
name = "left"
select.slab = { axis = "x", from = 0.0, to = 0.05 }
[[handle]]
name = "right"
select.slab = { axis = "x", from = 0.95, to = 1.0 }
translate = [0.0, 0.0, 0.2]
)");
    Write("broken.toml", "mesh = \"no-such-mesh.obj\"\n");
  }
  Experiment Load(const std::string& config_text) const {
    return LoadExperiment(Write("experiment.toml", config_text));
  }
  SweepSummary Run(const Experiment& experiment, const std::string& out, Shard shard = {},
                   int jobs = 1) const {
    RunnerOptions options;
    options.out_dir = dir / out;
    options.shard = shard;
    options.jobs = jobs;
    options.threads = 1;
    options.executable = ::harap::testing::HarapExecutable();
    return RunExperiment(experiment, options);
  }
};

const std::string kSmallSweep = std::string(
                                    "[experiment]\nname = \"small\"\n[scenarios]\n"
                                    "files = [\"cylinder.toml\", \"plane.toml\"]\n") +
                                testing::kClassicAndHierarchicalVariants;

std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (const char c : line) {
    if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return fields;
}

// results.csv without the timing and memory columns, one string per row.
std::vector<std::string> CsvWithoutTimings(const fs::path& file) {
  std::istringstream lines(ReadText(file));
  std::string line;
  std::getline(lines, line);
  const std::vector<std::string> header = SplitCsvLine(line);
  std::vector<std::string> rows;
  while (std::getline(lines, line)) {
    const std::vector<std::string> fields = SplitCsvLine(line);
    REQUIRE(fields.size() == header.size());
    std::string kept;
    for (size_t i = 0; i < fields.size(); ++i) {
      if (!IsTimingColumn(header[i])) kept += header[i] + "=" + fields[i] + ";";
    }
    rows.push_back(kept);
  }
  return rows;
}

std::map<std::string, double> Energies(const fs::path& dir) {
  std::map<std::string, double> energies;
  for (const auto& entry : fs::directory_iterator(dir / "runs")) {
    if (entry.path().extension() != ".json") continue;
    const auto report = nlohmann::json::parse(ReadText(entry.path()));
    if (report["run"]["status"] == "ok") energies[report["run"]["id"]] = report["energy"];
  }
  return energies;
}

}  // namespace

TEST_CASE("Experiment: scenarios x variants x grid, in plan order, with labels and configs",
          "[experiments][runner]") {
  Workspace workspace("grid");
  const Experiment experiment = workspace.Load(R"(
[scenarios]
files = ["cylinder.toml", "pla*.toml"]
[optimizer]
max_iterations = 50
[[variant]]
name = "classic"
optimizer.type = "classic"
[[variant]]
name = "hierarchical"
optimizer.type = "hierarchical"
upsampler.type = "positions"
[grid]
"optimizer.tolerance" = [1e-5, 1e-6, 1e-7]
solver.type = ["cholmod", "eigen_ldlt"]
solver.check_residual = [false]
)");
  // 2 scenarios x 2 variants x (3 x 2 x 1) grid values.
  REQUIRE(experiment.scenarios.size() == 2);
  CHECK(experiment.scenarios[0].name == "cylinder");
  CHECK(experiment.scenarios[1].name == "plane");
  CHECK(experiment.grid_keys ==
        std::vector<std::string>{"optimizer.tolerance", "solver.type", "solver.check_residual"});
  REQUIRE(experiment.runs.size() == 24);
  std::set<std::string> ids;
  for (size_t i = 0; i < experiment.runs.size(); ++i) {
    const ExperimentRun& run = experiment.runs[i];
    CHECK(run.index == static_cast<int>(i));
    ids.insert(run.id);
    CHECK(run.scenario == static_cast<int>(i / 12));  // scenario-major
    CHECK(run.variant == (i % 12 < 6 ? "classic" : "hierarchical"));
    CHECK(run.config_toml.find("max_iterations = 50") != std::string::npos);  // base table
  }
  CHECK(ids.size() == 24);
  // Within a variant the first grid key varies slowest.
  const ExperimentRun& run = experiment.runs[6 + 3];  // hierarchical, tolerance 1e-6, eigen_ldlt
  CHECK(run.label == "hierarchical, tolerance=1e-06, solver=eigen_ldlt, check_residual=false");
  REQUIRE(run.parameters.size() == 5);
  CHECK(run.parameters[0].first == "optimizer.type");
  CHECK(run.parameters[1].first == "upsampler.type");
  CHECK(run.parameters[2].first == "optimizer.tolerance");
  CHECK(run.config_toml.find("eigen_ldlt") != std::string::npos);
  CHECK(run.config_toml.find("positions") != std::string::npos);
  // Ids depend on the settings and the scenario, not on the plan position.
  const Experiment smaller = workspace.Load(R"(
[scenarios]
files = ["pla*.toml"]
[optimizer]
max_iterations = 50
[[variant]]
name = "hierarchical"
optimizer.type = "hierarchical"
upsampler.type = "positions"
[grid]
"optimizer.tolerance" = [1e-6]
solver.type = ["eigen_ldlt"]
solver.check_residual = [false]
)");
  REQUIRE(smaller.runs.size() == 1);
  CHECK(smaller.runs[0].id == experiment.runs[12 + 6 + 3].id);
}

TEST_CASE("Experiment: config errors name the problem before any run", "[experiments][runner]") {
  Workspace workspace("errors");
  CHECK_THROWS_WITH(workspace.Load("[scenarios]\nfiles = [\"cylinder.toml\"]\n"
                                   "[grid]\nsolver.type = [\"cholmod\", \"cholmod\"]\n"),
                    Catch::Contains("same settings"));
  CHECK_THROWS_WITH(workspace.Load("[scenarios]\nfiles = [\"cylinder.toml\"]\n"
                                   "[grid]\nsolver.type = [\"no_such_solver\"]\n"),
                    Catch::Contains("no_such_solver") && Catch::Contains("cholmod"));
  CHECK_THROWS_WITH(workspace.Load("[scenarios]\nfiles = [\"cylinder.toml\"]\n"
                                   "[grid]\noptimizer.tolerence = [1e-6]\n"),
                    Catch::Contains("tolerence"));
  CHECK_THROWS_WITH(workspace.Load("[scenarios]\nfiles = [\"missing.toml\"]\n"),
                    Catch::Contains("missing.toml") && Catch::Contains("not found"));
  CHECK_THROWS_WITH(workspace.Load("[scenarios]\nfiles = [\"nothing*.toml\"]\n"),
                    Catch::Contains("matches no file"));
  CHECK_THROWS_WITH(workspace.Load("[scenarios]\nfiles = [\"cylinder.toml\"]\n[grid]\n"
                                   "tolerance = [1e-6]\n"),
                    Catch::Contains("not a run option"));
  CHECK_THROWS_WITH(workspace.Load("[scenarios]\nfiles = [\"cylinder.toml\"]\n[run]\n"
                                   "thread = 1\n"),
                    Catch::Contains("unknown key 'thread'") && Catch::Contains("threads"));
  CHECK_THROWS_AS(ParseShard("2/2"), ConfigError);
  CHECK_THROWS_AS(ParseShard("1"), ConfigError);
  CHECK_THROWS_AS(ParseShard("-1/3"), ConfigError);
}

TEST_CASE("Experiment: a folder of meshes with a handle template", "[experiments][runner]") {
  HARAP_REQUIRE_SHARED(meshes, "meshes/cactus.obj.xz");
  Workspace workspace("template");
  const Experiment experiment = workspace.Load(fmt::format(R"(
[scenarios]
[[scenarios.folder]]
path = "{}"
include = ["cactus.obj.xz", "cow.*"]
template = {{ axis = "longest", fixed = 0.1, moved = 0.2, degrees = 30.0 }}
)",
                                                           meshes.parent_path().string()));
  REQUIRE(experiment.scenarios.size() == 2);
  CHECK(experiment.scenarios[0].name == "cactus");
  CHECK(experiment.scenarios[1].name == "cow");
  // The cactus is tallest along y and thinnest along z: the top 20% along y bends about z.
  const double extent[3] = {1.0, 1.5, 0.3};
  const std::string scenario = TemplateScenarioToml(experiment.scenarios[0], extent);
  CHECK(scenario.find("axis = \"y\", from = 0.0, to = 0.1") != std::string::npos);
  CHECK(scenario.find("axis = \"y\", from = 0.8, to = 1.0") != std::string::npos);
  CHECK(scenario.find("axis = [0.0, 0.0, 1.0], degrees = 30") != std::string::npos);
}

TEST_CASE("Sharding partitions the runs exactly", "[experiments][runner]") {
  for (int count = 1; count <= 5; ++count) {
    std::vector<int> owners(23, 0);
    for (int index = 0; index < count; ++index) {
      const Shard shard = ParseShard(fmt::format("{}/{}", index, count));
      for (int run = 0; run < 23; ++run) owners[run] += shard.Contains(run);
    }
    for (int run = 0; run < 23; ++run) CHECK(owners[run] == 1);
  }
  Workspace workspace("shards");
  const Experiment experiment = workspace.Load(kSmallSweep);
  std::set<std::string> seen;
  int total = 0;
  for (int index = 0; index < 3; ++index) {
    const SweepSummary summary =
        workspace.Run(experiment, "out", ParseShard(fmt::format("{}/3", index)));
    CHECK(summary.planned == 4);
    total += summary.in_shard;
    CHECK(summary.skipped == 0);  // no shard ran another shard's runs
    const MergeSummary merged = MergeResults(workspace.dir / "out");
    CHECK(merged.succeeded == total);
    CHECK(merged.missing == 4 - total);
  }
  CHECK(total == 4);
  CHECK(fs::exists(workspace.dir / "out" / "results-shard-2-of-3.csv"));
}

TEST_CASE("Resume skips finished runs; a failing run is recorded and the sweep goes on",
          "[experiments][runner]") {
  Workspace workspace("resume");
  std::string config = kSmallSweep;
  config.replace(config.find("\"plane.toml\"]"), 13, "\"broken.toml\", \"plane.toml\"]");
  const Experiment experiment = workspace.Load(config);
  REQUIRE(experiment.runs.size() == 6);

  const SweepSummary first = workspace.Run(experiment, "out", {}, 2);
  CHECK(first.succeeded == 4);
  CHECK(first.failed == 2);
  const fs::path out = workspace.dir / "out";
  for (const ExperimentRun& run : experiment.runs) {
    const auto report = nlohmann::json::parse(ReadText(out / "runs" / (run.id + ".json")));
    if (experiment.scenarios[run.scenario].name == "broken") {
      CHECK(report["run"]["status"] == "failed");
      CHECK_THAT(report["run"]["error"].get<std::string>(), Catch::Contains("no-such-mesh.obj"));
      CHECK(fs::exists(out / report["run"]["log"].get<std::string>()));
    } else {
      CHECK(report["run"]["status"] == "ok");
      CHECK(report.contains("trace"));
      CHECK(report["timings"].contains("constrain"));
    }
  }
  const std::string csv = ReadText(out / "results.csv");
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 7);
  CHECK(csv.find("no-such-mesh.obj") != std::string::npos);

  // Second run: everything is finished (failures too), nothing runs.
  const auto before = fs::last_write_time(out / "runs" / (experiment.runs[0].id + ".json"));
  const SweepSummary second = workspace.Run(experiment, "out");
  CHECK(second.skipped == 6);
  CHECK(second.succeeded + second.failed == 0);
  CHECK(fs::last_write_time(out / "runs" / (experiment.runs[0].id + ".json")) == before);
  CHECK(ReadText(out / "results.csv") == csv);

  // A removed report is run again, alone.
  fs::remove(out / "runs" / (experiment.runs[1].id + ".json"));
  const SweepSummary third = workspace.Run(experiment, "out");
  CHECK(third.skipped == 5);
  CHECK(third.succeeded == 1);
}

TEST_CASE("Runs are deterministic: same energies in two sweeps", "[experiments][runner]") {
  Workspace workspace("determinism");
  const Experiment experiment = workspace.Load(kSmallSweep);
  workspace.Run(experiment, "a", {}, 2);
  workspace.Run(experiment, "b", {}, 1);
  const auto a = Energies(workspace.dir / "a");
  const auto b = Energies(workspace.dir / "b");
  REQUIRE(a.size() == 4);
  CHECK(a == b);
  CHECK(CsvWithoutTimings(workspace.dir / "a" / "results.csv") ==
        CsvWithoutTimings(workspace.dir / "b" / "results.csv"));
}

TEST_CASE("Two shards run with GNU parallel, merged, equal the unsharded run",
          "[experiments][runner]") {
  if (std::system("command -v parallel >/dev/null 2>&1") != 0) {
    WARN("skipped: GNU parallel not installed (Debian package 'parallel', see .ci/setup)");
    return;
  }
  Workspace workspace("parallel");
  const fs::path config = workspace.Write("experiment.toml", kSmallSweep);
  const fs::path whole = workspace.dir / "whole";
  const fs::path sharded = workspace.dir / "sharded";
  const std::string harap = ::harap::testing::HarapExecutable();
  REQUIRE(std::system(fmt::format("{} run {} --out {} --threads 1 -q", harap, config.string(),
                                  whole.string())
                          .c_str()) == 0);
  REQUIRE(std::system(fmt::format("parallel --will-cite --halt now,fail=1 {} run {} --out {} "
                                  "--threads 1 -q --shard {{}}/2 ::: 0 1",
                                  harap, config.string(), sharded.string())
                          .c_str()) == 0);
  CHECK(fs::exists(sharded / "results-shard-0-of-2.csv"));
  CHECK(fs::exists(sharded / "results-shard-1-of-2.csv"));
  const MergeSummary merged = MergeResults(sharded);
  CHECK(merged.succeeded == 4);
  CHECK(merged.missing == 0);
  CHECK(CsvWithoutTimings(sharded / "results.csv") == CsvWithoutTimings(whole / "results.csv"));
  CHECK(Energies(sharded) == Energies(whole));
}

TEST_CASE("harap report writes report.md from a run folder", "[experiments][runner]") {
  if (std::system("/usr/bin/python3 -c 'import matplotlib, numpy' >/dev/null 2>&1") != 0) {
    WARN("skipped: /usr/bin/python3 lacks matplotlib/numpy (Debian python3-matplotlib)");
    return;
  }
  Workspace workspace("report");
  const fs::path config = workspace.Write("experiment.toml", std::string(kSmallSweep) +
                                                                 "[report]\nclaim = \"lower\"\n"
                                                                 "figures = [\"phases\"]\n");
  const fs::path out = workspace.dir / "out";
  const std::string harap = ::harap::testing::HarapExecutable();
  REQUIRE(std::system(
              fmt::format("{} run {} --out {} --threads 1 -q", harap, config.string(), out.string())
                  .c_str()) == 0);
  REQUIRE(std::system(
              fmt::format("{} report {} --no-render >/dev/null", harap, out.string()).c_str()) ==
          0);
  const std::string report = ReadText(out / "report.md");
  CHECK(report.find("| lower | **hierarchical** vs **classic** (2 pairs)") != std::string::npos);
  CHECK(report.find("| cylinder | ") != std::string::npos);
  CHECK(fs::exists(out / "figures" / "phases.png"));
  CHECK(fs::exists(out / "figures" / "phases.svg"));
}
