// SPDX-License-Identifier: MIT
#include "cli/interrupt.h"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstring>

namespace harap {

namespace {

std::atomic<int> interrupts{0};
struct sigaction previous_action {};

void OnInterrupt(int) {
  // Only async-signal-safe calls here: write(2) and _exit(2).
  if (interrupts.fetch_add(1) == 0) {
    constexpr char kMessage[] =
        "\nharap: interrupted: stopping after the current iteration, then writing the results "
        "(Ctrl-C again quits at once)\n";
    [[maybe_unused]] const ssize_t written = write(STDERR_FILENO, kMessage, sizeof kMessage - 1);
  } else {
    _exit(130);
  }
}

}  // namespace

InterruptGuard::InterruptGuard() {
  interrupts = 0;
  struct sigaction action {};
  action.sa_handler = OnInterrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  sigaction(SIGINT, &action, &previous_action);
}

InterruptGuard::~InterruptGuard() { sigaction(SIGINT, &previous_action, nullptr); }

bool InterruptGuard::Requested() { return interrupts.load() > 0; }

}  // namespace harap
