// SPDX-License-Identifier: MIT
#include "framework/io/openmesh_log.h"

#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <iostream>
#include <mutex>
#include <sstream>
#include <utility>
#include <vector>

namespace harap::io_internal {

namespace {

std::mutex& OpenMeshMutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace

struct OpenMeshLogCapture::State {
  std::unique_lock<std::mutex> lock{OpenMeshMutex()};
  std::ostringstream errors;
  std::ostringstream other;  // omlog/omout: progress chatter, dropped
  // Which default targets were connected, so that exactly those are restored.
  bool err_to_cerr = false;
  bool log_to_clog = false;
  bool log_to_cerr = false;
  bool out_to_cout = false;
};

OpenMeshLogCapture::OpenMeshLogCapture() : state_(std::make_unique<State>()) {
  // disconnect() returns whether the target was connected; OpenMesh connects omerr to cerr,
  // omlog to clog (cerr in some builds) and omout to cout on first use.
  state_->err_to_cerr = omerr().disconnect(std::cerr);
  state_->log_to_clog = omlog().disconnect(std::clog);
  state_->log_to_cerr = omlog().disconnect(std::cerr);
  state_->out_to_cout = omout().disconnect(std::cout);
  omerr().connect(state_->errors);
  omlog().connect(state_->other);
  omout().connect(state_->other);
}

OpenMeshLogCapture::~OpenMeshLogCapture() {
  omerr().flush();
  omlog().flush();
  omout().flush();
  omerr().disconnect(state_->errors);
  omlog().disconnect(state_->other);
  omout().disconnect(state_->other);
  if (state_->err_to_cerr) omerr().connect(std::cerr);
  if (state_->log_to_clog) omlog().connect(std::clog);
  if (state_->log_to_cerr) omlog().connect(std::cerr);
  if (state_->out_to_cout) omout().connect(std::cout);
}

std::string OpenMeshLogCapture::Errors() {
  omerr().flush();
  // OpenMesh repeats one line per refused face; keep each distinct line once, with its count.
  std::vector<std::pair<std::string, int>> distinct;
  std::istringstream lines(state_->errors.str());
  std::string line;
  while (std::getline(lines, line)) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos) continue;
    const auto last = line.find_last_not_of(" \t\r");
    line = line.substr(first, last - first + 1);
    auto it = std::find_if(distinct.begin(), distinct.end(),
                           [&](const auto& entry) { return entry.first == line; });
    if (it == distinct.end()) {
      distinct.emplace_back(line, 1);
    } else {
      ++it->second;
    }
  }
  std::string joined;
  for (const auto& [text, count] : distinct) {
    if (!joined.empty()) joined += "; ";
    joined += count == 1 ? text : text + " (" + std::to_string(count) + " times)";
  }
  return joined;
}

}  // namespace harap::io_internal
