// SPDX-License-Identifier: MIT
#include "framework/config.h"

#include <catch2/catch.hpp>

#include "framework/error.h"
#include "framework/registries.h"

using namespace harap;

TEST_CASE("OptionReader reads typed options with defaults and rejects unknown keys",
          "[framework]") {
  ConfigNode root = ConfigNode::Parse(R"(
[solver]
type = "cg"
sweeps = 10
tolerance = 1   # an integer where a float is expected is fine
flag = true
)",
                                      "run.toml");
  OptionReader solver(root.Child("solver"));
  CHECK(solver.Get("sweeps", 3, "h") == 10);
  CHECK(solver.Get("tolerance", 0.5, "h") == 1.0);
  CHECK(solver.Get("flag", false, "h") == true);
  CHECK(solver.Get("absent", 2.5, "h") == 2.5);
  CHECK(solver.Get("type", "x", "h") == "cg");
  solver.RejectUnknownKeys();  // all keys read

  OptionReader typo(ConfigNode::Parse("[solver]\nsweps = 3\n", "run.toml").Child("solver"));
  typo.Get("sweeps", 1, "sweeps per solve");
  CHECK_THROWS_WITH(typo.RejectUnknownKeys(), Catch::Contains("run.toml:2") &&
                                                  Catch::Contains("sweps") &&
                                                  Catch::Contains("valid options: sweeps"));
}

TEST_CASE("OptionReader reports type errors with file, line and key", "[framework]") {
  OptionReader node(ConfigNode::Parse("a = \"x\"\nb = 1.5\nc = nan\n", "bad.toml"));
  CHECK_THROWS_WITH(node.Get("a", 1.0, "h"), Catch::Contains("bad.toml:1") &&
                                                 Catch::Contains("'a'") &&
                                                 Catch::Contains("number"));
  CHECK_THROWS_WITH(node.Get("b", 1, "h"),
                    Catch::Contains("bad.toml:2") && Catch::Contains("integer"));
  CHECK_THROWS_WITH(node.Get("c", 1.0, "h"), Catch::Contains("finite"));
  CHECK_THROWS_WITH(ConfigNode::Parse("a = [1,\n", "broken.toml"),
                    Catch::Contains("broken.toml") && Catch::Contains("syntax"));
  CHECK_THROWS_WITH(node.GetChoice("a", "y", {"y", "z"}, "h"),
                    Catch::Contains("\"x\"") && Catch::Contains("y, z"));
}

TEST_CASE("ConfigNode::Set parses command-line values", "[framework]") {
  ConfigNode root;
  root.Set("energy.lambda", "0.5");
  root.Set("solver.type", "cholmod");  // bare word: a string
  root.Set("solver.sweeps", "10");
  root.Set("optimizer.targets_follow_rotations", "false");
  OptionReader reader(root);
  CHECK(reader.Child("energy").Get("lambda", 0.0, "h") == 0.5);
  CHECK(reader.Child("solver").Get("type", "x", "h") == "cholmod");
  CHECK(reader.Child("solver").Get("sweeps", 1, "h") == 10);
  CHECK(reader.Child("optimizer").Get("targets_follow_rotations", true, "h") == false);
  CHECK_THROWS_AS(root.Set("energy..x", "1"), ConfigError);
  root.Set("energy.lambda", "0.25");  // overrides
  CHECK(reader.Child("energy").Get("lambda", 0.0, "h") == 0.25);
  root.Child("solver").Remove("sweeps");
  CHECK_FALSE(root.Child("solver").Has("sweeps"));
  CHECK(root.Child("solver").Has("type"));
}

TEST_CASE("the record of keys read belongs to a reader, not to the document", "[framework]") {
  const ConfigNode root =
      ConfigNode::Parse("[energy]\ntype = \"spokes\"\nlambda = 0.5\n", "run.toml");
  // Looking at the document records nothing.
  CHECK(root.Child("energy").Has("lambda"));
  CHECK(root.Keys() == std::vector<std::string>{"energy"});
  OptionReader first(root);
  OptionReader energy = first.Child("energy");
  CHECK(energy.Get("type", "x", "which energy") == "spokes");
  // A copy and a child share the record: keys read through any of them count for the table.
  OptionReader copy = energy;
  CHECK(copy.Get("lambda", 0.0, "h") == 0.5);
  CHECK_NOTHROW(energy.RejectUnknownKeys());
  CHECK_NOTHROW(first.RejectUnknownKeys());
  CHECK(energy.Options().size() == 2);
  // Another reader of the same document starts with an empty record.
  OptionReader second(root.Child("energy"));
  CHECK(second.Options().empty());
  second.Get("type", "x", "which energy");
  CHECK_THROWS_WITH(second.RejectUnknownKeys(), Catch::Contains("run.toml:3") &&
                                                    Catch::Contains("'energy.lambda'") &&
                                                    Catch::Contains("valid options: type"));
}

namespace {

struct Widget {
  virtual ~Widget() = default;
  int size = 0;
};

}  // namespace

TEST_CASE("Registry creates by name and lists the valid names on errors", "[framework]") {
  Registry<Widget> registry("widget");
  const auto make = [](int size) {
    auto widget = std::make_unique<Widget>();
    widget->size = size;
    return widget;
  };
  registry.Add(
      "small", "a small widget",
      [](OptionReader node) {
        const int size = node.Get("size", 1, "the size");
        node.RejectUnknownKeys();
        return size;
      },
      make);
  registry.Add(
      "large", "a large widget", [](const OptionReader&) { return 100; }, make);
  CHECK(registry.Names() == std::vector<std::string>{"large", "small"});
  CHECK(registry.Create("small", ConfigNode::Parse("size = 3", "t"))->size == 3);
  CHECK(registry.Create(ConfigNode::Parse("type = \"large\"", "t"), "small")->size == 100);
  CHECK(registry.Create(ConfigNode(), "small")->size == 1);
  CHECK_THROWS_WITH(
      registry.Create("medium", ConfigNode()),
      Catch::Contains("unknown widget 'medium'") && Catch::Contains("valid names: large, small"));
  CHECK_THROWS_AS(registry.Add("small", "again", nullptr), InternalError);
  const auto options = registry.DescribeOptions("small");
  REQUIRE(options.size() == 1);
  CHECK(options[0].key == "size");
  CHECK(options[0].default_value == "1");
  CHECK(options[0].help == "the size");
}
