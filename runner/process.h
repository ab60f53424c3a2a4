// SPDX-License-Identifier: MIT
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace harap {

struct ProcessResult {
  bool started = false;    ///< false: the program could not be executed
  bool timed_out = false;  ///< killed after the timeout
  int exit_code = -1;      ///< when it exited normally
  int signal = 0;          ///< when a signal ended it
  bool ok() const { return started && !timed_out && signal == 0 && exit_code == 0; }
};

struct ProcessOptions {
  /// Standard output and error go to this file (created/truncated); empty: inherited.
  std::filesystem::path output_file;
  /// Environment variables added unless the environment already sets them ("NAME=value").
  std::vector<std::string> default_environment;
  /// Seconds after which the process is killed (SIGKILL); 0: no limit.
  double timeout = 0.0;
  /// Linux: the process gets SIGKILL when the calling thread's process dies (prctl
  /// PR_SET_PDEATHSIG), so a sweep killed with SIGKILL leaves no run behind that goes on
  /// writing into its folder.
  bool die_with_parent = false;
};

/// Runs `arguments[0]` (searched on PATH when it has no '/') with the given arguments and waits
/// for it. Standard input is /dev/null.
ProcessResult RunProcess(const std::vector<std::string>& arguments, const ProcessOptions& options);

}  // namespace harap
