// SPDX-License-Identifier: MIT
// `harap run` / `harap report`: grid expansion, sharding, resume, failures, determinism, two
// GNU parallel shards merged against one unsharded run, shards of two hosts in one folder, and
// a sweep on a real (local) Slurm. Built-in meshes of a few hundred
// vertices keep every sweep well under a second per run.
#include "runner/runner.h"

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "api/presets.h"
#include "framework/config.h"
#include "framework/error.h"
#include "io/mesh_writers.h"
#include "runner/experiment.h"
#include "runner/slurm.h"
#include "tests/support/run_harap.h"
#include "tests/support/shared_data.h"
#include "tests/support/temp_folder.h"
#include "tests/support/test_files.h"
#include "tests/support/test_meshes.h"

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
                   int jobs = 1, const std::string& host = "") const {
    RunnerOptions options;
    options.host = host;
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

TEST_CASE("Experiment: a variant names a preset; its run config keeps the name",
          "[experiments][runner]") {
  Workspace workspace("preset");
  const Experiment experiment = workspace.Load(R"([scenarios]
files = ["cylinder.toml"]
[[variant]]
name = "fast"
preset = "fast"
[[variant]]
name = "fast, fixed coarse tolerance"
preset = "fast"
optimizer.coarse_tolerance = 1e-7
)");
  REQUIRE(experiment.runs.size() == 2);
  for (const ExperimentRun& run : experiment.runs) {
    ConfigNode config = ConfigNode::Parse(run.config_toml, "run");
    CHECK(OptionReader(config).Get("preset", std::string(), "") == "fast");
    // What `harap deform --config` then makes of it: the preset below the variant's settings.
    ApplyPreset(config, "");
    CHECK(OptionReader(config.Child("solver").Child("level_0")).Get("type", std::string(), "") ==
          "adaptive");
  }
  const SweepSummary summary = workspace.Run(experiment, "out");
  CHECK(summary.failed == 0);
  const auto report = nlohmann::json::parse(
      ReadText(workspace.dir / "out" / "runs" / (experiment.runs[1].id + ".json")));
  CHECK(report["levels"][0]["solver"].get<std::string>().starts_with("adaptive"));
  // A [grid] of presets: one run each.
  const Experiment grid = workspace.Load(
      "[scenarios]\nfiles = [\"cylinder.toml\"]\n[grid]\npreset = [\"fast\", \"hierarchical\"]\n");
  REQUIRE(grid.runs.size() == 2);
  CHECK(grid.runs[0].label == "preset=fast");
  CHECK(grid.runs[0].id != grid.runs[1].id);
}

TEST_CASE("Experiment: config errors name the problem before any run", "[experiments][runner]") {
  Workspace workspace("errors");
  const std::string cylinder = "[scenarios]\nfiles = [\"cylinder.toml\"]\n";
  // A config and what its error must say.
  const std::vector<std::pair<std::string, std::vector<std::string>>> errors = {
      {cylinder + "[grid]\nsolver.type = [\"cholmod\", \"cholmod\"]\n", {"same settings"}},
      {cylinder + "[grid]\nsolver.type = [\"no_such_solver\"]\n", {"no_such_solver", "cholmod"}},
      {cylinder + "[grid]\noptimizer.tolerence = [1e-6]\n", {"tolerence"}},
      {"[scenarios]\nfiles = [\"missing.toml\"]\n", {"missing.toml", "not found"}},
      {"[scenarios]\nfiles = [\"nothing*.toml\"]\n", {"matches no file"}},
      {cylinder + "[grid]\ntolerance = [1e-6]\n", {"not a run option"}},
      {cylinder + "[run]\nthread = 1\n", {"unknown key 'thread'", "threads"}},
      {cylinder + "[run]\nmin_time = -1\n", {"'min_time' must be 0 to 3600 seconds"}},
      {cylinder + "[run]\nmin_time = nan\n", {"min_time is a non-finite number"}},
      {cylinder + "[[variant]]\nname = \"a\"\npreset = \"fastest\"\n",
       {"unknown preset 'fastest'", "fast"}},
      {cylinder + "[[variant]]\nname = \"a\"\npreset = 1\n", {"'preset' must be a string"}},
      {cylinder + "[grid]\npreset = [\"fast\", 2]\n", {"'preset' must be a string"}},
  };
  for (const auto& [config, says] : errors) {
    INFO(config);
    try {
      workspace.Load(config);
      FAIL("no error");
    } catch (const Error& error) {
      for (const std::string& part : says) CHECK_THAT(error.what(), Catch::Contains(part));
    }
  }
  CHECK_THROWS_AS(ParseShard("2/2"), ConfigError);
  CHECK_THROWS_AS(ParseShard("1"), ConfigError);
  CHECK_THROWS_AS(ParseShard("-1/3"), ConfigError);
}

TEST_CASE("A registration experiment: known-answer cases, registered, scored, reported",
          "[experiments][runner][registration]") {
  Workspace workspace("registration");
  const std::string config = R"([experiment]
name = "known"
[scenarios]
files = ["cylinder.toml"]
[known_answers]
targets = ["mesh", "points"]
[registration]
max_updates = 10
[[variant]]
name = "hierarchical"
optimizer.type = "hierarchical"
hierarchy.min_vertices = 100
[[variant]]
name = "flat"
optimizer.type = "classic"
[report]
baseline = "flat"
)";
  const Experiment experiment = workspace.Load(config);
  REQUIRE(experiment.scenarios.size() == 2);
  CHECK(experiment.scenarios[0].name == "cylinder-mesh");
  CHECK(experiment.scenarios[1].known_answer_target == "points");
  REQUIRE(experiment.runs.size() == 4);
  const SweepSummary summary = workspace.Run(experiment, "out");
  CHECK(summary.failed == 0);
  const fs::path out = workspace.dir / "out";
  // One case per scenario and target, made once and shared by both variants.
  for (const char* name : {"cylinder-mesh", "cylinder-points"}) {
    for (const char* file : {"source.ply", "target.ply", "answer.ply"}) {
      CHECK(fs::exists(out / "cases" / name / file));
    }
  }
  for (const ExperimentRun& run : experiment.runs) {
    const auto report = nlohmann::json::parse(ReadText(out / "runs" / (run.id + ".json")));
    INFO(run.label);
    CHECK(report["command"] == "register");
    CHECK(report["mode"] == (run.variant == "flat" ? "flat" : "hierarchical"));
    CHECK(report["answer"]["mean_error_relative"].get<double>() > 0.0);
    CHECK(report["registration"]["max_updates"] == 10);
  }
  const std::string csv = ReadText(out / "results.csv");
  CHECK(csv.find("answer_mean_error") != std::string::npos);
  if (std::system("/usr/bin/python3 -c 'import matplotlib, numpy' >/dev/null 2>&1") == 0) {
    REQUIRE(std::system(fmt::format("{} report {} --no-render >/dev/null",
                                    ::harap::testing::HarapExecutable(), out.string())
                            .c_str()) == 0);
    const std::string report = ReadText(out / "report.md");
    CHECK(report.find("**hierarchical** vs **flat** (2 cases)") != std::string::npos);
    CHECK(report.find("| cylinder-points | 591 | flat | 1,182 points |") != std::string::npos);
  }

  SECTION("config errors name the problem before any run") {
    CHECK_THROWS_WITH(workspace.Load("[scenarios]\nfiles = [\"cylinder.toml\"]\n"
                                     "[registration]\nstages = 2\n"),
                      Catch::Contains("[known_answers]"));
    CHECK_THROWS_WITH(workspace.Load("[scenarios]\nfiles = [\"cylinder.toml\"]\n"
                                     "[known_answers]\ntargets = [\"cloud\"]\n"),
                      Catch::Contains("cloud") && Catch::Contains("mesh, points, damaged"));
    CHECK_THROWS_WITH(workspace.Load("[scenarios]\nfiles = [\"cylinder.toml\"]\n"
                                     "[known_answers]\nremoved = 1.5\n"),
                      Catch::Contains("removed"));
    CHECK_THROWS_WITH(workspace.Load("[scenarios]\nfiles = [\"cylinder.toml\"]\n"
                                     "[known_answers]\n[grid]\nregistration.stagez = [2]\n"),
                      Catch::Contains("stagez") && Catch::Contains("stages"));
  }
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

TEST_CASE("Experiment: generated scenarios, meshes x kinds x refine; bad meshes fail alone",
          "[experiments][runner]") {
  Workspace workspace("generated");
  fs::create_directories(workspace.dir / "meshes");
  const Mesh tube = testing::Tube(16, 10);
  WriteMesh(workspace.dir / "meshes" / "tube.ply", tube.vertices, tube.elements);
  workspace.Write("meshes/empty.obj", "");
  workspace.Write("meshes/tiny.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const Experiment experiment = workspace.Load(R"(
[scenarios]
meshes = "meshes/*"
kinds = ["bend", "twist"]
refine = [0, 1]
[optimizer]
tolerance = 1e-4
)");
  std::vector<std::string> names;
  for (const ExperimentScenario& scenario : experiment.scenarios) names.push_back(scenario.name);
  CHECK(names == std::vector<std::string>{"empty-bend", "empty-bend-r1", "empty-twist",
                                          "empty-twist-r1", "tiny-bend", "tiny-bend-r1",
                                          "tiny-twist", "tiny-twist-r1", "tube-bend",
                                          "tube-bend-r1", "tube-twist", "tube-twist-r1"});
  const SweepSummary summary = workspace.Run(experiment, "out");
  CHECK(summary.succeeded == 4);
  CHECK(summary.failed == 8);
  for (const ExperimentRun& run : experiment.runs) {
    const auto report =
        nlohmann::json::parse(ReadText(workspace.dir / "out" / "runs" / (run.id + ".json")));
    const std::string& name = experiment.scenarios[run.scenario].name;
    CAPTURE(name);
    if (name.starts_with("tube")) {
      CHECK(report["run"]["status"] == "ok");
      const int vertices = report["mesh"]["vertices"];
      if (name.ends_with("-r1")) {
        CHECK(vertices > 3 * tube.num_vertices());  // Loop-refined once
      } else {
        CHECK(vertices == tube.num_vertices());
      }
    } else {
      CHECK(report["run"]["status"] == "failed");
      CHECK_THAT(report["run"]["error"].get<std::string>(),
                 Catch::Contains(name.starts_with("tiny") ? "cannot place handles" : "empty.obj"));
    }
  }
  // A typo in a kind fails before any run, naming the valid kinds.
  CHECK_THROWS_WITH(workspace.Load("[scenarios]\nmeshes = \"meshes/*\"\nkinds = [\"bent\"]\n"),
                    Catch::Contains("bend, twist, lift, stretch"));
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

TEST_CASE("Shards on two hosts share one folder: each removes only its own host's stale files",
          "[experiments][runner]") {
  Workspace workspace("two-hosts");
  const Experiment experiment = workspace.Load(kSmallSweep);
  const fs::path out = workspace.dir / "out";
  fs::create_directories(out / "runs");
  // A PID that is not running: a child that has exited and been reaped.
  const pid_t gone = fork();
  if (gone == 0) _exit(0);
  REQUIRE(gone > 0);
  waitpid(gone, nullptr, 0);
  // The same dead PID on both hosts (PIDs repeat across hosts), and a live process of host A.
  const fs::path stale_a = out / "runs" / fmt::format(".x.json.{}@node-a.tmp", gone);
  const fs::path stale_b = out / "runs" / fmt::format(".x.json.{}@node-b.tmp", gone);
  const fs::path live_a = out / "runs" / fmt::format(".y.json.{}@node-a.tmp", getppid());
  for (const fs::path& file : {stale_a, stale_b, live_a}) std::ofstream(file) << "partial";

  // Host A's shard: its own dead process's file goes; host B's file (whose PID host A cannot
  // check) and the live one stay.
  CHECK(workspace.Run(experiment, "out", ParseShard("0/2"), 1, "node-a").succeeded == 2);
  CHECK_FALSE(fs::exists(stale_a));
  CHECK(fs::exists(stale_b));
  CHECK(fs::exists(live_a));
  // Host B's shard: under another name (dots, as gethostname may give, become '_') it leaves
  // the file alone; under its own name it removes its stale file.
  CHECK(workspace.Run(experiment, "out", ParseShard("1/2"), 1, "node.b").succeeded == 2);
  CHECK(fs::exists(stale_b));  // "node.b" is written "node_b": not this file's host
  CHECK(workspace.Run(experiment, "out", ParseShard("1/2"), 1, "node-b").skipped == 2);
  CHECK_FALSE(fs::exists(stale_b));
  CHECK(fs::exists(live_a));
  // Both hosts' results merge into one folder, nothing lost.
  const MergeSummary merged = MergeResults(out);
  CHECK(merged.succeeded == 4);
  CHECK(merged.missing == 0);
  CHECK(Energies(out).size() == 4);
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

  // [run] min_time: the short runs are repeated in their processes, with the same results.
  const Experiment repeated = workspace.Load(kSmallSweep + "[run]\nmin_time = 30.0\n");
  CHECK(repeated.settings.min_time == 30.0);
  workspace.Run(repeated, "c", {}, 2);
  CHECK(Energies(workspace.dir / "c") == a);
  CHECK(CsvWithoutTimings(workspace.dir / "c" / "results.csv") ==
        CsvWithoutTimings(workspace.dir / "a" / "results.csv"));
  for (const auto& entry : fs::directory_iterator(workspace.dir / "c" / "runs")) {
    if (entry.path().extension() != ".json") continue;
    const auto report = nlohmann::json::parse(ReadText(entry.path()));
    CHECK(report["repetitions"]["count"] == 30);
    CHECK_THAT(report["run"]["command"].get<std::string>(), Catch::Contains("--min-time 30"));
  }
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

namespace {

// A private single-node Slurm (.ci/slurm-local) for the duration of a test; SLURM_CONF points
// harap, sbatch and squeue at it.
struct LocalSlurm {
  explicit LocalSlurm(const fs::path& folder) : dir(folder) {
    const auto started = testing::RunCommand(fmt::format(
        "{}/.ci/slurm-local start {}", ::harap::testing::SourceDir().string(), dir.string()));
    up = started.status == 0;
    output = started.output;
    if (up) setenv("SLURM_CONF", (dir / "slurm.conf").c_str(), 1);
  }
  ~LocalSlurm() {
    (void)testing::RunCommand(fmt::format("{}/.ci/slurm-local stop {}",
                                          ::harap::testing::SourceDir().string(), dir.string()));
    unsetenv("SLURM_CONF");
  }
  // Waits until the queue is empty (at most `seconds`); false on timeout.
  bool WaitForEmptyQueue(double seconds) const {
    for (int i = 0; i < static_cast<int>(seconds * 10); ++i) {
      const auto queue = testing::RunCommand("squeue -h");
      if (queue.status == 0 && queue.output.empty()) return true;
      usleep(100000);
    }
    return false;
  }
  fs::path dir;
  bool up = false;
  std::string output;
};

}  // namespace

TEST_CASE("harap run --slurm on a real Slurm: a cancelled task resumed, merged = unsharded",
          "[experiments][runner][slurm]") {
  if (std::system("command -v sbatch >/dev/null && command -v slurmctld >/dev/null && "
                  "command -v slurmd >/dev/null && command -v munged >/dev/null") != 0) {
    WARN(
        "skipped: Slurm is not installed (Debian packages slurmctld slurmd slurm-client munge; "
        ".ci/setup installs them)");
    return;
  }
  Workspace workspace("slurm");
  LocalSlurm slurm(workspace.dir / "cluster");
  INFO(slurm.output);
  REQUIRE(slurm.up);
  // Six runs of about a second each (a fixed number of iterations) in three shards.
  workspace.Write("slow.toml", testing::kSlowCylinderScenario);
  const std::string config = workspace.Write("sweep.toml", R"(
[scenarios]
files = ["slow.toml"]
[slurm]
tasks = 3
cpus_per_task = 1
[optimizer]
tolerance = 1e-30
[grid]
"optimizer.max_iterations" = [400, 401, 402, 403, 404, 405]
)");
  const fs::path out = workspace.dir / "out";
  const auto submitted =
      testing::RunHarap(fmt::format("run {} --out {} --slurm", config, out.string()));
  INFO(submitted.output);
  REQUIRE(submitted.status == 0);
  CHECK_THAT(submitted.output, Catch::Contains("(3 of 3 shards: 0,1,2)"));
  const std::string script = ReadText(out / "slurm" / "array.sh");
  CHECK_THAT(script, Catch::Contains("--shard \"${SLURM_ARRAY_TASK_ID}/3\""));
  CHECK_THAT(script, Catch::Contains(fmt::format("--out '{}'", out.string())));

  // Cancel shard 1 while it runs.
  const std::string array_job = nlohmann::json::parse(
      ReadText(out / "slurm" / "submissions.json"))["submissions"][0]["array_job"];
  bool cancelled = false;
  for (int i = 0; i < 600 && !cancelled; ++i) {
    const auto state = testing::RunCommand(fmt::format("squeue -h -r -j {}_1 -o %T", array_job));
    if (state.output == "RUNNING\n") {
      usleep(300000);
      cancelled = testing::RunCommand(fmt::format("scancel {}_1", array_job)).status == 0;
    }
    usleep(100000);
  }
  REQUIRE(cancelled);
  REQUIRE(slurm.WaitForEmptyQueue(120));
  const auto after_cancel = testing::RunHarap("status " + out.string());
  INFO(after_cancel.output);
  CHECK_THAT(after_cancel.output, Catch::Contains("no job of the last submission is queued"));
  const FolderStatus partial = CollectStatus(out);
  REQUIRE(partial.tasks == 3);
  CHECK(partial.shards[0].done == 2);
  CHECK(partial.shards[2].done == 2);
  CHECK(partial.shards[1].missing > 0);

  // The same command submits shard 1 alone; the report job merges every shard.
  const auto resumed =
      testing::RunHarap(fmt::format("run {} --out {} --slurm", config, out.string()));
  INFO(resumed.output);
  REQUIRE(resumed.status == 0);
  CHECK_THAT(resumed.output, Catch::Contains("(1 of 3 shards: 1)"));
  REQUIRE(slurm.WaitForEmptyQueue(120));
  int logs = 0;
  for (const auto& entry : fs::directory_iterator(out / "slurm" / "logs")) {
    logs += entry.path().filename().string().starts_with("shard-1-job-");
  }
  CHECK(logs == 2);  // the cancelled task's log and the resumed one's
  const FolderStatus complete = CollectStatus(out);
  for (const ShardStatus& shard : complete.shards) CHECK(shard.done == 2);
  const auto again =
      testing::RunHarap(fmt::format("run {} --out {} --slurm", config, out.string()));
  CHECK_THAT(again.output, Catch::Contains("nothing submitted"));

  const fs::path whole = workspace.dir / "whole";
  REQUIRE(testing::RunHarap(fmt::format("run {} --out {} --threads 1 -q", config, whole.string()))
              .status == 0);
  REQUIRE(fs::exists(out / "results.csv"));  // written by the report job
  CHECK(CsvWithoutTimings(out / "results.csv") == CsvWithoutTimings(whole / "results.csv"));
  CHECK(Energies(out) == Energies(whole));
  CHECK(Energies(out).size() == 6);
}
