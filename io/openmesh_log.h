// SPDX-License-Identifier: MIT
#pragma once

// Internal to harap::io (includes no OpenMesh header, so it may be included anywhere in io/).

#include <memory>
#include <string>

namespace harap::io_internal {

/// While alive, holds the one lock for OpenMesh's process-wide state and diverts what OpenMesh
/// writes to its log streams (omerr/omlog/omout) into a buffer.
///
/// Why: OpenMesh's readers are singletons with mutable per-read members and its log streams are
/// globals that print to std::cerr/std::clog/std::cout by default. Library code must not print,
/// and two threads reading at once would corrupt the readers' state, so every use of OpenMesh
/// in io/ happens inside one of these scopes. The diverted error text goes into our exception
/// messages instead. (OpenMesh users outside io/, e.g. a decimater on another thread, that write
/// to omerr() while a capture is active write into the capture; nothing in harap relies on
/// seeing those lines.)
class OpenMeshLogCapture {
 public:
  OpenMeshLogCapture();
  ~OpenMeshLogCapture();
  OpenMeshLogCapture(const OpenMeshLogCapture&) = delete;
  OpenMeshLogCapture& operator=(const OpenMeshLogCapture&) = delete;

  /// What OpenMesh wrote to omerr() so far: distinct lines, trimmed, with "(N times)" for
  /// repeats, joined with "; " ("" if nothing).
  std::string Errors();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace harap::io_internal
