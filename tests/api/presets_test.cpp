// SPDX-License-Identifier: MIT
// --preset / `preset = "..."`: named option sets below every other option (api/presets.h),
// and the per-level solver tables they use.
#include "api/presets.h"

#include <catch2/catch.hpp>

#include "api/builtins.h"
#include "api/component_factory.h"
#include "cli/piece_flags.h"
#include "framework/error.h"
#include "solvers/optimizers/hierarchical_optimizer.h"

using namespace harap;

namespace {

std::string TypeOf(const ConfigNode& config, const std::string& table) {
  return OptionReader(config.Child(table)).Get("type", std::string(), "");
}

}  // namespace

TEST_CASE("preset fast: the hierarchical optimizer with the adaptive solver on level 0",
          "[experiments][preset]") {
  PieceFlags flags;
  flags.preset = "fast";
  const ConfigNode config = flags.BuildConfig();
  CHECK(TypeOf(config, "optimizer") == "hierarchical");
  OptionReader level0(config.Child("solver").Child("level_0"));
  CHECK(level0.Get("type", std::string(), "") == "adaptive");
  CHECK(level0.Get("expected_solves", 0.0, "") == 4.0);
  // If it factors, it solves with the supernodal factor (few solves: no conversion).
  CHECK(level0.Child("direct").Get("mode", std::string(), "") == "supernodal");
  // Fixed coarse targets, so that Anderson acceleration takes effect on the coarse levels.
  CHECK_FALSE(OptionReader(config.Child("optimizer")).Get("targets_follow_rotations", true, ""));
  CHECK(OptionReader(config.Child("optimizer")).Get("anderson", 0, "") == 5);
  // Coarse levels stopped at 0.3 × the tolerance: a better converged start for the finest.
  CHECK(OptionReader(config.Child("optimizer")).Get("coarse_tolerance_factor", 1.0, "") == 0.3);
  // The factory then gives level 0 the adaptive solver and the other levels [solver]'s.
  const Registries registries = MakeBuiltinRegistries();
  const RegistryComponentFactory factory(registries, flags.BuildConfig());
  CHECK(factory.solver_name_for(0, 1000) == "adaptive");
  CHECK(factory.solver_name_for(1, 1000) == "cholmod");
  CHECK(factory.solver_used(1, 1000) == "cholmod");
}

TEST_CASE("presets sit below the config, the flags and --set", "[experiments][preset]") {
  PieceFlags flags;
  flags.preset = "fast";
  flags.settings = {"solver.level_0.expected_solves=9", "optimizer.coarse_tolerance=1e-7"};
  CHECK(OptionReader(flags.BuildConfig().Child("solver").Child("level_0"))
            .Get("expected_solves", 0.0, "") == 9.0);
  // A coarse_tolerance set wins over the preset's coarse_tolerance_factor (still set, unused).
  const Registries fixed_registries = MakeBuiltinRegistries();
  ConfigNode fixed = flags.BuildConfig().Child("optimizer");
  fixed.Remove("type");  // the factory's key, not the optimizer's
  const auto options = HierarchicalOptimizer::Options::FromConfig(OptionReader(fixed),
                                                                  fixed_registries.level_solvers);
  CHECK(options.Request(1, 3, true, 1.0).tolerance == 1e-7);
  CHECK(options.Request(1, 3, true, 1.0).tolerance_factor == 1.0);
  // Another optimizer: the hierarchical-only settings are left out (classic would reject them).
  flags.settings.clear();
  flags.optimizer = "classic";
  const ConfigNode classic = flags.BuildConfig();
  CHECK(TypeOf(classic, "optimizer") == "classic");
  CHECK_FALSE(classic.Child("solver").Has("level_0"));
  // Another solver type for level 0: the adaptive solver's options are left out.
  flags.optimizer.clear();
  flags.settings = {"solver.level_0.type=\"cg\""};
  const ConfigNode cg = flags.BuildConfig();
  CHECK_FALSE(cg.Child("solver").Child("level_0").Has("expected_solves"));
  CHECK_FALSE(cg.Child("solver").Child("level_0").Has("direct"));  // nor its subtables
  const Registries registries = MakeBuiltinRegistries();
  CHECK_NOTHROW(RegistryComponentFactory(registries, flags.BuildConfig()));
  // Another level solver: local_global's options (anderson) are left out, the rest stays.
  flags.settings = {"optimizer.inner=\"admm_pd\""};
  const ConfigNode admm = flags.BuildConfig();
  CHECK_FALSE(admm.Child("optimizer").Has("anderson"));
  CHECK_FALSE(admm.Child("optimizer").Has("coarse_tolerance_factor"));
  CHECK_FALSE(OptionReader(admm.Child("optimizer")).Get("targets_follow_rotations", true, ""));
}

TEST_CASE("presets: unknown names are rejected, the config's preset key is read",
          "[experiments][preset]") {
  PieceFlags flags;
  flags.preset = "fastest";
  CHECK_THROWS_WITH(flags.BuildConfig(),
                    Catch::Contains("fastest") && Catch::Contains("fast, hierarchical"));
  ConfigNode config = ConfigNode::Parse("preset = \"hierarchical\"\n", "<test>");
  CHECK(ApplyPreset(config, "") == "hierarchical");
  CHECK(TypeOf(config, "optimizer") == "hierarchical");
  CHECK_NOTHROW(ValidateRunConfig(config));
  // The flag wins over the config's key.
  ConfigNode both = ConfigNode::Parse("preset = \"hierarchical\"\n", "<test>");
  CHECK(ApplyPreset(both, "fast") == "fast");
  CHECK(both.Child("solver").Has("level_0"));
}

TEST_CASE("solver.level_<l> tables: validated at once, named per level", "[experiments]") {
  const Registries registries = MakeBuiltinRegistries();
  const auto make = [&](const std::string& toml) {
    return RegistryComponentFactory(registries, ConfigNode::Parse(toml, "<test>"));
  };
  const auto factory = make("[solver.level_2]\ntype = \"cg\"\nmax_iterations = 7\n");
  CHECK_FALSE(factory.MakeLinearSolver(2, 100)->is_direct());
  CHECK(factory.MakeLinearSolver(1, 100)->is_direct());
  CHECK(factory.solver_used(2, 100) == "cg");
  CHECK_FALSE(factory.solver_direct(2, 100));
  CHECK(factory.solver_direct(0, 100));
  CHECK_THROWS_AS(make("[solver.level_1]\ntype = \"cg\"\nmode = \"auto\"\n"), ConfigError);
  CHECK_THROWS_WITH(make("[solver.level_x]\ntype = \"cg\"\n"), Catch::Contains("level_<l>"));
}

TEST_CASE("the factory records what an adaptive solver chose for its level", "[experiments]") {
  const Registries registries = MakeBuiltinRegistries();
  if (!registries.linear_solvers.Contains("adaptive")) {
    WARN("skipped: this build has no CHOLMOD");
    return;
  }
  const RegistryComponentFactory factory(
      registries, ConfigNode::Parse("[solver.level_0]\ntype = \"adaptive\"\n[solver.level_1]\n"
                                    "type = \"adaptive\"\nchoose = \"iterative\"\n",
                                    "<test>"));
  // A 1D Laplacian with both ends pinned: SPD, tridiagonal.
  const Index n = 200;
  std::vector<Eigen::Triplet<double>> entries;
  for (Index i = 0; i < n; ++i) {
    entries.emplace_back(i, i, 2.0);
    if (i + 1 < n) {
      entries.emplace_back(i, i + 1, -1.0);
      entries.emplace_back(i + 1, i, -1.0);
    }
  }
  SparseMatrix a(n, n);
  a.setFromTriplets(entries.begin(), entries.end());
  const Context context;
  CHECK(factory.solver_used(0, n) == "adaptive");  // nothing chosen yet
  auto direct = factory.MakeLinearSolver(0, n);
  direct->Factorize(a, context);
  auto iterative = factory.MakeLinearSolver(1, n);
  iterative->Factorize(a, context);
  CHECK(factory.solver_used(0, n) == "adaptive:cholmod");
  CHECK(factory.solver_direct(0, n));
  CHECK(factory.solver_used(1, n) == "adaptive:cg");
  CHECK_FALSE(factory.solver_direct(1, n));
}
