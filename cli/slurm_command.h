// SPDX-License-Identifier: MIT
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace harap {

/// The `harap run --slurm` options; unset ones come from the config's [slurm] table.
struct SlurmArguments {
  bool slurm = false;
  int tasks = 0;
  std::string partition, time, mem;
  int cpus_per_task = 0;
  int throttle = -1;
  std::vector<std::string> sbatch_flags;
};

/// Adds --slurm and its options to `harap run`.
void AddSlurmOptions(CLI::App& run, SlurmArguments& args);

/// `harap run CONFIG --slurm`: submits the sweep to Slurm (runner/slurm.h) and prints the job
/// ids. Returns the exit code.
int SubmitSweepToSlurm(const std::string& config, const std::string& out,
                       const SlurmArguments& args);

/// `harap status DIR`.
CLI::App* AddStatusCommand(CLI::App& app, std::string& dir);
int StatusCommand(const std::string& dir);

}  // namespace harap
