// SPDX-License-Identifier: MIT
// `harap run` / `harap report` for a new user: the whole config, figures included,
// is checked before any run; runs are named in the progress; comparisons across different
// energies are flagged; a sweep killed with SIGKILL resumes keeping every finished run and
// leaves no partial file.
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>

#include "framework/error.h"
#include "runner/experiment.h"
#include "tests/support/run_harap.h"
#include "tests/support/shared_data.h"
#include "tests/support/temp_folder.h"
#include "tests/support/test_files.h"

namespace {

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using harap::testing::ReadText;
using harap::testing::RunCommand;
using harap::testing::RunHarap;
using harap::testing::TempFolder;

// Each case's folder with the scenario its configs name.
struct Folder : TempFolder {
  explicit Folder(const std::string& name) : TempFolder("sweep-ux-" + name) {
    Write("cylinder.toml", harap::testing::kCylinderBendScenario);
  }
};

const std::string kTwoVariants = std::string("[scenarios]\nfiles = [\"cylinder.toml\"]\n") +
                                 harap::testing::kClassicAndHierarchicalVariants;

TEST_CASE("harap run checks [report] before any run: figures, keys, compare",
          "[experiments][sweep_ux]") {
  Folder folder("report-keys");
  const std::string config = folder.Write(
      "bad.toml", std::string(kTwoVariants) + "[report]\nfigures = [\"phases\", \"phasse\"]\n");
  const fs::path out = folder.dir / "out";
  const auto result = RunHarap(fmt::format("run {} --out {}", config, out.string()));
  INFO(result.output);
  CHECK(result.status == 1);
  CHECK_THAT(result.output, Contains("bad.toml:"));
  CHECK_THAT(result.output, Contains("unknown figure 'phasse'"));
  CHECK_THAT(result.output,
             Contains("phases, energy_vs_time, relative_scatter, levels, energy_bars"));
  CHECK_FALSE(fs::exists(out));  // nothing ran, nothing was written

  // The list is the one report.py reads.
  const std::string keys =
      ReadText(::harap::testing::SourceDir() / "experiments/scripts/report_keys.json");
  for (const std::string& figure : harap::LoadReportKeys().figures) {
    CHECK(keys.find(fmt::format("\"{}\"", figure)) != std::string::npos);
  }
  const std::string report_py =
      ReadText(::harap::testing::SourceDir() / "experiments/scripts/report.py");
  CHECK_THAT(report_py, Contains("report_keys.json"));

  // A typo in a scenario file fails now too, naming the scenario file and line.
  folder.Write("typo.toml",
               "mesh = { builtin = \"cylinder\", vertices = 600 }\n[[handle]]\n"
               "select.slab = { axis = \"z\", from = 0.0, to = 0.05 }\n"
               "rotat = { axis = [1, 0, 0], degrees = 10 }\n");
  const std::string typo_config =
      folder.Write("typo-config.toml", "[scenarios]\nfiles = [\"typo.toml\"]\n");
  const auto typo = RunHarap(fmt::format("run {} --out {}", typo_config, out.string()));
  CHECK(typo.status == 1);
  CHECK_THAT(typo.output, Contains("typo.toml:4:1") && Contains("unknown key 'rotat'"));
  CHECK_FALSE(fs::exists(out));

  auto error_of = [&](const std::string& report_table) {
    try {
      harap::ParseExperiment(std::string(kTwoVariants) +
                                 "[grid]\n\"solver.type\" = "
                                 "[\"cholmod\", \"eigen_ldlt\"]\n" +
                                 report_table,
                             "x.toml", folder.dir);
    } catch (const harap::Error& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(error_of("[report]\nfigure = [\"phases\"]\n"),
             Contains("unknown key 'figure' in [report]") && Contains("figures"));
  CHECK_THAT(error_of("[report]\ncompare = \"solver\"\n"), Contains("compare = \"solver\"") &&
                                                               Contains("\"solver.type\"") &&
                                                               Contains("\"variant\""));
  CHECK_THAT(error_of("[report]\npanel = \"variant\"\n"), Contains("names no [grid] key"));
  CHECK_THAT(error_of("[report]\nrender = [\"cylinder\", \"bunny\"]\n"),
             Contains("'bunny', which is no scenario"));
  CHECK_THAT(error_of("[report]\nrender_runs = 0\n"), Contains("render_runs"));
  CHECK(error_of("[report]\ncompare = \"solver.type\"\nfigures = [\"levels\"]\n") == "no error");
}

TEST_CASE("harap run names the runs in its progress and warns about different energies",
          "[experiments][sweep_ux]") {
  Folder folder("names");
  const std::string config = folder.Write("energies.toml", R"(
[scenarios]
files = ["cylinder.toml"]
[optimizer]
tolerance = 1e-5
[[variant]]
name = "spokes"
energy.type = "spokes_and_rims"
[[variant]]
name = "edges"
energy.type = "spokes"
[report]
figures = ["phases", "relative_scatter", "energy_bars"]
)");
  const fs::path out = folder.dir / "out";
  // Piped: plain lines, one per finished run, named by scenario and variant.
  const auto result = RunHarap(fmt::format("run {} --out {} --threads 1", config, out.string()));
  INFO(result.output);
  REQUIRE(result.status == 0);
  CHECK_THAT(result.output, Contains("warning: the runs use 2 different energies"));
  CHECK_THAT(result.output, Contains("[1/2] ok      cylinder | spokes"));
  CHECK_THAT(result.output, Contains("[2/2] ok      cylinder | edges"));
  CHECK_THAT(result.output, !Contains("cylinder-"));  // no hashed ids

  if (std::system("/usr/bin/python3 -c 'import matplotlib, numpy' >/dev/null 2>&1") != 0) {
    WARN("skipped the report part: /usr/bin/python3 lacks matplotlib/numpy");
    return;
  }
  const auto report = RunHarap(fmt::format("report {} --no-render", out.string()));
  INFO(report.output);
  REQUIRE(report.status == 0);
  CHECK_THAT(report.output, Contains("report: ["));  // progress lines
  CHECK_THAT(report.output, Contains("figure 1/3: phases"));
  const std::string text = ReadText(out / "report.md");
  CHECK_THAT(text, Contains("different energies"));
  CHECK_THAT(text, Contains("spokes vs spokes_and_rims"));
  CHECK_THAT(text, !Contains("median energy ratio"));
  CHECK_THAT(text, Contains("relative_scatter: no data"));        // its only pair mixes energies
  CHECK_THAT(text, Contains("The runs use different energies"));  // energy_bars caption
  CHECK_THAT(text, !Contains("lower energy in"));
}

TEST_CASE("a sweep killed with SIGKILL resumes keeping every finished run, no partial file",
          "[experiments][sweep_ux]") {
  Folder folder("sigkill");
  // Six runs of most of a second each (a fixed number of iterations), meshes saved (more files
  // that could be left partial).
  folder.Write("slow.toml", harap::testing::kSlowCylinderScenario);
  const std::string config = folder.Write("kill.toml", R"(
[scenarios]
files = ["slow.toml"]
[run]
save_mesh = true
[optimizer]
tolerance = 1e-30
[grid]
"optimizer.max_iterations" = [700, 701, 702, 703, 704, 705]
)");
  const fs::path out = folder.dir / "out";
  // Start the sweep in the background, kill it with SIGKILL once two runs are finished.
  const auto killed = RunCommand(fmt::format(
      "{harap} run {config} --out {out} --threads 1 -q & pid=$!; "
      "for i in $(seq 1 600); do "
      "  n=$(ls {out}/runs/*.json 2>/dev/null | wc -l); [ \"$n\" -ge 2 ] && break; sleep 0.05; "
      "done; kill -9 $pid; wait $pid; echo \"exit $?\"",
      fmt::arg("harap", ::harap::testing::HarapExecutable()), fmt::arg("config", config),
      fmt::arg("out", out.string())));
  INFO(killed.output);
  REQUIRE_THAT(killed.output, Contains("exit 137"));  // killed, not finished
  std::map<std::string, std::string> finished;
  for (const auto& entry : fs::directory_iterator(out / "runs")) {
    if (entry.path().extension() == ".json" && entry.path().filename().string()[0] != '.') {
      finished[entry.path().filename().string()] = ReadText(entry.path());
    }
  }
  REQUIRE(finished.size() >= 2);
  REQUIRE(finished.size() < 6);
  // The killed sweep's running child died with it (no orphan goes on writing into the folder).
  usleep(100000);
  const auto still = RunCommand(fmt::format("pgrep -f -- '[-]-out {}' || true", out.string()));
  CHECK(still.output.empty());

  const auto resumed = RunHarap(fmt::format("run {} --out {} --threads 1", config, out.string()));
  INFO(resumed.output);
  REQUIRE(resumed.status == 0);
  CHECK_THAT(resumed.output,
             Contains(fmt::format("6 in this shard: {} done before", finished.size())));
  // Every finished run kept as it was; every run done; no temporary or partial file anywhere.
  for (const auto& [name, text] : finished) CHECK(ReadText(out / "runs" / name) == text);
  int reports = 0, meshes = 0;
  for (const auto& entry : fs::recursive_directory_iterator(out)) {
    const std::string name = entry.path().filename().string();
    INFO(entry.path());
    CHECK(name[0] != '.');
    CHECK(entry.path().extension() != ".log");
    reports +=
        entry.path().parent_path().filename() == "runs" && entry.path().extension() == ".json";
    meshes += entry.path().parent_path().filename() == "meshes" &&
              entry.path().extension() == ".ply" && name.find(".rest.") == std::string::npos;
  }
  CHECK(reports == 6);
  CHECK(meshes == 6);
  const std::string csv = ReadText(out / "results.csv");
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 7);
}

}  // namespace
