// SPDX-License-Identifier: MIT
// Handle-edit files (`harap drag --edits`): an added handle is selected exactly as a scenario's
// [[handle]] with the same table would select it; bad entries name file:line and the edit.
#include <catch2/catch.hpp>
#include <string>

#include "framework/error.h"
#include "io/scenario.h"
#include "tests/io/io_test_util.h"

using namespace harap;
using harap::testing::ScratchDir;

namespace {

const char* kScenario = R"(
mesh = { builtin = "cylinder", vertices = 2000 }
[[handle]]
name = "bottom"
select.slab = { axis = "z", from = 0.0, to = 0.05 }
)";

// The vertices a scenario handle written as `handle_table` selects on kScenario's mesh.
std::vector<Index> ScenarioSelects(const std::string& handle_table) {
  const Scenario scenario =
      ParseScenario(std::string(kScenario) + "[[handle]]\n" + handle_table, "inline", ".");
  return scenario.handles.back().vertices;
}

}  // namespace

TEST_CASE("LoadHandleEdits: adds are selected as scenario handles are", "[io][edits]") {
  ScratchDir dir;
  const Scenario scenario = ParseScenario(kScenario, "inline", ".");
  const auto file = dir.Write("edits.toml", R"(
[[edit]]
frame = 3
add = { name = "ball", select.ball = { center = [0.5, 0.5, 0.5], radius = 0.2 } }
[[edit]]
frame = 4
add = { name = "ring", units = "absolute", select.slab = { axis = "z", from = 1.0, to = 1.5 } }
[[edit]]
frame = 5
add = { name = "three", select.indices = [7, 3, 5, 3] }
[[edit]]
frame = 6
remove = "ball"
)");
  const std::vector<HandleEdit> edits = LoadHandleEdits(file, scenario);
  REQUIRE(edits.size() == 4);
  CHECK(edits[0].frame == 3);
  CHECK(edits[0].add);
  CHECK(edits[0].name == "ball");
  CHECK(
      edits[0].vertices ==
      ScenarioSelects("name = \"ball\"\nselect.ball = { center = [0.5, 0.5, 0.5], radius = 0.2 }"));
  CHECK_FALSE(edits[0].vertices.empty());
  CHECK(edits[1].vertices ==
        ScenarioSelects("name = \"ring\"\nunits = \"absolute\"\n"
                        "select.slab = { axis = \"z\", from = 1.0, to = 1.5 }"));
  CHECK_FALSE(edits[1].vertices.empty());
  CHECK(edits[2].vertices == std::vector<Index>{3, 5, 7});
  CHECK_FALSE(edits[3].add);
  CHECK(edits[3].name == "ball");
  CHECK(edits[3].vertices.empty());
}

TEST_CASE("LoadHandleEdits: bad entries name the file, the line and the edit", "[io][edits]") {
  ScratchDir dir;
  const Scenario scenario = ParseScenario(kScenario, "inline", ".");
  struct Case {
    const char* text;
    const char* expected;
  };
  const Case cases[] = {
      {"[[edit]]\nframe = 0\nremove = \"x\"\n", "frame = N, an integer >= 1"},
      {"[[edit]]\nframe = 2\n", "exactly one of add"},
      {"[[edit]]\nframe = 2\nremove = \"x\"\nadd = { name = \"y\", select.indices = [1] }\n",
       "exactly one of add"},
      {"[[edit]]\nframe = 2\nremov = \"x\"\n", "unknown key 'remov'"},
      {"[[edit]]\nframe = 2\nadd = { name = \"far\", select.ball = { center = [5.0, 5.0, 5.0], "
       "radius = 0.01 } }\n",
       "far"},
      {"[[edit]]\nframe = 2\nadd = { name = \"bad\", select.indices = [100000] }\n", "100000"},
      {"frames = 2\n", "unknown key 'frames'"},
      {"", "no [[edit]] entries"},
  };
  for (const Case& c : cases) {
    INFO(c.text);
    const auto file = dir.Write("bad.toml", c.text);
    try {
      (void)LoadHandleEdits(file, scenario);
      FAIL("no error");
    } catch (const Error& error) {
      const std::string message = error.what();
      INFO(message);
      CHECK(message.find("bad.toml") != std::string::npos);
      CHECK(message.find(c.expected) != std::string::npos);
    }
  }
  CHECK_THROWS_AS(LoadHandleEdits(dir.path() / "missing.toml", scenario), InputError);
}
