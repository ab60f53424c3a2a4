// SPDX-License-Identifier: MIT
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "cli/piece_flags.h"

namespace harap {

struct KnownAnswerCommandArguments : PieceFlags {
  std::string scenario;
  std::string target = "points";
  std::string out_dir;
  double points_per_vertex = 2.0;
  double removed = 0.10;
  double outliers = 0.01;
  long long seed = 1;
  int threads = 0;
  bool quiet = false;
};

/// `harap known-answer SCENARIO --target K --out-dir DIR`: a registration case with a known
/// answer (api/known_answer.h): the scenario solved by `harap deform` is the answer; the target
/// is made from it. Writes DIR/source.ply, DIR/target.ply and DIR/answer.ply and prints the
/// `harap register` command that registers them.
CLI::App* AddKnownAnswerCommand(CLI::App& app, KnownAnswerCommandArguments& args);
int KnownAnswerCommand(const KnownAnswerCommandArguments& args);

}  // namespace harap
