// SPDX-License-Identifier: MIT
// Range-checked and enum options read by ConfigNode itself: one error wording (where, key, value,
// what is valid) and the valid values in the help `harap list` shows.
#include <catch2/catch.hpp>
#include <cmath>

#include "framework/config.h"
#include "framework/error.h"

using namespace harap;

namespace {

enum class Sweep { kForward, kSymmetric };
constexpr EnumNames<Sweep, 2> kSweepNames = {
    {{Sweep::kForward, "forward"}, {Sweep::kSymmetric, "symmetric"}}};

}  // namespace

TEST_CASE("Range: membership and text", "[framework][config]") {
  CHECK(Range::HalfOpen(0, 1).Contains(0.0));
  CHECK_FALSE(Range::HalfOpen(0, 1).Contains(1.0));
  CHECK_FALSE(Range::Open(0, 2).Contains(0.0));
  CHECK(Range::LeftOpen(0, 180).Contains(180.0));
  CHECK(Range::AtLeast(1).Contains(1.0));
  CHECK_FALSE(Range::Above(0).Contains(0.0));
  CHECK_FALSE(Range::AtLeast(0).Contains(std::nan("")));
  CHECK(Range::HalfOpen(0, 1).ToString() == "in [0, 1)");
  CHECK(Range::Open(0, 2).ToString() == "in (0, 2)");
  CHECK(Range::LeftOpen(0, 180).ToString() == "in (0, 180]");
  CHECK(Range::AtLeast(1).ToString() == ">= 1");
  CHECK(Range::Above(0.5).ToString() == "> 0.5");
}

TEST_CASE("OptionReader::Get with a range: values outside fail naming where, key and range",
          "[framework][config]") {
  const ConfigNode root = ConfigNode::Parse(
      "[solver]\ntolerance = 1.5\nmax_iterations = 0\nrelaxation = 1.2\n", "run.toml");
  OptionReader solver(root.Child("solver"));
  CHECK(solver.Get("relaxation", 1.0, "ω", Range::Open(0, 2)) == 1.2);
  CHECK(solver.Get("absent", 3, "h", Range::AtLeast(1)) == 3);
  CHECK_THROWS_AS(solver.Get("tolerance", 0.0, "h", Range::HalfOpen(0, 1)), ConfigError);
  CHECK_THROWS_WITH(solver.Get("tolerance", 0.0, "h", Range::HalfOpen(0, 1)),
                    Catch::StartsWith("run.toml:2") &&
                        Catch::EndsWith(": option 'solver.tolerance' is 1.5, which is not in "
                                        "[0, 1)"));
  CHECK_THROWS_WITH(solver.Get("max_iterations", 10, "h", Range::AtLeast(1)),
                    Catch::StartsWith("run.toml:3") &&
                        Catch::EndsWith(": option 'solver.max_iterations' is 0, which is not "
                                        ">= 1"));
}

TEST_CASE("OptionReader::GetEnum reads names into values; help and errors list the names",
          "[framework][config]") {
  const ConfigNode root =
      ConfigNode::Parse("[a]\nsweep = \"symmetric\"\n[b]\nsweep = \"backward\"\n", "run.toml");
  OptionReader reader(root);
  CHECK(reader.Child("a").GetEnum("sweep", Sweep::kForward, kSweepNames, "h") == Sweep::kSymmetric);
  CHECK(OptionReader(ConfigNode()).GetEnum("sweep", Sweep::kSymmetric, kSweepNames, "h") ==
        Sweep::kSymmetric);
  CHECK_THROWS_WITH(reader.Child("b").GetEnum("sweep", Sweep::kForward, kSweepNames, "h"),
                    Catch::Contains("run.toml:4") &&
                        Catch::Contains("option 'b.sweep' is \"backward\", which is not one of: "
                                        "forward, symmetric"));
  CHECK(NameOf(kSweepNames, Sweep::kSymmetric) == "symmetric");
}

TEST_CASE("described options show their range and names", "[framework][config]") {
  OptionReader node = OptionReader::Describing();
  node.Get("tolerance", 0.0, "stop below this", Range::HalfOpen(0, 1));
  node.GetEnum("sweep", Sweep::kForward, kSweepNames, "sweep order");
  const auto options = node.Options();
  REQUIRE(options.size() == 2);
  CHECK(options[0].help == "stop below this (in [0, 1))");
  CHECK(options[0].default_value == "0");
  CHECK(options[1].help == "sweep order (one of: forward, symmetric)");
  CHECK(options[1].default_value == "\"forward\"");
}

TEST_CASE("RangeProblems: the same wording for options structs built in code",
          "[framework][config]") {
  CHECK(RangeProblems({{"ratio", 0.5, Range::HalfOpen(0, 1)}}).empty());
  const auto problems = RangeProblems(
      {{"ratio", 1.0, Range::HalfOpen(0, 1)}, {"min_vertices", -1, Range::AtLeast(0)}});
  REQUIRE(problems.size() == 2);
  CHECK(problems[0] == "ratio is 1, which is not in [0, 1)");
  CHECK(problems[1] == "min_vertices is -1, which is not >= 0");
}
