// SPDX-License-Identifier: MIT
// The `harap deform` walkthrough of a new user: output formats and unwritable paths
// fail before solving, a mesh given as a scenario says so, repaired meshes are summarized as
// solved, warnings for results that mislead, output that says what it measured (direct solvers,
// --version, list KIND, pieces, hierarchical iterations), progress phases, and Ctrl-C.
#include <fcntl.h>
#include <fmt/ranges.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "api/builtins.h"
#include "api/deform.h"
#include "api/huge_pages.h"
#include "api/run_warnings.h"
#include "cli/cli_output.h"
#include "cli/output_checks.h"
#include "cli/progress.h"
#include "io/mesh_io.h"
#include "tests/support/run_harap.h"
#include "tests/support/shared_data.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

namespace harap {
namespace {

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using testing::CommandResult;
using testing::RunHarap;

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("harap-cli-{}-{}", name, getpid());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

nlohmann::json ReadJson(const fs::path& file) {
  std::ifstream stream(file);
  REQUIRE(stream);
  return nlohmann::json::parse(stream);
}

// A 6 x 3 grid strip along x with its ends as handles.
constexpr const char* kStripHandles =
    "[[handle]]\nname = \"left\"\nselect.slab = { axis = \"x\", from = 0.0, to = 0.1 }\n"
    "[[handle]]\nname = \"right\"\nselect.slab = { axis = \"x\", from = 0.9, to = 1.0 }\n"
    "translate = [0.0, 0.0, 0.3]\n";

// Writes grid.obj (a welded grid) and, with `soup`, every triangle with its own three corners.
void WriteGridObj(const fs::path& file, int nx, int ny, bool soup) {
  const Mesh grid = testing::Grid(nx, ny);
  std::ofstream out(file);
  if (!soup) {
    for (Index v = 0; v < grid.num_vertices(); ++v) {
      out << fmt::format("v {} {} {}\n", grid.vertices(v, 0), grid.vertices(v, 1),
                         grid.vertices(v, 2));
    }
    for (Index f = 0; f < grid.num_elements(); ++f) {
      out << fmt::format("f {} {} {}\n", grid.elements(f, 0) + 1, grid.elements(f, 1) + 1,
                         grid.elements(f, 2) + 1);
    }
    return;
  }
  for (Index f = 0; f < grid.num_elements(); ++f) {
    for (int a = 0; a < 3; ++a) {
      const Index v = grid.elements(f, a);
      out << fmt::format("v {} {} {}\n", grid.vertices(v, 0), grid.vertices(v, 1),
                         grid.vertices(v, 2));
    }
    out << fmt::format("f {} {} {}\n", 3 * f + 1, 3 * f + 2, 3 * f + 3);
  }
}

fs::path StripScenario(const fs::path& dir, bool soup = false) {
  WriteGridObj(dir / "strip.obj", 12, 4, soup);
  std::ofstream(dir / "strip.toml") << "mesh = \"strip.obj\"\n" << kStripHandles;
  return dir / "strip.toml";
}

TEST_CASE("harap deform --out: the extension picks the format, else it refuses before solving",
          "[experiments][cli]") {
  const fs::path dir = TempDir("formats");
  const fs::path scenario = StripScenario(dir);
  for (const char* name : {"out.obj", "out.off", "out.ply", "out.stl"}) {
    const CommandResult run =
        RunHarap(fmt::format("deform {} --out {} -q", scenario.string(), (dir / name).string()));
    INFO(name << ": " << run.output);
    REQUIRE(run.status == 0);
    const Mesh out = ReadMesh(dir / name);
    CHECK(out.num_elements() == 2 * 11 * 3);
  }
  std::ifstream obj(dir / "out.obj");
  std::string first_line;
  std::getline(obj, first_line);
  CHECK(first_line == "# written by harap");  // text, not PLY bytes

  // Refused before the solve: no summary, no file, the valid extensions named.
  const CommandResult vtk =
      RunHarap(fmt::format("deform {} --out {}", scenario.string(), (dir / "out.vtk").string()));
  CHECK(vtk.status == 1);
  CHECK_THAT(vtk.output, Contains("out.vtk") && Contains(".obj") && Contains(".stl"));
  CHECK_THAT(vtk.output, !Contains("energy "));
  CHECK_FALSE(fs::exists(dir / "out.vtk"));
  const CommandResult tets =
      RunHarap(fmt::format("deform {} --out {}", scenario.string(), (dir / "out.mesh").string()));
  CHECK(tets.status == 1);
  CHECK_THAT(tets.output, Contains("holds tetrahedra"));
  CHECK_FALSE(fs::exists(dir / "out.mesh"));

  // Unwritable paths fail before the solve and leave no empty files behind.
  const CommandResult no_folder =
      RunHarap(fmt::format("deform {} --out {} --report {}", scenario.string(),
                           (dir / "new.ply").string(), (dir / "missing" / "report.json").string()));
  CHECK(no_folder.status == 1);
  CHECK_THAT(no_folder.output, Contains("--report") && Contains("does not exist"));
  CHECK_THAT(no_folder.output, !Contains("energy "));
  CHECK_FALSE(fs::exists(dir / "new.ply"));
  const CommandResult folder =
      RunHarap(fmt::format("deform {} --out {}", scenario.string(), dir.string() + "/"));
  CHECK(folder.status == 1);
  CHECK_THAT(folder.output, Contains("is a folder"));
  fs::remove_all(dir);
}

TEST_CASE("harap deform MESH says a scenario is expected and shows one", "[experiments][cli]") {
  const fs::path dir = TempDir("mesh-as-scenario");
  WriteGridObj(dir / "bar.obj", 4, 2, false);
  for (const char* command : {"deform", "hierarchy"}) {
    DYNAMIC_SECTION(command) {
      const CommandResult run = RunHarap(fmt::format("{} {}", command, (dir / "bar.obj").string()));
      INFO(run.output);
      CHECK(run.status == 1);
      CHECK_THAT(run.output, Contains("is a mesh file") && Contains("scenario"));
      CHECK_THAT(run.output, Contains("mesh = \"bar.obj\"") && Contains("[[handle]]"));
      CHECK_THAT(run.output, !Contains("TOML syntax error"));
    }
  }
  fs::remove_all(dir);
}

TEST_CASE("a triangle soup: warned about; welded, the summary shows the repaired mesh",
          "[experiments][cli]") {
  const fs::path dir = TempDir("soup");
  const fs::path scenario = StripScenario(dir, /*soup=*/true);
  const fs::path report_file = dir / "report.json";
  const CommandResult soup =
      RunHarap(fmt::format("deform {} --report {}", scenario.string(), report_file.string()));
  INFO(soup.output);
  REQUIRE(soup.status == 0);
  CHECK_THAT(soup.output, Contains("warning     the mesh is a triangle soup: 66 separate pieces") &&
                              Contains("mesh.weld_duplicates=true"));
  const auto report = ReadJson(report_file);
  REQUIRE(report["warnings"].size() == 1);
  CHECK_THAT(report["warnings"][0].get<std::string>(), Contains("soup"));
  CHECK(report["status"] == "ok");
  CHECK_FALSE(report["mesh_checks"].contains("after_repair"));

  const CommandResult welded =
      RunHarap(fmt::format("deform {} --set mesh.weld_duplicates=true --report {}",
                           scenario.string(), report_file.string()));
  INFO(welded.output);
  REQUIRE(welded.status == 0);
  // The input's findings, then the repaired mesh's: one component, no duplicates, no warning.
  CHECK_THAT(welded.output, Contains("checks      duplicate vertices"));
  CHECK_THAT(welded.output, Contains("repaired    solved on 48 vertices, 66 faces"));
  CHECK_THAT(welded.output, Contains("  checks    boundary edges"));
  CHECK_THAT(welded.output, !Contains("  checks    duplicate vertices") && !Contains("warning"));
  const auto repaired = ReadJson(report_file);
  CHECK(repaired["warnings"].empty());
  const auto& after = repaired["mesh_checks"]["after_repair"];
  CHECK(after["components"]["count"] == 1);
  CHECK(after["duplicate_vertices"]["count"] == 0);
  CHECK(repaired["mesh_checks"]["components"]["count"] == 66);
  fs::remove_all(dir);
}

TEST_CASE("warnings: overlapping handles, handles on every vertex, a one-level hierarchy",
          "[experiments][cli]") {
  const fs::path dir = TempDir("warnings");
  WriteGridObj(dir / "strip.obj", 12, 4, false);
  std::ofstream(dir / "overlap.toml")
      << "mesh = \"strip.obj\"\n[[handle]]\nname = \"a\"\n"
         "select.slab = { axis = \"x\", from = 0.0, to = 0.3 }\n[[handle]]\nname = \"b\"\n"
         "select.slab = { axis = \"x\", from = 0.2, to = 0.4 }\ntranslate = [0.0, 0.0, 0.1]\n";
  std::ofstream(dir / "everything.toml")
      << "mesh = \"strip.obj\"\n[[handle]]\nselect.slab = { axis = \"x\", from = 0.0, to = 1.0 }\n"
         "translate = [0.0, 0.0, 0.1]\n";
  const fs::path report_file = dir / "report.json";

  const CommandResult overlap = RunHarap(
      fmt::format("deform {} --report {}", (dir / "overlap.toml").string(), report_file.string()));
  INFO(overlap.output);
  REQUIRE(overlap.status == 0);
  CHECK_THAT(overlap.output, Contains("warning     handles 'a' and 'b' overlap: 4 vertices"));
  CHECK(ReadJson(report_file)["warnings"].size() == 1);

  const CommandResult everything = RunHarap(fmt::format(
      "deform {} --report {}", (dir / "everything.toml").string(), report_file.string()));
  INFO(everything.output);
  REQUIRE(everything.status == 0);
  CHECK_THAT(everything.output,
             Contains("iterations  0 (nothing to solve: every vertex is a handle)"));
  CHECK_THAT(everything.output, Contains("warning     the handles leave no vertex free"));
  CHECK_THAT(everything.output, !Contains("(converged)"));

  const CommandResult small =
      RunHarap(fmt::format("deform {} --optimizer hierarchical --report {}",
                           (dir / "overlap.toml").string(), report_file.string()));
  INFO(small.output);
  REQUIRE(small.status == 0);
  CHECK_THAT(small.output, Contains("warning     the hierarchy has a single level: the mesh (48 "
                                    "vertices)") &&
                               Contains("hierarchy.min_vertices="));
  const auto report = ReadJson(report_file);
  CHECK(report["warnings"].size() == 2);  // the overlap too
  // A hierarchy that has levels: no warning.
  const CommandResult levels = RunHarap(fmt::format(
      "deform {} --optimizer hierarchical --set hierarchy.min_vertices=10 -q --report {}",
      (dir / "overlap.toml").string(), report_file.string()));
  REQUIRE(levels.status == 0);
  CHECK(ReadJson(report_file)["warnings"].size() == 1);
  fs::remove_all(dir);
}

TEST_CASE("LooksLikeTriangleSoup: a body with a few loose triangles is no soup",
          "[experiments][cli]") {
  MeshCheckReport checks;
  checks.components.push_back({0, 500, 300, 10});
  for (int k = 0; k < 5; ++k) checks.components.push_back({Index(500 + k), 1, 3, 0});
  CHECK_FALSE(LooksLikeTriangleSoup(checks));
  for (int k = 0; k < 20; ++k) checks.components.push_back({Index(600 + k), 1, 3, 0});
  CHECK(LooksLikeTriangleSoup(checks));
}

TEST_CASE("the summary says what it measured: direct solvers, pieces, levels, --version, list",
          "[experiments][cli]") {
  const fs::path dir = TempDir("measured");
  const fs::path scenario = StripScenario(dir);
  const fs::path report_file = dir / "report.json";
  const CommandResult direct =
      RunHarap(fmt::format("deform {} --report {}", scenario.string(), report_file.string()));
  INFO(direct.output);
  REQUIRE(direct.status == 0);
  CHECK_THAT(direct.output, Contains("direct") && Contains("residual not computed"));
  CHECK_THAT(direct.output, !Contains("0 iterations") && !Contains("0.00e+00"));
  CHECK(ReadJson(report_file)["levels"][0]["max_relative_residual"].is_null());
  const CommandResult checked =
      RunHarap(fmt::format("deform {} --set solver.check_residual=true", scenario.string()));
  CHECK_THAT(checked.output, Contains("direct") && Contains("max residual"));
  const CommandResult iterative = RunHarap(fmt::format("deform {} --solver cg", scenario.string()));
  INFO(iterative.output);
  CHECK_THAT(iterative.output, Contains(" iterations ") && Contains("max residual"));

  const CommandResult hierarchical = RunHarap(fmt::format(
      "deform {} --optimizer hierarchical --set hierarchy.min_vertices=10", scenario.string()));
  INFO(hierarchical.output);
  REQUIRE(hierarchical.status == 0);
  CHECK_THAT(hierarchical.output,
             Contains("pieces      optimizer hierarchical | energy spokes_and_rims | solver "
                      "cholmod | hierarchy octree | upsampler rotations"));
  CHECK_THAT(hierarchical.output, Contains(" on the finest level / ") && Contains(" over all ") &&
                                      Contains(" levels ("));

  const CommandResult version = RunHarap("--version");
  CHECK(version.status == 0);
  CHECK_THAT(version.output, Contains("harap 0."));

  const CommandResult solvers = RunHarap("list solvers");
  REQUIRE(solvers.status == 0);
  CHECK_THAT(solvers.output, Contains("cholmod") && Contains("solver.small_systems"));
  CHECK_THAT(solvers.output, !Contains("spokes_and_rims") && !Contains("optimizer.tolerance"));
  CHECK_THAT(RunHarap("list energy").output, Contains("spokes_and_rims") && !Contains("cholmod"));
  const CommandResult unknown = RunHarap("list solverz");
  CHECK(unknown.status == 1);
  CHECK_THAT(unknown.output, Contains("solverz") && Contains("optimizers, energies, solvers, "
                                                             "hierarchies, upsamplers"));
  fs::remove_all(dir);
}

TEST_CASE("phases: optimizers announce them through the context, the display renders them",
          "[experiments][cli]") {
  testing::TestSetup setup(
      "[optimizer]\ntype = \"hierarchical\"\n[hierarchy]\nmin_vertices = 30\n");
  Scenario scenario;
  scenario.mesh = testing::Grid(16, 16);
  ScenarioHandle corner{"corner", {0, 1}, {}, {}, {}};
  corner.targets = scenario.mesh.vertices(corner.vertices, Eigen::all);
  corner.targets(1, 2) += 0.2;
  scenario.handles = {corner};
  DeformationProblem problem;
  problem.mesh = &scenario.mesh;
  problem.constraints = scenario.MergedConstraints();
  std::mutex mutex;
  std::vector<std::string> phases;
  Context context;
  context.phase_callback = [&](std::string_view phase, double) {
    const std::lock_guard lock(mutex);
    phases.emplace_back(phase);
  };
  setup.MakeOptimizer()->Optimize(problem, setup.factory, context);
  INFO(fmt::format("{}", fmt::join(phases, "; ")));
  REQUIRE_FALSE(phases.empty());
  // Level 0's setup starts on the background thread before the hierarchy is built (it needs
  // none), so its phases may come first; the coarse levels' come after the hierarchy's.
  const auto hierarchy = std::find(phases.begin(), phases.end(), "building the hierarchy");
  REQUIRE(hierarchy != phases.end());
  for (auto it = phases.begin(); it != hierarchy; ++it) {
    CHECK(it->find("level 0") != std::string::npos);
  }
  for (const char* phase :
       {"precomputing level 0", "factoring level 0", "precomputing level 1", "factoring level 1"}) {
    CHECK(std::find(phases.begin(), phases.end(), phase) != phases.end());
  }

  // Rendering, piped: a line per phase that lasts, iterations with their numbers.
  std::FILE* file = std::tmpfile();
  REQUIRE(file);
  {
    ProgressOptions options;
    options.terminal = false;
    options.show_after = 0.02;
    options.line_interval = 0.05;
    ProgressDisplay display(file, options);
    display.Phase("factoring level 0");
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
    IterationSummary summary;
    summary.level = 0;
    summary.iteration = 7;
    summary.energy = 1.5;
    display.Iteration(summary);
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
    display.Finish();
  }
  std::rewind(file);
  std::string text;
  char buffer[4096];
  while (size_t n = std::fread(buffer, 1, sizeof buffer, file)) text.append(buffer, n);
  std::fclose(file);
  INFO(text);
  CHECK_THAT(text, Contains("factoring level 0 ("));
  CHECK_THAT(text, Contains("solving level 0: iteration 7, energy 1.500000e+00"));
  CHECK_THAT(text, !Contains("\r"));

  // The loading phase says what loading will do.
  const fs::path scenarios = TempDir("loading");
  std::ofstream(scenarios / "tet.toml")
      << "mesh = { tetrahedralize = { builtin = \"cylinder\" } }\n";
  std::ofstream(scenarios / "refined.toml") << "mesh = \"a.obj\"\nrefine = 2\n";
  std::ofstream(scenarios / "broken.toml") << "mesh = [\n";
  CHECK(ScenarioLoadingPhase(scenarios / "tet.toml") ==
        "reading the scenario, tetrahedralizing its mesh (TetGen)");
  CHECK(ScenarioLoadingPhase(scenarios / "refined.toml") ==
        "reading the scenario, reading its mesh with refine = 2");
  CHECK(ScenarioLoadingPhase(scenarios / "broken.toml") == "reading the scenario and its mesh");
  fs::remove_all(scenarios);

  // --quiet: nothing at all on stderr or stdout.
  const fs::path dir = TempDir("quiet");
  const CommandResult quiet = RunHarap(fmt::format("deform {} -q", StripScenario(dir).string()));
  CHECK(quiet.status == 0);
  CHECK(quiet.output.empty());
  fs::remove_all(dir);
}

TEST_CASE(
    "harap report: setup installs what report.py imports, fallback pictures fill their "
    "panels",
    "[experiments][cli][report]") {
  const fs::path dir = TempDir("render");
  // The check runs in the interpreter `harap report` uses.
  std::ofstream(dir / "check.py") << R"PY(
import ast, sys
source = sys.argv[1]
tree = ast.parse(open(source + "/experiments/scripts/report.py").read())
modules = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import)
           for a in n.names}
modules |= {n.module.split(".")[0] for n in ast.walk(tree)
            if isinstance(n, ast.ImportFrom) and n.module}
debian = {"matplotlib": "python3-matplotlib", "mpl_toolkits": "python3-matplotlib",
          "numpy": "python3-numpy", "vtk": None}  # vtk: optional (pictures fall back)
setup = open(source + "/.ci/setup").read()
for module in sorted(modules - set(sys.stdlib_module_names)):
    if module not in debian:
        sys.exit(f"report.py imports {module}: add its Debian package to .ci/setup and here")
    if debian[module] and debian[module] not in setup:
        sys.exit(f"{debian[module]} (for report.py's {module}) is missing from .ci/setup")
try:
    import matplotlib, numpy as np
except ImportError:
    print("SKIP: no matplotlib in this interpreter")
    sys.exit(0)
sys.path.insert(0, source + "/experiments/scripts")
import report
# A 2 x 1 sheet, and the same sheet with its far end lifted: the shared frame must fit both.
nx, ny = 21, 11
x, y = np.meshgrid(np.linspace(0, 2, nx), np.linspace(0, 1, ny))
rest = np.stack([x.ravel(), y.ravel(), np.zeros(nx * ny)], axis=1)
bent = rest.copy()
bent[:, 2] = 0.3 * np.maximum(rest[:, 0] - 1.0, 0) ** 2
quads = [(j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i)
         for j in range(ny - 1) for i in range(nx - 1)]
triangles = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
labels = np.zeros(nx * ny, dtype=int)
labels[rest[:, 0] < 0.1] = 1
images = report.render_matplotlib([(rest, triangles, labels), (bent, triangles, labels)], 300)
low, high = np.array([1.0, 1.0]), np.array([0.0, 0.0])
for image in images:
    ink = (image < 245).any(axis=2)
    rows, cols = np.where(ink.any(axis=1))[0], np.where(ink.any(axis=0))[0]
    size = np.array(image.shape[:2], dtype=float)
    low = np.minimum(low, [rows[0] / size[0], cols[0] / size[1]])
    high = np.maximum(high, [(rows[-1] + 1) / size[0], (cols[-1] + 1) / size[1]])
print("covered", high - low)
if ((high - low) < 0.85).any():
    sys.exit(f"the meshes cover only {high - low} of the panel (rows, columns)")
)PY";
  const CommandResult check =
      testing::RunCommand(fmt::format("/usr/bin/python3 {} {}", (dir / "check.py").string(),
                                      ::harap::testing::SourceDir().string()));
  INFO(check.output);
  CHECK(check.status == 0);
  if (check.output.find("SKIP") != std::string::npos) WARN(check.output);
  fs::remove_all(dir);
}

// Starts harap with `arguments`, its stderr on a pipe; returns the pid and the pipe's read end.
std::pair<pid_t, int> SpawnHarap(const std::vector<std::string>& arguments) {
  int pipe_ends[2];
  REQUIRE(pipe(pipe_ends) == 0);
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    dup2(pipe_ends[1], STDERR_FILENO);
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, STDOUT_FILENO);
    close(pipe_ends[0]);
    std::vector<char*> argv;
    std::string executable = ::harap::testing::HarapExecutable();
    argv.push_back(executable.data());
    std::vector<std::string> copy = arguments;
    for (auto& argument : copy) argv.push_back(argument.data());
    argv.push_back(nullptr);
    execv(executable.c_str(), argv.data());
    _exit(127);
  }
  close(pipe_ends[1]);
  return {pid, pipe_ends[0]};
}

// Reads the child's stderr until `text` appears (true) or `seconds` pass / the pipe closes.
bool WaitForOutput(int fd, const std::string& text, double seconds, std::string& output) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (output.find(text) == std::string::npos) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd poll_fd{fd, POLLIN, 0};
    if (poll(&poll_fd, 1, static_cast<int>(left.count())) <= 0) return false;
    char buffer[4096];
    const ssize_t n = read(fd, buffer, sizeof buffer);
    if (n <= 0) return false;
    output.append(buffer, static_cast<size_t>(n));
  }
  return true;
}

// Waits for the child up to `seconds`; kills it if it does not end. Returns the wait status.
int WaitForExit(pid_t pid, double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  int status = 0;
  while (waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      FAIL("harap did not end after SIGINT");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return status;
}

TEST_CASE("Ctrl-C stops harap deform at the next iteration and still writes its results",
          "[experiments][cli][interrupt]") {
  const fs::path dir = TempDir("interrupt");
  // Slow on purpose: tolerance 0 never converges, so only the iteration cap or Ctrl-C ends it.
  std::ofstream(dir / "slow.toml")
      << "mesh = { builtin = \"cylinder\", vertices = 20000 }\n[[handle]]\n"
         "select.slab = { axis = \"z\", from = 0.0, to = 0.05 }\n[[handle]]\n"
         "select.slab = { axis = \"z\", from = 0.95, to = 1.0 }\ntranslate = [0.3, 0.0, 0.0]\n";
  const std::vector<std::string> arguments = {"deform",
                                              (dir / "slow.toml").string(),
                                              "--tolerance",
                                              "0",
                                              "--max-iterations",
                                              "1000000",
                                              "--threads",
                                              "1",
                                              "--out",
                                              (dir / "out.ply").string(),
                                              "--report",
                                              (dir / "report.json").string()};

  SECTION("one Ctrl-C: stops, writes the report (status interrupted) and the mesh so far") {
    auto [pid, fd] = SpawnHarap(arguments);
    std::string output;
    // Piped progress: a line once the iterations have run for a second.
    const bool iterating = WaitForOutput(fd, "iteration", 60.0, output);
    INFO(output);
    if (!iterating) kill(pid, SIGKILL);
    REQUIRE(iterating);
    REQUIRE(kill(pid, SIGINT) == 0);
    const int status = WaitForExit(pid, 30.0);
    WaitForOutput(fd, "never printed", 1.0, output);
    close(fd);
    INFO(output);
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 130);
    CHECK_THAT(output, Contains("interrupted"));
    const auto report = ReadJson(dir / "report.json");
    CHECK(report["status"] == "interrupted");
    CHECK(report["iterations"].get<int>() > 0);
    CHECK_FALSE(report["converged"].get<bool>());
    const Mesh out = ReadMesh(dir / "out.ply");
    CHECK(out.num_vertices() == report["mesh"]["vertices"].get<Index>());
    CHECK(out.vertices.allFinite());
  }

  SECTION("a second Ctrl-C ends it at once, without results") {
    auto [pid, fd] = SpawnHarap(arguments);
    std::string output;
    const bool iterating = WaitForOutput(fd, "iteration", 60.0, output);
    if (!iterating) kill(pid, SIGKILL);
    REQUIRE(iterating);
    kill(pid, SIGINT);
    kill(pid, SIGINT);
    const int status = WaitForExit(pid, 30.0);
    close(fd);
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 130);
  }
  fs::remove_all(dir);
}

TEST_CASE("the summary's timings say when the phases overlap", "[experiments][cli]") {
  PhaseTimings sequential{
      .hierarchy = 0.1, .precompute = 0.8, .constrain = 2.8, .solve = 2.1, .total = 5.8};
  CHECK(TimingsLine(sequential) ==
        "hierarchy 0.100 | precompute 0.800 | constrain 2.800 | solve 2.100 | total 5.800");
  // Measured with overlap_setup on a 300K-vertex cylinder: 13.8 s of phases in 8.0 s.
  PhaseTimings overlapped{
      .hierarchy = 0.1, .precompute = 2.3, .constrain = 7.9, .solve = 3.5, .total = 8.0};
  CHECK_THAT(TimingsLine(overlapped), Contains("total 8.000 (phases overlap"));
}

TEST_CASE("harap deform names the scenario's stiffness regions in its summary",
          "[experiments][cli][stiffness]") {
  const fs::path dir = TempDir("stiffness");
  const fs::path scenario = dir / "stiff.toml";
  std::ofstream(scenario) << R"(mesh = { builtin = "cylinder", vertices = 800 }
[[handle]]
select.slab = { axis = "z", from = 0.0, to = 0.05 }
[[handle]]
select.slab = { axis = "z", from = 0.95, to = 1.0 }
translate = [0.2, 0.0, 0.0]
[[stiffness]]
name = "middle"
select.slab = { axis = "z", from = 0.4, to = 0.6 }
factor = 10
)";
  const CommandResult run = RunHarap(fmt::format("deform {}", scenario.string()));
  INFO(run.output);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.output, Contains("stiffness   middle: factor 10 on") && Contains("slab z"));
  fs::remove_all(dir);
}

TEST_CASE("huge pages for malloc: GLIBC_TUNABLES gains glibc.malloc.hugetlb=1 only where it helps",
          "[experiments][cli]") {
  CHECK(TunableValue("", "glibc.malloc.hugetlb") == std::nullopt);
  CHECK(TunableValue("glibc.malloc.hugetlb=0", "glibc.malloc.hugetlb") == "0");
  CHECK(TunableValue("glibc.malloc.arena_max=1:glibc.malloc.hugetlb=2", "glibc.malloc.hugetlb") ==
        "2");
  CHECK(TunableValue("glibc.malloc.hugetlbx=1", "glibc.malloc.hugetlb") == std::nullopt);
  CHECK(TunablesWithHugePages("", "madvise", true) == "glibc.malloc.hugetlb=1");
  CHECK(TunablesWithHugePages("glibc.malloc.arena_max=1", "madvise", true) ==
        "glibc.malloc.arena_max=1:glibc.malloc.hugetlb=1");
  // The user's own value wins, 0 (off) included.
  CHECK(TunablesWithHugePages("glibc.malloc.hugetlb=0", "madvise", true) == std::nullopt);
  // Nothing to gain: the kernel gives huge pages to everything, or to nothing; or an old glibc.
  CHECK(TunablesWithHugePages("", "always", true) == std::nullopt);
  CHECK(TunablesWithHugePages("", "never", true) == std::nullopt);
  CHECK(TunablesWithHugePages("", "", true) == std::nullopt);
  CHECK(TunablesWithHugePages("", "madvise", false) == std::nullopt);
}

TEST_CASE("harap restarts itself with huge pages for malloc and reports how memory was backed",
          "[experiments][cli]") {
  const fs::path dir = TempDir("huge-pages");
  const fs::path scenario = StripScenario(dir);
  const std::string mode = TransparentHugePageMode();
  auto backing = [&](const std::string& environment) {
    const fs::path report_file = dir / "report.json";
    const CommandResult run = testing::RunCommand(fmt::format(
        "env -u GLIBC_TUNABLES -u HARAP_REQUESTED_HUGE_PAGES {} {} "
        "deform {} --report {}",
        environment, testing::HarapExecutable(), scenario.string(), report_file.string()));
    INFO(run.output);
    REQUIRE(run.status == 0);
    const std::string reported = ReadJson(report_file)["huge_pages"];
    CHECK_THAT(run.output, Contains(fmt::format("(huge pages: {})", reported)));
    return reported;
  };
  if (mode != "madvise" || !MallocHasHugePageTunable()) {
    // The kernel gives huge pages to everything or to nothing, or glibc has no tunable: nothing
    // to restart for.
    WARN("THP mode '" << mode << "': the restart is not exercised on this machine");
    CHECK(backing("") == (mode == "always" ? "always" : "off"));
  } else {
    // Reported from the environment the process started with: only a restart makes it "malloc".
    CHECK(backing("") == "malloc");
    // A value the user set wins; the marker of an earlier request stops a second one.
    CHECK(backing("GLIBC_TUNABLES=glibc.malloc.hugetlb=0") == "off");
    CHECK(backing("HARAP_REQUESTED_HUGE_PAGES=1") == "off");
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace harap
