// SPDX-License-Identifier: MIT
// The three TOML readers (run configs, scenario files, experiment configs) share one toolkit
// (framework/toml_reading.h) and so one error style: "file:line:column: [context: ]problem",
// the problem naming the key. The same mistake reads the same in each.
#include <catch2/catch.hpp>
#include <string>

#include "framework/config.h"
#include "framework/error.h"
#include "io/scenario.h"
#include "runner/experiment.h"
#include "tests/support/temp_folder.h"
#include "tests/support/test_files.h"

namespace {

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using harap::testing::TempFolder;

// What reading `text` with `read` throws ("no error" if nothing).
template <class Read>
std::string ErrorOf(Read read) {
  try {
    read();
  } catch (const harap::ConfigError& error) {
    return error.what();
  } catch (const harap::Error& error) {
    return std::string("not a ConfigError: ") + error.what();
  }
  return "no error";
}

struct Readers : TempFolder {
  Readers() : TempFolder("toml-errors") {
    Write("cylinder.toml", harap::testing::kCylinderBendScenario);
  }
  std::string Config(const std::string& text) const {
    return ErrorOf([&] { harap::ConfigNode::Parse(text, "run.toml"); });
  }
  std::string Scenario(const std::string& text) const {
    return ErrorOf([&] { harap::ParseScenario(text, "scene.toml", dir); });
  }
  std::string Experiment(const std::string& text) const {
    return ErrorOf([&] { harap::ParseExperiment(text, "sweep.toml", dir); });
  }
};

const std::string kScenarios = "[scenarios]\nfiles = [\"cylinder.toml\"]\n";

}  // namespace

TEST_CASE("TOML readers: a syntax error names the file, line and column alike",
          "[experiments][toml]") {
  const Readers readers;
  CHECK_THAT(readers.Config("[energy]\ntype = \n"),
             StartsWith("run.toml:2:") && Contains("TOML syntax error"));
  CHECK_THAT(readers.Scenario("mesh = \"x.obj\"\n[[handle]\n"),
             StartsWith("scene.toml:2:") && Contains("TOML syntax error"));
  CHECK_THAT(readers.Experiment(kScenarios + "[run\n"),
             StartsWith("sweep.toml:3:") && Contains("TOML syntax error"));
}

TEST_CASE("TOML readers: an unknown key is named where it is written, with the valid keys",
          "[experiments][toml]") {
  const Readers readers;
  CHECK(readers.Scenario("mesh = \"x.obj\"\nrefin = 2\n") ==
        "scene.toml:2:1: unknown key 'refin' in the top level; valid keys: mesh, refine, "
        "initial, planar, handle, stiffness, units, selection, deformation");
  CHECK(readers.Experiment(kScenarios + "[run]\nthread = 2\n") ==
        "sweep.toml:4:1: unknown key 'thread' in [run]; valid keys: threads, save_mesh, timeout, "
        "min_time");
  // Inside a handle the handle is named too.
  CHECK(readers.Scenario("mesh = \"x.obj\"\n[[handle]]\nname = \"feet\"\n"
                         "select.slab = { axis = \"z\", from = 0, to = 0.1, units = 1 }\n") ==
        "scene.toml:4:57: handle 'feet': 'units' is a key of the [[handle]] (or of the top "
        "level), not of select.slab: write units = \"absolute\" on its own line in the handle; "
        "it applies to the selection, rotate.center and translate");
}

TEST_CASE("TOML readers: numbers must be numbers, and finite", "[experiments][toml]") {
  const Readers readers;
  CHECK(readers.Scenario("mesh = \"x.obj\"\n[[handle]]\nselect.indices = [0]\n"
                         "rotate = { axis = [0, 0, 1], degrees = \"ten\" }\n") ==
        "scene.toml:4:40: handle 1: rotate degrees must be a number");
  CHECK(readers.Experiment(kScenarios + "[run]\ntimeout = \"ten\"\n") ==
        "sweep.toml:4:11: timeout must be a number");
  // nan passed the old `timeout < 0` check of the experiment reader and meant no timeout.
  CHECK(readers.Experiment(kScenarios + "[run]\ntimeout = nan\n") ==
        "sweep.toml:4:11: timeout is a non-finite number (nan)");
  CHECK(readers.Scenario("mesh = \"x.obj\"\n[[handle]]\nselect.indices = [0]\n"
                         "translate = [0, inf, 0]\n") ==
        "scene.toml:4:17: handle 1: translate is a non-finite number (inf)");
  // A run config's values are typed when an implementation reads them (OptionReader::Get).
  CHECK_THAT(ErrorOf([] {
               harap::OptionReader(
                   harap::ConfigNode::Parse("[optimizer]\ntolerance = \"small\"\n", "run.toml"))
                   .Child("optimizer")
                   .Get("tolerance", 1.0, "");
             }),
             StartsWith("run.toml:2:13:") && Contains("'optimizer.tolerance'") &&
                 Contains("must be a number"));
}
