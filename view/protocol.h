// SPDX-License-Identifier: MIT
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "framework/types.h"

namespace harap::view {

/// The messages the page of `harap view` sends, one JSON object per WebSocket text message
/// (docs/view.md lists them). Every message may carry an `id` (a non-negative integer) that the
/// answer repeats, so the page can match answers and time them.

/// Moves handle group `group` rigidly: its targets become `rotation · rest + translation`, where
/// `rest` are the group's positions when it was made (the scenario's targets for the scenario's
/// handles). `full`: solve to the tolerance; otherwise a preview frame (Session::Preview).
struct MoveMessage {
  int group = 0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  bool full = false;
};
/// Adds a handle group: the vertices within `radius` of vertex `vertex`'s rest position that are
/// no handle yet (as a scenario's `select.ball` with `units = "absolute"` selects them).
struct AddHandleMessage {
  Index vertex = 0;
  double radius = 0.0;
};
struct RemoveHandleMessage {
  int group = 0;
};
/// Builds the session again with other pieces; empty strings and NaN keep the current choice.
struct ConfigureMessage {
  std::string optimizer, energy, solver, preset;
  double tolerance = 0.0;  ///< 0: keep
};
/// A full solve of the current targets.
struct SolveMessage {};
/// Asks for the scenario TOML of the current handles and targets (`harap deform` reproduces it).
struct ScenarioMessage {};
/// Asks for hierarchy level `level`'s clusters (FrameKind::kClusters).
struct LevelMessage {
  int level = 0;
};

using ClientMessage = std::variant<MoveMessage, AddHandleMessage, RemoveHandleMessage,
                                   ConfigureMessage, SolveMessage, ScenarioMessage, LevelMessage>;

/// What a message is checked against: the session's sizes.
struct MessageLimits {
  Index num_vertices = 0;
  int num_groups = 0;
  int num_levels = 1;  ///< the session's hierarchy levels (0: not set up yet)
  /// Longer text messages are refused before parsing (a page's largest message is a few
  /// hundred bytes).
  size_t max_bytes = 64 * 1024;
};

struct ParsedMessage {
  std::optional<int64_t> id;
  ClientMessage message;
};

/// Parses and validates one text message from the page. Throws InputError naming the problem
/// (invalid JSON, unknown type or key, a missing or mistyped field, an index out of range, a
/// number that is not finite or out of its range, a rotation that is not one) and never
/// anything else.
ParsedMessage ParseClientMessage(std::string_view text, const MessageLimits& limits);

/// The page sends text only; a binary message is refused with this message.
std::string BinaryMessageRefusal(size_t size);

/// The `id` of a message that failed to parse, if its text is a JSON object with a valid one
/// (so the error answer can name the request); never throws.
std::optional<int64_t> MessageIdOf(std::string_view text);

/// Whether a text message, once carried out, makes a full solve still running pointless: a move
/// (its own solve follows), a solve, a configure (the session is built again) or a removed handle
/// (a full solve follows). Looks at the type only (the message is validated when it is carried
/// out); false for anything else, text that is not JSON included. Never throws.
bool SupersedesFullSolve(std::string_view text);

/// What a page asks for when it connects, in the query of its WebSocket's address
/// (`/ws?display_vertices=20000`).
struct PageOptions {
  /// Draw at most this many vertices (at least kMinDisplayVertices), or 0: the server's budget
  /// (ViewSource::display_vertices). The smaller of the two applies. A page drawn by a software
  /// renderer asks for fewer (web/app.js).
  Index display_vertices = 0;
};
inline constexpr Index kMinDisplayVertices = 100;

/// Parses the query of the WebSocket's address (the part after '?', may be empty): `key=value`
/// pairs joined by '&'. Throws InputError naming the problem (an unknown key, listing the valid
/// ones; a repeated key; a value that is not an integer in range) and never anything else.
PageOptions ParsePageQuery(std::string_view query);

/// Binary frames the server sends (little-endian). Every frame starts with a uint32 kind.
enum class FrameKind : uint32_t {
  /// kind, num_display_vertices D, num_triangles T, num_mesh_vertices V, float32 rest positions
  /// [3·D], uint32 triangles [3·T] (indices of display vertices), uint32 mesh vertex of each
  /// display vertex [D]. The display is the surface (the boundary faces of a tetrahedral mesh),
  /// decimated when it has more vertices than the display budget (DisplayMesh).
  kMesh = 1,
  /// kind, solve id, count; if count < D: uint32 display vertex indices [count]; float32
  /// positions [3·count] (only the display vertices whose float32 position changed since the
  /// last frame).
  kPositions = 2,
  /// kind, level, count D; uint32 [D]: for each display vertex the vertex of hierarchy level
  /// `level` it maps to (its cluster; 0xffffffff: none), so the page colours the clusters.
  kClusters = 3,
};

}  // namespace harap::view
