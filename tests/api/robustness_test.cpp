// SPDX-License-Identifier: MIT
// Robustness end to end (docs/robustness.md): mesh checks in runs and reports, welding,
// configuration errors with their location, and running out of memory under `ulimit -v`.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "api/builtins.h"
#include "api/deform.h"
#include "framework/error.h"
#include "io/mesh_io.h"
#include "tests/support/run_harap.h"
#include "tests/support/shared_data.h"
#include "tests/support/test_meshes.h"

namespace harap {
namespace {

namespace fs = std::filesystem;
using Catch::Matchers::Contains;

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("harap-{}-{}", name, getpid());
  fs::create_directories(dir);
  return dir;
}

// The seamed grid with its left edge fixed and its right edge lifted: the halves meet only at
// duplicate positions, so without welding the seam opens.
Scenario SeamScenario(std::vector<std::pair<Index, Index>>& seam) {
  Scenario scenario;
  scenario.mesh = testing::SeamedGrid(9, seam);
  ScenarioHandle left{"left", {}, {}, {}, {}}, right{"right", {}, {}, {}, {}};
  for (Index v = 0; v < scenario.mesh.num_vertices(); ++v) {
    if (scenario.mesh.vertices(v, 0) == 0.0) left.vertices.push_back(v);
    if (scenario.mesh.vertices(v, 0) == 1.0) right.vertices.push_back(v);
  }
  left.targets.resize(static_cast<Index>(left.vertices.size()), 3);
  right.targets.resize(static_cast<Index>(right.vertices.size()), 3);
  for (size_t k = 0; k < left.vertices.size(); ++k) {
    left.targets.row(static_cast<Index>(k)) = scenario.mesh.vertices.row(left.vertices[k]);
  }
  for (size_t k = 0; k < right.vertices.size(); ++k) {
    right.targets.row(static_cast<Index>(k)) = scenario.mesh.vertices.row(right.vertices[k]);
    right.targets(static_cast<Index>(k), 2) += 0.4;
  }
  scenario.handles = {left, right};
  scenario.mesh_source = "seamed grid";
  return scenario;
}

double LargestSeamGap(const Positions& positions,
                      const std::vector<std::pair<Index, Index>>& seam) {
  double gap = 0.0;
  for (const auto& [copy, original] : seam) {
    gap = std::max(gap, (positions.row(copy) - positions.row(original)).norm());
  }
  return gap;
}

TEST_CASE("RunDeform: an unwelded seam opens, mesh.weld_duplicates closes it", "[robustness]") {
  const Registries registries = MakeBuiltinRegistries();
  std::vector<std::pair<Index, Index>> seam;
  const Scenario scenario = SeamScenario(seam);
  for (const char* optimizer : {"classic", "hierarchical"}) {
    DYNAMIC_SECTION(optimizer) {
      ConfigNode config;
      config.Set("optimizer.type", fmt::format("\"{}\"", optimizer));
      const DeformOutcome as_is = RunDeform(registries, scenario, config, {});
      CHECK(as_is.mesh_checks.duplicate_vertices.count == static_cast<Index>(seam.size()));
      CHECK_FALSE(as_is.mesh_repaired);
      CHECK(LargestSeamGap(as_is.result.positions, seam) > 0.05);

      config.Set("mesh.weld_duplicates", "true");
      const DeformOutcome welded = RunDeform(registries, scenario, config, {});
      REQUIRE(welded.mesh_repaired);
      CHECK(welded.solved_vertices ==
            scenario.mesh.num_vertices() - static_cast<Index>(seam.size()));
      REQUIRE(welded.result.positions.rows() == scenario.mesh.num_vertices());
      CHECK(LargestSeamGap(welded.result.positions, seam) == 0.0);
      CHECK(welded.result.converged);
      const auto report = nlohmann::json::parse(DeformReportJson(scenario, welded, false));
      CHECK(report["mesh_checks"]["repaired"] == true);
      CHECK_THAT(report["mesh_checks"]["duplicate_vertices"]["action"].get<std::string>(),
                 Contains("welded"));
    }
  }
}

TEST_CASE("harap deform: mesh checks on the terminal and in the report, output per input vertex",
          "[robustness]") {
  const fs::path dir = TempDir("checks");
  // A closed octahedron plus an unreferenced vertex (index 6) and a repeated face.
  std::ofstream(dir / "mesh.obj")
      << "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\nv 7 7 7\n"
         "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\nf 5 3 1\n";
  std::ofstream(dir / "scenario.toml")
      << "mesh = \"mesh.obj\"\n[[handle]]\nselect.slab = { axis = \"z\", from = 0.0, to = 0.1 }\n"
         "[[handle]]\nselect.slab = { axis = \"z\", from = 0.9, to = 1.0 }\n"
         "translate = [0.1, 0.0, 0.0]\n";
  const fs::path report_file = dir / "report.json", out_file = dir / "out.ply";
  const testing::CommandResult run = testing::RunHarap(
      fmt::format("deform {} --report {} --out {}", (dir / "scenario.toml").string(),
                  report_file.string(), out_file.string()));
  INFO(run.output);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.output, Contains("checks      unreferenced vertices 1 (e.g. vertex 6): "));
  CHECK_THAT(run.output,
             Contains("duplicate faces 1 (e.g. face 8 repeats face 0): 1 copies left out"));
  CHECK_THAT(run.output, Contains("repaired    solved on 7 vertices, 8 faces"));
  std::ifstream stream(report_file);
  const auto report = nlohmann::json::parse(stream);
  const auto& checks = report["mesh_checks"];
  for (const char* key :
       {"non_finite_vertices", "unreferenced_vertices", "duplicate_vertices", "zero_area_faces",
        "duplicate_faces", "boundary_edges", "non_manifold_edges", "non_manifold_vertices",
        "inconsistently_oriented_edges"}) {
    INFO(key);
    REQUIRE(checks.contains(key));
    CHECK(checks[key].contains("count"));
    CHECK(checks[key].contains("action"));
  }
  CHECK(checks["unreferenced_vertices"]["count"] == 1);
  CHECK(checks["duplicate_faces"]["examples"][0] == nlohmann::json::array({8, 0}));
  CHECK(checks["components"]["count"] == 1);
  CHECK(checks["components"]["without_handles"] == 0);
  CHECK(checks["solved_elements"] == 8);
  const Mesh out = ReadMesh(out_file);
  REQUIRE(out.num_vertices() == 7);
  CHECK(out.num_elements() == 9);                             // written with the input's faces
  CHECK(out.vertices.row(6) == Eigen::RowVector3d(7, 7, 7));  // unreferenced: kept in place
  fs::remove_all(dir);
}

TEST_CASE("run-config errors name the file, line and dotted key", "[robustness]") {
  const Registries registries = MakeBuiltinRegistries();
  const Scenario scenario = ParseScenario(
      "mesh = { builtin = \"plane\", vertices = 100 }\n[[handle]]\n"
      "select.slab = { axis = \"x\", from = 0.0, to = 0.1 }\n",
      "inline", ".");
  // config text, then phrases the ConfigError message must contain.
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"[optimizer]\ntolerance = -1.0\n", {"run.toml:2:", "optimizer.tolerance", ">= 0"}},
      {"[optimizer]\n\nmax_iterations = 0\n", {"run.toml:3:", "optimizer.max_iterations"}},
      {"[optimizer]\ntype = \"clasic\"\n",
       {"run.toml:2:", "unknown optimizer 'clasic'", "classic"}},
      {"[solver]\nmode = \"fast\"\n", {"run.toml:2:", "solver.mode", "supernodal"}},
      {"[solver]\npivot_tolerance = 2.0\n", {"run.toml:2:", "solver.pivot_tolerance"}},
      {"[energy]\nlambda = 0.5\n", {"run.toml:2:", "energy.lambda", "valid options"}},
      {"[mesh]\nweld_duplicates = \"yes\"\n",
       {"run.toml:2:", "mesh.weld_duplicates", "true or false"}},
      {"[mesh]\nweld = true\n", {"run.toml:2:", "mesh.weld", "weld_duplicates"}},
      {"[optimizer]\ntype = \"hierarchical\"\n[hierarchy]\nmin_vertices = -5\n",
       {"run.toml:4:", "hierarchy.min_vertices", ">= 0"}},
      {"[optimizer]\ntype = \"hierarchical\"\n[upsampler]\ntype = \"smoothed_rotations\"\n"
       "passes = 0\n",
       {"run.toml:5:", "upsampler.passes", ">= 1"}},
      {"[solvr]\nmode = \"amd\"\n", {"run.toml:1:", "solvr", "solver"}},
      {"[optimizer\n", {"run.toml:1:", "TOML syntax error"}},
  };
  for (const auto& [text, phrases] : cases) {
    DYNAMIC_SECTION(text) {
      std::string message;
      try {
        RunDeform(registries, scenario, ConfigNode::Parse(text, "run.toml"), {});
      } catch (const ConfigError& error) {
        message = error.what();
      }
      INFO("message: " << message);
      REQUIRE_FALSE(message.empty());
      for (const auto& phrase : phrases) CHECK_THAT(message, Contains(phrase));
    }
  }
}

TEST_CASE("harap deform under `ulimit -v`: a clear out-of-memory error, never a crash or hang",
          "[robustness][resources]") {
  if (kAddressSanitizer) {
    WARN(
        "skipped under AddressSanitizer: it reserves terabytes of address space, so "
        "`ulimit -v` makes every run fail at start-up");
    return;
  }
  const fs::path dir = TempDir("ulimit");
  std::ofstream(dir / "scenario.toml")
      << "mesh = { builtin = \"cylinder\", vertices = 60000 }\n[[handle]]\n"
         "select.slab = { axis = \"z\", from = 0.0, to = 0.05 }\n[[handle]]\n"
         "select.slab = { axis = \"z\", from = 0.95, to = 1.0 }\ntranslate = [0.1, 0.0, 0.0]\n";
  // From start-up (about 100 MB of address space) to enough: each limit fails in a different
  // place (mesh generation, precomputation, factorization) or succeeds. `timeout` turns a hang
  // (as OpenBLAS's retry loop caused before; docs/robustness.md) into exit status 124.
  int failures = 0;
  for (const char* solver : {"cholmod", "eigen_ldlt"}) {
    for (const int megabytes : {100, 160, 220, 280, 340, 400}) {
      const testing::CommandResult run = testing::RunCommand(fmt::format(
          "ulimit -v {} && exec timeout 300 {} deform {} --solver {} --max-iterations 2 "
          "--threads 2 -q",
          megabytes * 1024, ::harap::testing::HarapExecutable(), (dir / "scenario.toml").string(),
          solver));
      INFO(solver << " under " << megabytes << " MB: exit status " << run.status
                  << ", output: " << run.output);
      CHECK((run.status == 0 || run.status == 1));
      if (run.status == 1) {
        ++failures;
        CHECK_THAT(run.output, Contains("harap: error:") && Contains("out of memory"));
        CHECK_THAT(run.output, Contains("cg") && Contains("gauss_seidel"));
      }
    }
  }
  CHECK(failures > 0);  // 100 MB is not enough for anything
  fs::remove_all(dir);
}

}  // namespace
}  // namespace harap
