// SPDX-License-Identifier: MIT
#include "api/drag.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "api/builtins.h"
#include "tests/support/run_harap.h"
#include "tests/support/shared_data.h"
#include "tests/support/test_files.h"

using namespace harap;
using namespace harap::testing;

namespace {

const std::string kCylinder =
    ::harap::testing::SourceDir().string() + "/experiments/scenarios/cylinder-bend.toml";

}  // namespace

TEST_CASE("drag: frame targets move from rest to the scenario's targets", "[experiments]") {
  const Scenario scenario = LoadScenario(kCylinder);
  const Constraints end = scenario.MergedConstraints();
  const Constraints at_end = FrameConstraints(scenario, 1.0);
  const Constraints at_rest = FrameConstraints(scenario, 0.0);
  REQUIRE(at_end.indices == end.indices);
  CHECK((at_end.targets - end.targets).cwiseAbs().maxCoeff() < 1e-12);
  for (size_t k = 0; k < at_rest.indices.size(); ++k) {
    CHECK((at_rest.targets.row(k) - scenario.mesh.vertices.row(at_rest.indices[k])).norm() < 1e-12);
  }
  // Halfway, the top ring (turned by 90 degrees) is turned by 45: its rest-to-halfway rotation
  // moves the ring's vertices less than the whole motion does.
  const Constraints halfway = FrameConstraints(scenario, 0.5);
  double half = 0.0, whole = 0.0;
  for (size_t k = 0; k < end.indices.size(); ++k) {
    const Eigen::RowVector3d rest = scenario.mesh.vertices.row(end.indices[k]);
    half = std::max(half, (halfway.targets.row(k) - rest).norm());
    whole = std::max(whole, (end.targets.row(k) - rest).norm());
  }
  CHECK(half > 0.3 * whole);
  CHECK(half < 0.7 * whole);
}

TEST_CASE("drag: a session replays the cylinder bend, frame by frame", "[experiments]") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "harap_drag_test";
  std::filesystem::remove_all(dir);
  const CommandResult run =
      RunHarap("drag " + kCylinder + " --optimizer hierarchical --frames 3 --threads 2 --report " +
               (dir / "drag.json").string() + " --out-frames " + (dir / "frames").string());
  INFO(run.output);
  REQUIRE(run.status == 0);
  CHECK(run.output.find("frames:") != std::string::npos);
  std::ifstream file(dir / "drag.json");
  const nlohmann::json report = nlohmann::json::parse(file);
  CHECK(report["mode"] == "session");
  REQUIRE(report["frames"].size() == 3);
  for (const auto& frame : report["frames"]) {
    CHECK(frame["seconds"].get<double>() > 0.0);
    CHECK(frame["iterations"].get<int>() >= 1);
    CHECK(frame["levels"].size() >= 2);
    // The handles moved away from rest (the energy need not grow from frame to frame: the bent
    // cylinder buckles into another shape on the way).
    CHECK(frame["energy"].get<double>() > 0.01);
  }
  CHECK(std::filesystem::exists(dir / "frames" / "frame_003.ply"));
  // The last frame is the scenario's end pose: a one-shot run ends near the same energy.
  const CommandResult scratch = RunHarap("drag " + kCylinder +
                                         " --optimizer hierarchical --frames 3 --threads 2 "
                                         "--from-scratch --report " +
                                         (dir / "scratch.json").string());
  REQUIRE(scratch.status == 0);
  std::ifstream scratch_file(dir / "scratch.json");
  const nlohmann::json from_scratch = nlohmann::json::parse(scratch_file);
  CHECK(from_scratch["mode"] == "from_scratch");
  const double session_energy = report["frames"][2]["energy"];
  const double scratch_energy = from_scratch["frames"][2]["energy"];
  CHECK(session_energy < scratch_energy * 1.05);
  // Handle edits: a ball added before frame 2 and removed before frame 3.
  {
    std::ofstream edits(dir / "edits.toml");
    edits << "[[edit]]\nframe = 2\nadd = { name = \"ball\", select.ball = { center = [0.5, 0.0, "
             "0.5], radius = 0.1 } }\n[[edit]]\nframe = 3\nremove = \"ball\"\n";
  }
  const CommandResult edited =
      RunHarap("drag " + kCylinder + " --optimizer hierarchical --frames 3 --threads 2 --edits " +
               (dir / "edits.toml").string() + " --report " + (dir / "edited.json").string());
  INFO(edited.output);
  REQUIRE(edited.status == 0);
  std::ifstream edited_file(dir / "edited.json");
  const nlohmann::json with_edits = nlohmann::json::parse(edited_file);
  CHECK_FALSE(with_edits["frames"][0].contains("edit_seconds"));
  for (int frame : {1, 2}) {
    const auto& entry = with_edits["frames"][frame];
    REQUIRE(entry.contains("edit_seconds"));
    CHECK(entry["edit_seconds"].get<double>() > 0.0);
    REQUIRE(entry["edit"]["levels"].size() >= 2);
    for (const auto& level : entry["edit"]["levels"]) CHECK(level["changed_rows"].get<int>() > 0);
  }
  // Removing the ball restores the scenario's handles: the last frame lands where it would
  // without the edits (the same problem, a different warm-start path).
  const double edited_energy = with_edits["frames"][2]["energy"];
  CHECK(std::abs(edited_energy - session_energy) < 0.05 * session_energy);
  {
    std::ofstream bad(dir / "bad.toml");
    bad << "[[edit]]\nframe = 2\nremove = \"nothing\"\n";
  }
  const CommandResult bad =
      RunHarap("drag " + kCylinder + " --frames 3 --edits " + (dir / "bad.toml").string());
  CHECK(bad.status == 1);
  CHECK(bad.output.find("no handle 'nothing'") != std::string::npos);
  CHECK(RunHarap("drag " + kCylinder + " --frames 0").status == 1);
  CHECK(RunHarap("drag " + kCylinder + " --frame-start sideways")
            .output.find("valid are corrected") != std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_CASE("drag: soft handles (a handle's weight) stay soft in the session", "[experiments]") {
  const Registries registries = MakeBuiltinRegistries();
  const Scenario scenario =
      ParseScenario(testing::CylinderScenario(testing::CylinderMesh(1500), 0.03, 0.0,
                                              "[0.0, 0.3, -0.1]", "weight = 2.0\n"),
                    "inline", ".");
  REQUIRE(scenario.MergedConstraints().has_soft());
  for (const char* optimizer : {"classic", "hierarchical"}) {
    DYNAMIC_SECTION(optimizer) {
      ConfigNode config;
      config.Set("optimizer.type", fmt::format("\"{}\"", optimizer));
      config.Set("optimizer.tolerance", "1e-6");
      DragOptions options;
      options.threads = 2;
      // One frame: the session's first solve is the one-shot run, soft handles and all.
      options.frames = 1;
      const DragOutcome session = RunDrag(registries, scenario, config, options);
      options.from_scratch = true;
      const DragOutcome scratch = RunDrag(registries, scenario, config, options);
      const double session_energy = session.frames[0].energy;
      const double scratch_energy = scratch.frames[0].energy;
      CHECK(std::abs(session_energy - scratch_energy) <= 1e-9 * scratch_energy);
      CHECK(session.frames[0].iterations == scratch.frames[0].iterations);
      // Several frames, solved and previewed: the soft targets move every frame.
      options.from_scratch = false;
      options.frames = 3;
      const DragOutcome frames = RunDrag(registries, scenario, config, options);
      options.preview = true;
      const DragOutcome previews = RunDrag(registries, scenario, config, options);
      REQUIRE(frames.frames.size() == 3);
      REQUIRE(previews.frames.size() == 3);
      CHECK(frames.frames[2].energy < scratch_energy * 1.05);
      CHECK(std::isfinite(previews.frames[2].energy));
    }
  }
}
