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
  /// The page draws at most this many vertices: a larger surface is decimated for the display
  /// (DisplayMesh); the session always solves the whole mesh.
  Index display_vertices = 200000;
};

/// What the page draws: triangles over a subset of the mesh's vertices.
struct DisplayMesh {
  std::vector<Index> vertices;  ///< mesh vertex of each display vertex, ascending
  Elements triangles;           ///< indices into `vertices`
};

/// The surface (SurfaceTriangles) as a display mesh of at most `budget` vertices: all of it when
/// it has no more, otherwise simplified by meshoptimizer (edge collapses onto existing vertices,
/// so each display vertex is a mesh vertex whose solved position the page is sent).
DisplayMesh MakeDisplayMesh(const Mesh& mesh, Index budget);

/// One page's deformation: its own ConfiguredSession (one per WebSocket connection, so pages
/// cannot touch each other's), its handle groups and what it last sent. Turns the page's
/// messages into session calls and answers. Not thread-safe: the server calls it from the
/// page's worker thread only; answers go to `send`, which must not block.
class PageSession {
 public:
  using Send = std::function<void(Outgoing)>;
  /// Whether the page sent a message that makes a running full solve pointless
  /// (SupersedesFullSolve) or closed: the solve then stops after its current iteration; if the
  /// message is refused after all, the solve is resumed once the messages are handled.
  using NewerMessageWaiting = std::function<bool()>;
  /// `options`: what the page asked for when it connected (ParsePageQuery). Without
  /// `newer_message_waiting` only a superseding message of the same batch stops a full solve.
  PageSession(const Registries& registries, const ViewSource& source, Send send,
              const PageOptions& options = {}, NewerMessageWaiting newer_message_waiting = {});
  ~PageSession();

  /// Builds the session (hierarchy, precomputation, the scenario's handles), sending progress,
  /// then the mesh, the handles and a first full solve. A failure is sent as an error.
  void Start();
  /// Parses, validates and carries out one text message; a bad one is answered with
  /// {"type": "error", "message", "id"}. Never throws.
  void HandleText(std::string_view text);
  /// Carries out a batch of text messages that arrived together: of consecutive preview moves
  /// of one group only the last is solved (the page sees the newest targets sooner); a full
  /// solve followed by a superseding message of the batch stops after one iteration. Then, once
  /// no superseding message waits, a stopped full solve that no later solve superseded (its
  /// stopping message was refused) runs again from where it stopped, answering with its own id.
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
  /// A preview (`full` false) or a full solve to the tolerance, answered with the positions
  /// and a "solved" message; a full solve stops early when a superseding message waits or
  /// follows in the batch ("interrupted": true), and is owed until another solve starts.
  void Solve(bool full, std::optional<int64_t> id);
  /// The server's NewerMessageWaiting, false without one.
  bool SupersedingMessageWaits() const;
  /// Level `level`'s clusters as a FrameKind::kClusters frame.
  void SendClusters(int level);
  void SendPositions(const Positions& positions, int64_t solve_id);
  void SendText(const std::string& json);
  void SendError(const std::string& message, std::optional<int64_t> id);
  std::string GroupsJson() const;
  std::string ScenarioToml() const;

  const Registries& registries_;
  const ViewSource& source_;
  Send send_;
  PageOptions options_;
  NewerMessageWaiting newer_message_waiting_;
  /// A full solve that a superseding message stopped is owed until another solve starts; it is
  /// resumed, with the id of the message that asked for it, after a batch of messages once no
  /// superseding message waits (the one that stopped it was refused).
  bool full_solve_owed_ = false;
  std::optional<int64_t> owed_solve_id_;
  /// While a batch's message is carried out: a later message of the batch supersedes its solve.
  bool superseded_within_batch_ = false;
  ConfigNode config_;
  std::unique_ptr<ConfiguredSession> session_;
  std::vector<Group> groups_;
  int next_group_number_ = 1;
  DisplayMesh display_;
  std::vector<float> sent_;  ///< display positions as last sent, float32
  bool session_has_handles_ = false;
};

/// The surface triangles of a mesh: its triangles, or the faces of a tetrahedral mesh that
/// belong to one tetrahedron only (oriented outwards).
Elements SurfaceTriangles(const Mesh& mesh);

}  // namespace harap::view
