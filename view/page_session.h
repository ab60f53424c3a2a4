// SPDX-License-Identifier: MIT
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "api/session.h"
#include "framework/config.h"
#include "framework/registries.h"
#include "io/scenario.h"
#include "view/protocol.h"

namespace harap::view {

/// A message to the page: JSON text, or a binary frame (FrameKind).
struct Outgoing {
  bool binary = false;
  std::string data;
};

/// What `harap view` shows: the scenario (its mesh and handles, or a mesh alone) and the run
/// config the session starts with.
struct ViewSource {
  Scenario scenario;
  ConfigNode run_config = ConfigNode::Parse("", "<view>");
  /// The scenario's top-level keys other than its handles, as TOML lines with file names made
  /// absolute (the exported scenario starts with them), e.g. `mesh = "/data/bunny.ply"`.
  std::string mesh_toml;
  int threads = 0;
};

/// One page's deformation: its own ConfiguredSession (one per WebSocket connection, so pages
/// cannot touch each other's), its handle groups and what it last sent. Turns the page's
/// messages into session calls and answers. Not thread-safe: the server calls it from the
/// page's worker thread only; answers go to `send`, which must not block.
class PageSession {
 public:
  using Send = std::function<void(Outgoing)>;
  PageSession(const Registries& registries, const ViewSource& source, Send send);
  ~PageSession();

  /// Builds the session (hierarchy, precomputation, the scenario's handles), sending progress,
  /// then the mesh, the handles and a first full solve. A failure is sent as an error.
  void Start();
  /// Parses, validates and carries out one text message; a bad one is answered with
  /// {"type": "error", "message", "id"}. Never throws.
  void HandleText(std::string_view text);
  /// Carries out a batch of text messages that arrived together: of consecutive preview moves
  /// of one group only the last is solved (the page sees the newest targets sooner).
  void HandleTexts(const std::vector<std::string>& texts);
  /// Binary messages are refused with an error message.
  void HandleBinary(size_t size);

  MessageLimits limits() const;

 private:
  struct Group;
  void Apply(const ParsedMessage& parsed);
  void Move(const MoveMessage& move, std::optional<int64_t> id);
  void AddHandle(const AddHandleMessage& add, std::optional<int64_t> id);
  void RemoveHandle(const RemoveHandleMessage& remove, std::optional<int64_t> id);
  void Configure(const ConfigureMessage& configure, std::optional<int64_t> id);
  void Build(const ConfigNode& config);
  /// The session's handles and targets from the groups (first group wins a shared vertex).
  void ApplyGroupsAsHandles();
  Positions HandleTargets() const;
  void Solve(bool full, std::optional<int64_t> id);
  void SendPositions(const Positions& positions, int64_t solve_id);
  void SendText(const std::string& json);
  void SendError(const std::string& message, std::optional<int64_t> id);
  std::string GroupsJson() const;
  std::string ScenarioToml() const;

  const Registries& registries_;
  const ViewSource& source_;
  Send send_;
  ConfigNode config_;
  std::unique_ptr<ConfiguredSession> session_;
  std::vector<Group> groups_;
  int next_group_number_ = 1;
  std::vector<float> sent_;  ///< positions as last sent, float32
  bool session_has_handles_ = false;
};

/// The surface triangles of a mesh: its triangles, or the faces of a tetrahedral mesh that
/// belong to one tetrahedron only (oriented outwards).
Elements SurfaceTriangles(const Mesh& mesh);

}  // namespace harap::view
