// SPDX-License-Identifier: MIT
#include "cli/known_answer_command.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "api/builtins.h"
#include "api/known_answer.h"
#include "framework/error.h"
#include "io/scenario.h"

namespace harap {

CLI::App* AddKnownAnswerCommand(CLI::App& app, KnownAnswerCommandArguments& args) {
  auto* command = app.add_subcommand(
      "known-answer",
      "make a registration case whose answer is known: the scenario deformed by harap deform is "
      "the answer, the target is made from it (docs/registration.md)");
  command->add_option("scenario", args.scenario, "deformation scenario (TOML)")->required();
  command->add_option("--target", args.target,
                      fmt::format("what to register to: {} (default points)",
                                  fmt::join(KnownAnswerTargetNames(), ", ")));
  command->add_option("--out-dir", args.out_dir, "folder for source.ply, target.ply and answer.ply")
      ->required();
  command->add_option("--points-per-vertex", args.points_per_vertex,
                      "points sampled on the deformed surface per mesh vertex (default 2)");
  command->add_option("--removed", args.removed,
                      "damaged target: fraction of the points removed as one hole (default 0.1)");
  command->add_option("--outliers", args.outliers,
                      "damaged target: outliers added, as a fraction of the points (default "
                      "0.01)");
  command->add_option("--seed", args.seed, "seed of the sampling and the damage (default 1)");
  command->add_option("--config", args.config_file,
                      "TOML run config of the answer's solve (harap deform's tables)");
  command->add_option("--optimizer", args.optimizer, "the answer's optimizer");
  command->add_option("--energy", args.energy, "the answer's energy");
  command->add_option("--tolerance", args.tolerance, "the answer's tolerance");
  command->add_option("--set", args.settings, "set an option of the answer's solve (repeatable)");
  command->add_option("--threads", args.threads, "worker threads (default: all cores)");
  command->add_flag("--quiet,-q", args.quiet, "print nothing on success");
  return command;
}

int KnownAnswerCommand(const KnownAnswerCommandArguments& args) {
  KnownAnswerOptions options;
  options.target = ParseKnownAnswerTarget(args.target);
  options.points_per_vertex = args.points_per_vertex;
  options.damage.removed = args.removed;
  options.damage.outliers = args.outliers;
  if (args.seed < 0) throw ConfigError(fmt::format("--seed {} must be >= 0", args.seed));
  options.seed = static_cast<std::uint64_t>(args.seed);
  options.threads = args.threads;
  options.Validate();
  const ConfigNode config = args.BuildConfig();
  const Scenario scenario = LoadScenario(args.scenario);
  const KnownAnswerCase known =
      MakeKnownAnswerCase(MakeBuiltinRegistries(), scenario, config, options);
  const KnownAnswerFiles files = WriteKnownAnswerCase(known, args.out_dir);
  if (!args.quiet) {
    fmt::print(
        "answer: {}\nwrote {} ({} vertices), {} ({} {}), {}\nregister with:\n  harap "
        "register {} {} --answer {}\n",
        known.answer_description, files.source.string(), known.source.num_vertices(),
        files.target.string(), known.target.num_points(), known.target.mesh ? "vertices" : "points",
        files.answer.string(), files.source.string(), files.target.string(), files.answer.string());
  }
  return 0;
}

}  // namespace harap
