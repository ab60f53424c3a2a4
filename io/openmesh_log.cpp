// SPDX-License-Identifier: MIT
#include "io/openmesh_log.h"

#include <OpenMesh/Core/System/omstream.hh>
#include <algorithm>
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
  std::stringbuf errors;
  std::stringbuf other;  // omlog/omout: progress chatter, dropped
  std::streambuf* old_err = nullptr;
  std::streambuf* old_log = nullptr;
  std::streambuf* old_out = nullptr;
};

// The log streams are std::ostreams whose buffer multiplexes to the connected targets (cerr,
// clog, cout by default). Swapping the stream buffer, rather than disconnecting those targets and
// connecting our own, is deliberate: OpenMesh's disconnect() never frees the target it removes,
// so a connect/disconnect pair per call leaks memory (LeakSanitizer reports it).
OpenMeshLogCapture::OpenMeshLogCapture() : state_(std::make_unique<State>()) {
  state_->old_err = omerr().rdbuf(&state_->errors);
  state_->old_log = omlog().rdbuf(&state_->other);
  state_->old_out = omout().rdbuf(&state_->other);
}

OpenMeshLogCapture::~OpenMeshLogCapture() {
  omerr().rdbuf(state_->old_err);
  omlog().rdbuf(state_->old_log);
  omout().rdbuf(state_->old_out);
}

std::string OpenMeshLogCapture::Errors() {
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
