// SPDX-License-Identifier: MIT
#include "runner/process.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <string_view>
#include <thread>

extern char** environ;

namespace harap {

ProcessResult RunProcess(const std::vector<std::string>& arguments, const ProcessOptions& options) {
  ProcessResult result;
  if (arguments.empty()) return result;
  std::vector<std::string> environment;
  for (char** entry = environ; *entry; ++entry) environment.emplace_back(*entry);
  for (const std::string& variable : options.default_environment) {
    const std::string name = variable.substr(0, variable.find('=') + 1);
    bool present = false;
    for (const std::string& existing : environment) present |= existing.starts_with(name);
    if (!present) environment.push_back(variable);
  }
  std::vector<char*> argv, envp;
  for (const std::string& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  for (const std::string& variable : environment)
    envp.push_back(const_cast<char*>(variable.c_str()));
  envp.push_back(nullptr);

  pid_t pid = 0;
  if (options.die_with_parent) {
    // fork + exec instead of posix_spawn, which cannot set the parent-death signal. Between fork
    // and exec the child only makes async-signal-safe calls (the strings are built above).
    const pid_t parent = getpid();
    pid = fork();
    if (pid == 0) {
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent) _exit(127);  // the parent died before prctl
      const int input = open("/dev/null", O_RDONLY);
      if (input >= 0) dup2(input, STDIN_FILENO);
      if (!options.output_file.empty()) {
        const int output = open(options.output_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (output < 0) _exit(127);
        dup2(output, STDOUT_FILENO);
        dup2(output, STDERR_FILENO);
      }
      if (std::string_view(argv[0]).find('/') != std::string_view::npos) {
        execve(argv[0], argv.data(), envp.data());
      } else {
        execvpe(argv[0], argv.data(), envp.data());
      }
      _exit(127);
    }
    if (pid < 0) return result;
  } else {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    if (!options.output_file.empty()) {
      posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, options.output_file.c_str(),
                                       O_WRONLY | O_CREAT | O_TRUNC, 0644);
      posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    }
    const int spawn_error =
        posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), envp.data());
    posix_spawn_file_actions_destroy(&actions);
    if (spawn_error != 0) return result;
  }
  result.started = true;

  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  int status = 0;
  while (true) {
    const pid_t done = waitpid(pid, &status, options.timeout > 0 ? WNOHANG : 0);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) {
      result.started = false;
      return result;
    }
    if (options.timeout > 0 && !result.timed_out &&
        std::chrono::duration<double>(Clock::now() - start).count() > options.timeout) {
      kill(pid, SIGKILL);
      result.timed_out = true;
    }
    if (done == 0) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
  return result;
}

}  // namespace harap
