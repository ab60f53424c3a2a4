// SPDX-License-Identifier: MIT
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

#include "cli/piece_flags.h"

namespace harap {

struct ViewArguments : PieceFlags {
  std::string file;  ///< scenario TOML or a mesh file
  std::string host = "127.0.0.1";
  uint16_t port = 8080;
  std::string assets;  ///< the page's files; default: share/harap/view beside the executable
  bool open = false;
  int threads = 0;
  int display_vertices = 200000;  ///< ViewSource::display_vertices
};

/// `harap view SCENARIO.toml | MESH`: the interactive page (docs/view.md).
CLI::App* AddViewCommand(CLI::App& app, ViewArguments& args);
/// Runs the server until Ctrl-C; returns the exit code.
int RunViewCommand(const ViewArguments& args);

}  // namespace harap
