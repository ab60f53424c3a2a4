// SPDX-License-Identifier: MIT
// A new user's walkthroughs: `harap handles` before solving, absolute coordinates,
// per-vertex targets, the deformation benchmark's .sel/.def files, refining a non-manifold mesh.
// Small generated meshes only.
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "tests/support/run_harap.h"
#include "tests/support/temp_folder.h"
#include "tests/support/test_files.h"

namespace {

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using harap::testing::BarOff;
using harap::testing::ReadText;
using harap::testing::RunHarap;
using harap::testing::TempFolder;

TEST_CASE("harap handles: box, per-handle count, centroid and motion; coloured PLY",
          "[experiments][handles]") {
  TempFolder folder("ux-handles");
  folder.Write("bar.off", BarOff(/*caps=*/true));
  const std::string scenario = folder.Write(
      "bar.toml",
      "mesh = \"bar.off\"\n"
      "[[handle]]\nname = \"left\"\nselect.slab = { axis = \"x\", from = 0, to = 0.1 }\n"
      "[[handle]]\nname = \"right\"\nunits = \"absolute\"\n"
      "select.slab = { axis = \"x\", from = 2.5, to = 3.5 }\n"
      "rotate = { axis = [1, 0, 0], degrees = 30 }\ntranslate = [0, 0, 0.5]\n");
  const std::string ply = (folder.dir / "handles.ply").string();
  const auto result = RunHarap(fmt::format("handles {} --out {}", scenario, ply));
  INFO(result.output);
  REQUIRE(result.status == 0);
  CHECK_THAT(result.output, Contains("bounding box x in [0, 3], y in [0, 1], z in [0, 1]"));
  CHECK_THAT(result.output, Contains("'left' (blue in the PLY)"));
  CHECK_THAT(result.output, Contains("'right' (red in the PLY)"));
  CHECK_THAT(result.output, Contains("vertices  4"));
  CHECK_THAT(result.output, Contains("centroid  (3, 0.5, 0.5) -> (3, 0.5, 1)"));
  CHECK_THAT(result.output, Contains("rotate 30° about (1, 0, 0)"));
  CHECK_THAT(result.output, Contains("translate (0, 0, 0.5)"));
  CHECK_THAT(result.output, Contains("absolute coordinates"));
  CHECK_THAT(result.output, Contains("free        8 of 16 vertices"));
  CHECK_THAT(result.output, !Contains("iterations"));  // nothing solved
  // The PLY: 16 vertices with colours, handle colours where the handles are, grey elsewhere.
  const std::string bytes = ReadText(ply);
  REQUIRE(bytes.find("property uchar red") != std::string::npos);
  const size_t body = bytes.find("end_header\n") + 11;
  auto color = [&](int v) {
    const size_t at = body + static_cast<size_t>(v) * (3 * 8 + 3) + 24;
    return fmt::format("{} {} {}", static_cast<int>(static_cast<unsigned char>(bytes[at])),
                       static_cast<int>(static_cast<unsigned char>(bytes[at + 1])),
                       static_cast<int>(static_cast<unsigned char>(bytes[at + 2])));
  };
  CHECK(color(0) == "31 119 180");   // left: blue
  CHECK(color(15) == "214 39 40");   // right: red
  CHECK(color(6) == "190 190 190");  // free: grey
  // A non-PLY name is refused before anything is written.
  const auto wrong =
      RunHarap(fmt::format("handles {} --out {}", scenario, (folder.dir / "handles.obj").string()));
  CHECK(wrong.status == 1);
  CHECK_THAT(wrong.output, Contains("ending in .ply"));
  CHECK_FALSE(fs::exists(folder.dir / "handles.obj"));
  // A selection in the wrong units: the error says which units and gives the box.
  const std::string miss =
      folder.Write("miss.toml",
                   "mesh = \"bar.off\"\n[[handle]]\nselect.slab = { axis = \"x\", from = 2.5, "
                   "to = 3.0 }\n");
  const auto missed = RunHarap("handles " + miss);
  CHECK(missed.status == 1);
  CHECK_THAT(missed.output, Contains("fractions of the bounding box x in [0, 3]"));
  CHECK_THAT(missed.output, Contains("units = \"absolute\""));
}

TEST_CASE("deformation benchmark files and per-vertex targets: handles, then deform",
          "[experiments][handles]") {
  TempFolder folder("ux-benchmark");
  folder.Write("bar.off", BarOff(/*caps=*/true));
  std::string labels;
  for (int v = 0; v < 16; ++v) labels += v < 4 ? "0\n" : v < 12 ? "1\n" : "2\n";
  folder.Write("bar.sel", labels);
  folder.Write("bar.def", "1 0 0 0\n0 1 0 0\n0 0 1 1.5\n0 0 0 1\n");  // lift by 1.5
  const std::string scenario = folder.Write(
      "bar.toml", "mesh = \"bar.off\"\nselection = \"bar.sel\"\ndeformation = \"bar.def\"\n");
  const auto shown = RunHarap("handles " + scenario);
  INFO(shown.output);
  REQUIRE(shown.status == 0);
  CHECK_THAT(shown.output, Contains("'fixed'"));
  CHECK_THAT(shown.output, Contains("label 2 of bar.sel"));
  CHECK_THAT(shown.output, Contains("4x4 transform from bar.def"));
  CHECK_THAT(shown.output, Contains("centroid  (3, 0.5, 0.5) -> (3, 0.5, 2)"));
  const auto solved =
      RunHarap(fmt::format("deform {} --out {}", scenario, (folder.dir / "bar-out.ply").string()));
  INFO(solved.output);
  CHECK(solved.status == 0);

  // Per-vertex targets: the right end's four vertices, given one by one.
  folder.Write("moves.txt", "# index x y z\n12 3 0 1\n13 3 1 1\n14 3 1 2\n15 3 0 2\n");
  const std::string targets =
      folder.Write("targets.toml",
                   "mesh = \"bar.off\"\n"
                   "[[handle]]\nname = \"left\"\nselect.indices = [0, 1, 2, 3]\n"
                   "[[handle]]\nname = \"lifted\"\ntarget_file = \"moves.txt\"\n");
  const auto listed = RunHarap("handles " + targets);
  INFO(listed.output);
  CHECK(listed.status == 0);
  CHECK_THAT(listed.output, Contains("per-vertex targets from"));
  CHECK_THAT(listed.output, Contains("centroid  (3, 0.5, 0.5) -> (3, 0.5, 1.5)"));
  folder.Write("moves.txt", "12 3 0 1\n13 3 1\n");
  const auto bad = RunHarap("deform " + targets);
  CHECK(bad.status == 1);
  CHECK_THAT(bad.output, Contains("moves.txt:2"));
  CHECK_THAT(bad.output, Contains("4 values"));
}

TEST_CASE("refine = 1 of a non-manifold mesh refines with a note", "[experiments][handles]") {
  TempFolder folder("ux-nonmanifold");
  // Three triangles on the edge (0, 1) and a second fan touching vertex 2.
  folder.Write("book.obj",
               "v 0 0 0\nv 2 0 0\nv 1 1 0\nv 1 -1 0\nv 1 0 1\nv 2 2 0\nv 0 2 0\nv 1 3 0\n"
               "f 1 2 3\nf 2 1 4\nf 1 2 5\nf 3 6 8\nf 3 8 7\n");
  const std::string scenario = folder.Write("book.toml",
                                            "mesh = \"book.obj\"\nrefine = 1\n"
                                            "[[handle]]\nselect.indices = [0]\n");
  const auto result = RunHarap("handles " + scenario);
  INFO(result.output);
  REQUIRE(result.status == 0);
  CHECK_THAT(result.output, Contains("(20 vertices, 20 faces)"));  // 8 + 12 edges, 4 x 5
  CHECK_THAT(result.output, Contains("Loop variant"));
  CHECK_THAT(result.output, Contains("1 non-manifold edge "));
}

TEST_CASE("a mesh or a wrong output name fails before any work, saying what goes where",
          "[experiments][handles]") {
  TempFolder folder("ux-wrong-files");
  folder.Write("bar.off", BarOff(/*caps=*/true));
  const std::string scenario =
      folder.Write("bar.toml",
                   "mesh = \"bar.off\"\n[[handle]]\nselect.slab = { axis = \"x\", from = 0, "
                   "to = 0.1 }\n[[handle]]\nselect.slab = { axis = \"x\", from = 0.9, to = 1 }\n"
                   "translate = [0, 0.2, 0]\n");
  const std::string mesh = (folder.dir / "bar.off").string();
  // Where a scenario is expected (harap drag as harap deform), an experiment config, a --config.
  const auto drag = RunHarap("drag " + mesh);
  CHECK(drag.status == 1);
  CHECK_THAT(drag.output, Contains("is a mesh file, but a scenario (TOML) is expected"));
  const auto run = RunHarap(fmt::format("run {} --out {}", mesh, (folder.dir / "out").string()));
  CHECK(run.status == 1);
  CHECK_THAT(run.output, Contains("this is a mesh file, but harap run takes an experiment config"));
  CHECK_FALSE(fs::exists(folder.dir / "out"));
  // A scenario given to harap run, an experiment config where a scenario is expected.
  const auto run_scenario =
      RunHarap(fmt::format("run {} --out {}", scenario, (folder.dir / "out").string()));
  CHECK(run_scenario.status == 1);
  CHECK_THAT(run_scenario.output, Contains("is a scenario (mesh and [[handle]]), but harap run "
                                           "takes an experiment config") &&
                                      Contains("files = [\"bar.toml\"]") &&
                                      Contains("harap deform " + scenario));
  CHECK_FALSE(fs::exists(folder.dir / "out"));
  const std::string sweep = folder.Write(
      "sweep.toml", "[scenarios]\nfiles = [\"bar.toml\"]\n[[variant]]\nname = \"classic\"\n");
  for (const char* command : {"deform", "handles", "hierarchy", "drag"}) {
    const auto wrong = RunHarap(fmt::format("{} {}", command, sweep));
    INFO(command << ": " << wrong.output);
    CHECK(wrong.status == 1);
    CHECK_THAT(wrong.output, Contains("is an experiment config") &&
                                 Contains("run the config with harap run " + sweep));
  }
  for (const char* command : {"deform", "hierarchy", "drag"}) {
    const auto config = RunHarap(fmt::format("{} {} --config {}", command, scenario, mesh));
    INFO(command << ": " << config.output);
    CHECK(config.status == 1);
    CHECK_THAT(config.output, Contains("--config " + mesh + ": this is a mesh file"));
    CHECK_THAT(config.output, !Contains("TOML syntax error"));
  }
  // Output folders that do not exist: before the mesh is read (handles) or solved (drag).
  const std::string nowhere = (folder.dir / "no-such-folder").string();
  const auto handles = RunHarap(fmt::format("handles {} --out {}/h.ply", scenario, nowhere));
  CHECK(handles.status == 1);
  CHECK_THAT(handles.output, Contains("the folder " + nowhere + " does not exist"));
  CHECK_THAT(handles.output, !Contains("bounding box"));  // nothing was loaded or printed
  const auto report =
      RunHarap(fmt::format("drag {} --frames 2 --report {}/d.json", scenario, nowhere));
  CHECK(report.status == 1);
  CHECK_THAT(report.output, Contains("--report " + nowhere + "/d.json: the folder"));
}

TEST_CASE("harap handles prints a centred mesh's centroids without rounding noise",
          "[experiments][handles]") {
  // The built-in cylinder is centred on the z axis: its ring centroids are x = y = 0 up to
  // rounding (1e-17), which printed as "-2.67985e-17".
  TempFolder folder("ux-centroid");
  const auto result =
      RunHarap("handles " + folder.Write("c.toml", harap::testing::kCylinderBendScenario));
  INFO(result.output);
  REQUIRE(result.status == 0);
  CHECK_THAT(result.output, Contains("centroid  (0, 0, 0.046798) -> (0, 0, 0.046798)"));
  CHECK_THAT(result.output, Contains("through (0, 0, 3.9532) (the handle's centroid)"));
  CHECK_THAT(result.output, !Contains("e-1"));
}

TEST_CASE("harap report without matplotlib says what to install, no traceback",
          "[experiments][handles]") {
  TempFolder folder("ux-no-matplotlib");
  // A Python without its site packages (where Debian's matplotlib lives) stands in for a
  // machine without matplotlib; the run folder needs one finished run.
  const std::string python = folder.Write("python", "#!/bin/sh\nexec /usr/bin/python3 -S \"$@\"\n");
  fs::permissions(python, fs::perms::owner_all);
  folder.Write("c.toml", harap::testing::kCylinderBendScenario);
  const std::string config = folder.Write(
      "sweep.toml", "[scenarios]\nfiles = [\"c.toml\"]\n[[variant]]\nname = \"classic\"\n");
  const std::string out = (folder.dir / "out").string();
  REQUIRE(RunHarap(fmt::format("run {} --out {} -q", config, out)).status == 0);
  const auto report = RunHarap(fmt::format("report {} --python {} --no-render", out, python));
  INFO(report.output);
  CHECK(report.status == 1);
  CHECK_THAT(report.output, Contains("cannot import matplotlib"));
  CHECK_THAT(report.output, Contains("python3-matplotlib"));
  CHECK_THAT(report.output, !Contains("Traceback"));
}

}  // namespace
