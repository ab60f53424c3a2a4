// SPDX-License-Identifier: MIT
// Handle options beyond FORMAT.md (docs/input.md): absolute coordinates (`units`), per-vertex
// targets from a file (`target_file`) and the deformation benchmark's .sel/.def files.
#include <catch2/catch.hpp>
#include <cmath>

#include "framework/error.h"
#include "io/scenario.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_files.h"

namespace harap {
namespace {

using Catch::Matchers::Contains;
using testing::ScratchDir;

// A 4 x 1 grid in the plane z = 0 shifted to x in [10, 14], y in [-1, 0]: absolute coordinates
// and box fractions differ on every axis.
constexpr const char* kGridObj =
    "v 10 -1 0\nv 12 -1 0\nv 14 -1 0\nv 10 0 0\nv 12 0 0\nv 14 0 0\n"
    "f 1 2 5\nf 1 5 4\nf 2 3 6\nf 2 6 5\n";

std::string MessageOf(const std::filesystem::path& file) {
  try {
    LoadScenario(file);
  } catch (const Error& error) {
    return error.what();
  }
  FAIL("no exception for " << file);
  return "";
}

TEST_CASE("scenario units: absolute coordinates for selections, centre and translate",
          "[io][scenario][units]") {
  ScratchDir dir;
  dir.Write("grid.obj", kGridObj);
  const auto file = dir.Write(
      "s.toml",
      "mesh = \"grid.obj\"\n"
      "[[handle]]\nname = \"frac\"\nselect.slab = { axis = \"x\", from = 0.9, to = 1.0 }\n"
      "translate = [0.0, 0.0, 1.0]\n"
      "[[handle]]\nname = \"abs\"\nunits = \"absolute\"\n"
      "select.slab = { axis = \"x\", from = 9.5, to = 10.5 }\n"
      "rotate = { axis = [0, 0, 1], degrees = 90, center = [10, 0, 0] }\n"
      "translate = [0.0, 0.0, 1.0]\n"
      "[[handle]]\nname = \"ball\"\nunits = \"absolute\"\n"
      "select.ball = { center = [12, -0.5, 0], radius = 0.6 }\n");
  const Scenario scenario = LoadScenario(file);
  REQUIRE(scenario.handles.size() == 3);
  CHECK(scenario.box_min == Eigen::Vector3d(10, -1, 0));
  CHECK(scenario.box_max == Eigen::Vector3d(14, 0, 0));
  // Fractions: x >= 0.9 of [10, 14] is x = 14; translate in box diagonals (sqrt(17)).
  const ScenarioHandle& frac = scenario.handles[0];
  CHECK(frac.vertices == std::vector<Index>{2, 5});
  CHECK(frac.targets(0, 2) == Approx(std::sqrt(17.0)));
  CHECK_THAT(frac.selection, Contains("fractions of the bounding box"));
  // Absolute: x in [9.5, 10.5] is x = 10; the centre (10, 0, 0) and translate (0, 0, 1) as written.
  const ScenarioHandle& abs = scenario.handles[1];
  REQUIRE(abs.vertices == std::vector<Index>{0, 3});
  // Vertex 0 (10, -1, 0) turned 90 degrees about z through (10, 0, 0) is (11, 0, 0), then +z.
  CHECK(abs.targets(0, 0) == Approx(11.0));
  CHECK(abs.targets(0, 1) == Approx(0.0).margin(1e-12));
  CHECK(abs.targets(0, 2) == Approx(1.0));
  CHECK_THAT(abs.selection, Contains("absolute coordinates"));
  CHECK_THAT(abs.motion, Contains("rotate 90"));
  CHECK_THAT(abs.motion, Contains("translate (0, 0, 1)"));
  // Ball of radius 0.6 (mesh units) about (12, -0.5): (12, -1) and (12, 0) at distance 0.5.
  CHECK(scenario.handles[2].vertices == std::vector<Index>{1, 4});
}

TEST_CASE("scenario units: a ball in absolute coordinates and the top-level default",
          "[io][scenario][units]") {
  ScratchDir dir;
  dir.Write("grid.obj", kGridObj);
  const auto file = dir.Write("s.toml",
                              "mesh = \"grid.obj\"\nunits = \"absolute\"\n"
                              "[[handle]]\nselect.ball = { center = [12, -1, 0], radius = 0.5 }\n"
                              "[[handle]]\nunits = \"fractions\"\n"
                              "select.ball = { center = [0.5, 0.0, 0.0], radius = 0.1 }\n");
  const Scenario scenario = LoadScenario(file);
  CHECK(scenario.handles[0].vertices == std::vector<Index>{1});
  CHECK(scenario.handles[1].vertices == std::vector<Index>{1});  // (12, -1): fractions (0.5, 0)
}

TEST_CASE("scenario units: messages say the kind of selection and give the box",
          "[io][scenario][units]") {
  ScratchDir dir;
  dir.Write("grid.obj", kGridObj);
  // Coordinates written as fractions (the default): matches nothing, the message says so.
  std::string message =
      MessageOf(dir.Write("a.toml",
                          "mesh = \"grid.obj\"\n[[handle]]\nname = \"end\"\n"
                          "select.slab = { axis = \"x\", from = 13.5, to = 14.0 }\n"));
  CHECK_THAT(message, Contains("a.toml:4"));
  CHECK_THAT(message, Contains("handle 'end'"));
  CHECK_THAT(message, Contains("slab x in [13.5, 14]"));
  CHECK_THAT(message, Contains("fractions of the bounding box x in [10, 14], y in [-1, 0]"));
  CHECK_THAT(message, Contains("matches no vertex"));
  CHECK_THAT(message, Contains("units = \"absolute\""));
  // Absolute coordinates that miss the mesh: the message gives the box.
  message = MessageOf(dir.Write("b.toml",
                                "mesh = \"grid.obj\"\n[[handle]]\nunits = \"absolute\"\n"
                                "select.slab = { axis = \"x\", from = 0.9, to = 1.0 }\n"));
  CHECK_THAT(message, Contains("absolute coordinates"));
  CHECK_THAT(message, Contains("x in [10, 14]"));
  CHECK_THAT(message, Contains("matches no vertex"));
  // `units` in the selection table: a hint where it belongs; a bad value lists the valid ones.
  message = MessageOf(
      dir.Write("c.toml",
                "mesh = \"grid.obj\"\n[[handle]]\n"
                "select.slab = { axis = \"x\", from = 9, to = 11, units = \"absolute\" }\n"));
  CHECK_THAT(message, Contains("c.toml:3"));
  CHECK_THAT(message, Contains("key of the [[handle]]"));
  message = MessageOf(dir.Write(
      "d.toml", "mesh = \"grid.obj\"\n[[handle]]\nunits = \"meters\"\nselect.indices = [0]\n"));
  CHECK_THAT(message, Contains("d.toml:3"));
  CHECK_THAT(message, Contains("\"fractions\""));
  CHECK_THAT(message, Contains("\"absolute\""));
}

TEST_CASE("scenario target_file: per-vertex targets, errors name file and line",
          "[io][scenario][targets]") {
  ScratchDir dir;
  dir.Write("grid.obj", kGridObj);
  dir.Write("moves.txt", "# index x y z\n5 14 0 2\n\n0 10 -1 0  # held\n3 9.5 0.5 0\n");
  const Scenario scenario =
      LoadScenario(dir.Write("s.toml",
                             "mesh = \"grid.obj\"\n[[handle]]\nname = \"moves\"\n"
                             "target_file = \"moves.txt\"\n"));
  REQUIRE(scenario.handles.size() == 1);
  const ScenarioHandle& handle = scenario.handles[0];
  REQUIRE(handle.vertices == std::vector<Index>{0, 3, 5});  // ascending
  CHECK(handle.targets.row(0) == Eigen::RowVector3d(10, -1, 0));
  CHECK(handle.targets.row(1) == Eigen::RowVector3d(9.5, 0.5, 0));
  CHECK(handle.targets.row(2) == Eigen::RowVector3d(14, 0, 2));
  CHECK_THAT(handle.motion, Contains("moves.txt"));
  CHECK_FALSE(scenario.mesh.planar);  // a target leaves the plane z = 0

  auto error_for = [&](const std::string& content) {
    dir.Write("bad.txt", content);
    return MessageOf(dir.Write("bad.toml",
                               "mesh = \"grid.obj\"\n[[handle]]\nname = \"t\"\n"
                               "target_file = \"bad.txt\"\n"));
  };
  std::string message = error_for("0 1 2 3\n1 1 2\n");
  CHECK_THAT(message, Contains("bad.toml:4"));
  CHECK_THAT(message, Contains("handle 't'"));
  CHECK_THAT(message, Contains("bad.txt:2"));
  CHECK_THAT(message, Contains("4 values"));
  message = error_for("0 1 2 3\n\n1 1 x 3\n");
  CHECK_THAT(message, Contains("bad.txt:3"));
  CHECK_THAT(message, Contains("'x' is not a number"));
  message = error_for("6 1 2 3\n");
  CHECK_THAT(message, Contains("bad.txt:1"));
  CHECK_THAT(message, Contains("index 6 out of range"));
  message = error_for("2 1 2 3\n2 1 2 3\n");
  CHECK_THAT(message, Contains("bad.txt:2"));
  CHECK_THAT(message, Contains("vertex 2 has a target already (line 1)"));
  message = error_for("1 1 inf 3\n");
  CHECK_THAT(message, Contains("not a finite number"));
  message = error_for("# nothing\n");
  CHECK_THAT(message, Contains("no 'index x y z' line"));
  message = MessageOf(dir.Write("both.toml",
                                "mesh = \"grid.obj\"\n[[handle]]\n"
                                "target_file = \"moves.txt\"\n"
                                "select.indices = [0]\n"));
  CHECK_THAT(message, Contains("both.toml:4"));
  CHECK_THAT(message, Contains("remove 'select'"));
  message = MessageOf(dir.Write("missing.toml",
                                "mesh = \"grid.obj\"\n[[handle]]\n"
                                "target_file = \"nowhere.txt\"\n"));
  CHECK_THAT(message, Contains("missing.toml:3"));
  CHECK_THAT(message, Contains("nowhere.txt not found"));
}

// A generated example of the deformation benchmark's format (Botsch & Sorkine 2008): a bar as
// OFF, one label per vertex, the handle's transform.
void WriteBenchmarkBar(const ScratchDir& dir) {
  // Rings at x = 0, 1, 2, 3 (16 vertices), the sides triangulated, the ends open.
  dir.Write("bar.off", testing::BarOff(/*caps=*/false));
  // Ring 0 fixed, rings 1 and 2 free, ring 3 the handle.
  std::string labels = "# 0 fixed, 1 free, 2 handle\n";
  for (int v = 0; v < 16; ++v) labels += v < 4 ? "0\n" : v < 12 ? "1\n" : "2\n";
  dir.Write("bar.sel", labels);
  // A quarter turn about z, then a shift by (0, 0, 0.5).
  dir.Write("bar.def", "0 -1 0 0\n1 0 0 0\n0 0 1 0.5\n0 0 0 1\n");
}

TEST_CASE("scenario: the deformation benchmark's .sel and .def files", "[io][scenario][sel]") {
  ScratchDir dir;
  WriteBenchmarkBar(dir);
  const Scenario scenario = LoadScenario(dir.Write(
      "bar.toml", "mesh = \"bar.off\"\nselection = \"bar.sel\"\ndeformation = \"bar.def\"\n"));
  REQUIRE(scenario.handles.size() == 2);
  const ScenarioHandle& fixed = scenario.handles[0];
  const ScenarioHandle& handle = scenario.handles[1];
  CHECK(fixed.name == "fixed");
  CHECK(fixed.vertices == std::vector<Index>{0, 1, 2, 3});
  CHECK(fixed.targets == scenario.mesh.vertices.topRows(4));
  CHECK(handle.name == "handle");
  REQUIRE(handle.vertices == std::vector<Index>{12, 13, 14, 15});
  // Vertex 13 = (3, 1, 0): rotated (-1, 3, 0), shifted (-1, 3, 0.5).
  CHECK(handle.targets.row(1) == Eigen::RowVector3d(-1, 3, 0.5));
  CHECK_THAT(handle.motion, Contains("bar.def"));
  CHECK_THAT(handle.selection, Contains("label 2 of bar.sel"));

  auto message = [&](const std::string& sel, const std::string& def,
                     const std::string& keys = "selection = \"x.sel\"\ndeformation = \"x.def\"\n") {
    dir.Write("x.sel", sel);
    dir.Write("x.def", def);
    return MessageOf(dir.Write("x.toml", "mesh = \"bar.off\"\n" + keys));
  };
  const std::string good_def = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  std::string labels;
  for (int v = 0; v < 16; ++v) labels += v < 15 ? "1\n" : "2\n";
  CHECK_THAT(message("0\n1\n2\n", good_def), Contains("has 3 labels, but the mesh has 16"));
  CHECK_THAT(message("0\n1\n7\n", good_def), Contains("x.sel:3"));
  CHECK_THAT(message("0\n1\n7\n", good_def), Contains("'7' is not a vertex label"));
  CHECK_THAT(message(std::string(16 * 2, '1').replace(1, 1, "\n"), good_def),
             Contains("is not a vertex label"));
  std::string no_handle;
  for (int v = 0; v < 16; ++v) no_handle += "0\n";
  CHECK_THAT(message(no_handle, good_def), Contains("no vertex as handle (label 2)"));
  CHECK_THAT(message(labels, "1 0 0 0\n0 1 0 0\n"), Contains("ends after 8 of the 16 numbers"));
  CHECK_THAT(message(labels, "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n5\n"), Contains("x.def:5"));
  CHECK_THAT(message(labels, "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n"),
             Contains("not an affine transform"));
  CHECK_THAT(message(labels, "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "selection = \"x.sel\"\n"),
             Contains("come together"));
  // Labels with no 0 give only the moving handle; the rest is free.
  const Scenario only_handle = LoadScenario(
      dir.Write("y.toml", "mesh = \"bar.off\"\nselection = \"x.sel\"\ndeformation = \"x.def\"\n"));
  REQUIRE(only_handle.handles.size() == 1);
  CHECK(only_handle.handles[0].vertices == std::vector<Index>{15});
}

TEST_CASE("scenario weight: soft handles carry their weight into the constraints",
          "[io][scenario][soft]") {
  ScratchDir dir;
  dir.Write("grid.obj", kGridObj);
  const auto file = dir.Write("s.toml",
                              "mesh = \"grid.obj\"\n"
                              "[[handle]]\nselect.slab = { axis = \"x\", from = 0.0, to = 0.1 }\n"
                              "[[handle]]\nselect.slab = { axis = \"x\", from = 0.9, to = 1.0 }\n"
                              "translate = [0.0, 0.0, 0.5]\nweight = 2.5\n");
  const Scenario scenario = LoadScenario(file);
  REQUIRE(scenario.handles.size() == 2);
  CHECK(scenario.handles[0].weight == Constraints::kHardWeight);
  CHECK(scenario.handles[1].weight == 2.5);
  const Constraints merged = scenario.MergedConstraints();
  REQUIRE(merged.weights.size() == merged.indices.size());
  for (size_t k = 0; k < merged.indices.size(); ++k) {
    CHECK(merged.is_hard(k) == (merged.indices[k] == 0 || merged.indices[k] == 3));
  }
  CHECK(merged.SoftPart().indices == std::vector<Index>{2, 5});
  CHECK(merged.HardPart().indices == std::vector<Index>{0, 3});
  // Without any weight the constraints stay as they were: all hard, no weights.
  const auto hard = dir.Write("h.toml",
                              "mesh = \"grid.obj\"\n"
                              "[[handle]]\nselect.slab = { axis = \"x\", from = 0.0, to = 0.1 }\n");
  CHECK(LoadScenario(hard).MergedConstraints().weights.empty());
  for (const char* bad : {"0", "-1.0", "nan", "inf", "\"heavy\""}) {
    DYNAMIC_SECTION("weight = " << bad) {
      const auto b = dir.Write("b.toml", std::string("mesh = \"grid.obj\"\n[[handle]]\n"
                                                     "select.slab = { axis = \"x\", from = 0.0, "
                                                     "to = 0.1 }\nweight = ") +
                                             bad + "\n");
      const std::string message = MessageOf(b);
      CHECK_THAT(message, Contains("weight"));
      CHECK_THAT(message, Contains("b.toml:4"));
    }
  }
}
}  // namespace
}  // namespace harap

namespace harap {
namespace {

TEST_CASE("scenario [[stiffness]]: regions select like handles, factors multiply per vertex",
          "[io][scenario][stiffness]") {
  testing::ScratchDir dir;
  dir.Write("grid.obj", kGridObj);
  const auto file =
      dir.Write("s.toml",
                "mesh = \"grid.obj\"\n"
                "[[handle]]\nselect.indices = [0, 3]\n"
                "[[stiffness]]\nname = \"right\"\nselect.slab = { axis = \"x\", from = 0.4, "
                "to = 1.0 }\nfactor = 10\n"
                "[[stiffness]]\nunits = \"absolute\"\nselect.indices = [2]\nfactor = 0.5\n");
  const Scenario scenario = LoadScenario(file);
  REQUIRE(scenario.stiffness.size() == 2);
  CHECK(scenario.stiffness[0].name == "right");
  CHECK(scenario.stiffness[0].vertices == std::vector<Index>{1, 2, 4, 5});
  CHECK(scenario.stiffness[1].name == "stiffness 2");
  // Vertex factors 1, 10, 5, 1, 10, 10; each face the mean of its corners.
  const std::vector<double> stiffness = scenario.ElementStiffness();
  REQUIRE(stiffness.size() == 4);
  CHECK(stiffness[0] == Approx(21.0 / 3.0));  // f 1 2 5
  CHECK(stiffness[1] == Approx(12.0 / 3.0));  // f 1 5 4
  CHECK(stiffness[2] == Approx(25.0 / 3.0));  // f 2 3 6
  CHECK(stiffness[3] == Approx(30.0 / 3.0));  // f 2 6 5
}

TEST_CASE("scenario [[stiffness]]: bad regions name the region and the place",
          "[io][scenario][stiffness]") {
  testing::ScratchDir dir;
  dir.Write("grid.obj", kGridObj);
  const auto with = [&](const std::string& region) {
    return MessageOf(dir.Write(
        "s.toml",
        "mesh = \"grid.obj\"\n[[handle]]\nselect.indices = [0]\n[[stiffness]]\n" + region));
  };
  CHECK_THAT(with("select.indices = [1]\nfactor = 0\n"),
             Contains("s.toml:6:10: stiffness 1: 'factor' must be a finite number > 0"));
  CHECK_THAT(with("select.indices = [1]\nfactor = nan\n"),
             Contains("stiffness 1: factor is a non-finite"));
  CHECK_THAT(with("select.indices = [1]\n"), Contains("needs factor = s"));
  CHECK_THAT(with("factor = 2\n"), Contains("needs select"));
  CHECK_THAT(with("select.indices = [1]\nfactor = 2\nweight = 3\n"), Contains("weight"));
  CHECK_THAT(with("select.indices = [99]\nfactor = 2\n"), Contains("index 99 out of range"));
  CHECK_THAT(
      with("name = \"x\"\nselect.slab = { axis = \"z\", from = 0.5, to = 0.6 }\nfactor = 2\n"),
      Contains("stiffness 'x'"));
}

// The grid above as ASCII PLY with a vertex property `k` and a face property `kf`; the last two
// triangles are one quad (fan-triangulated into two triangles that share its value).
constexpr const char* kGridPlyWithFactors =
    "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
    "property float z\nproperty float k\nelement face 3\nproperty list uchar int "
    "vertex_indices\nproperty double kf\nend_header\n"
    "10 -1 0 1\n12 -1 0 2\n14 -1 0 4\n10 0 0 1\n12 0 0 2\n14 0 0 8\n"
    "3 0 1 4 0.5\n3 0 4 3 3\n4 1 2 5 4 10\n";

TEST_CASE("scenario [[stiffness]]: factors from the mesh's PLY vertex or face property",
          "[io][scenario][stiffness]") {
  testing::ScratchDir dir;
  dir.Write("grid.ply", kGridPlyWithFactors);
  const auto load = [&](const std::string& regions) {
    return LoadScenario(dir.Write(
        "s.toml", "mesh = \"grid.ply\"\n[[handle]]\nselect.indices = [0, 3]\n" + regions));
  };
  SECTION("per vertex: each element the mean of its corners', times a selected region's") {
    const Scenario scenario = load(
        "[[stiffness]]\nname = \"painted\"\nattribute = \"k\"\n"
        "[[stiffness]]\nselect.indices = [0]\nfactor = 3\n");
    REQUIRE(scenario.stiffness.size() == 2);
    CHECK(scenario.stiffness[0].attribute == "k");
    CHECK_THAT(scenario.stiffness[0].selection,
               Contains("vertex property 'k'") && Contains("factors 1 to 8"));
    // Vertex factors 1·3, 2, 4, 1, 2, 8 on the triangles (0 1 4) (0 4 3) (1 2 5) (1 5 4).
    const std::vector<double> stiffness = scenario.ElementStiffness();
    REQUIRE(stiffness.size() == 4);
    CHECK(stiffness[0] == Approx(7.0 / 3.0));
    CHECK(stiffness[1] == Approx(6.0 / 3.0));
    CHECK(stiffness[2] == Approx(14.0 / 3.0));
    CHECK(stiffness[3] == Approx(12.0 / 3.0));
  }
  SECTION("per face: a polygon's value on each of its triangles") {
    const Scenario scenario = load("[[stiffness]]\nattribute = \"kf\"\n");
    CHECK(scenario.ElementStiffness() == std::vector<double>{0.5, 3.0, 10.0, 10.0});
  }
  SECTION("errors name the property, the file and the place") {
    const auto message = [&](const std::string& regions) {
      return MessageOf(
          dir.Write("s.toml", "mesh = \"grid.ply\"\n[[handle]]\nselect.indices = [0]\n" + regions));
    };
    CHECK_THAT(message("[[stiffness]]\nattribute = \"stiff\"\n"),
               Contains("s.toml:5:13") && Contains("no vertex or face property 'stiff'") &&
                   Contains("vertex k") && Contains("face kf"));
    CHECK_THAT(message("[[stiffness]]\nattribute = \"k\"\nfactor = 2\n"),
               Contains("'factor' does not go with 'attribute'"));
    dir.Write("zero.ply",
              std::string(kGridPlyWithFactors)
                  .replace(std::string(kGridPlyWithFactors).find("14 0 0 8"), 8, "14 0 0 0"));
    CHECK_THAT(MessageOf(dir.Write("z.toml",
                                   "mesh = \"zero.ply\"\n[[handle]]\n"
                                   "select.indices = [0]\n[[stiffness]]\n"
                                   "attribute = \"k\"\n")),
               Contains("zero.ply") && Contains("is 0 at vertex 5"));
    dir.Write("grid.obj", kGridObj);
    CHECK_THAT(MessageOf(dir.Write("o.toml",
                                   "mesh = \"grid.obj\"\n[[handle]]\n"
                                   "select.indices = [0]\n[[stiffness]]\n"
                                   "attribute = \"k\"\n")),
               Contains("must be a PLY file"));
    CHECK_THAT(MessageOf(dir.Write("r.toml",
                                   "mesh = \"grid.ply\"\nrefine = 1\n[[handle]]\n"
                                   "select.indices = [0]\n[[stiffness]]\n"
                                   "attribute = \"k\"\n")),
               Contains("no refine"));
  }
}

}  // namespace
}  // namespace harap
