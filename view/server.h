// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "framework/registries.h"
#include "view/page_session.h"

namespace harap::view {

struct ServerOptions {
  /// The address to listen on. 127.0.0.1 (the default) accepts this machine only; anything else
  /// exposes the session to the network (`harap view` warns).
  std::string host = "127.0.0.1";
  /// 0: a free port the system picks (port() tells which).
  uint16_t port = 0;
  /// The page's files (index.html, the scripts): only these are served, read once at start.
  std::filesystem::path assets;
  /// Whether Run() stops on SIGINT and SIGTERM (`harap view`); a host with its own handlers
  /// (Python's KeyboardInterrupt) calls Stop() instead.
  bool stop_on_signals = true;
};

/// The HTTP and WebSocket server of `harap view` (Boost.Beast): serves the page's own files at
/// `/` and gives each WebSocket connection at `/ws` its own PageSession, which solves on the
/// connection's worker thread so that the network thread never waits for a solve and a solve
/// never waits for the network.
class Server {
 public:
  /// Reads the assets and binds the address; throws InputError if either fails.
  Server(const ServerOptions& options, const Registries& registries, const ViewSource& source);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  uint16_t port() const;
  /// Serves until Stop() (from any thread or a signal handler's thread); then waits for the
  /// pages' worker threads to finish their current message.
  void Run();
  void Stop();

  /// The listening socket, the page files and the pages (server.cpp).
  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// The Content-Type of a file name's extension ("application/octet-stream" if unknown).
std::string ContentType(const std::filesystem::path& file);

}  // namespace harap::view
