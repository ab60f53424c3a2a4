// SPDX-License-Identifier: MIT
#include "view/page_session.h"

#include <fmt/format.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "api/presets.h"
#include "framework/error.h"
#include "io/handle_colors.h"

namespace harap::view {

namespace {

using Json = nlohmann::json;
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void AppendU32(std::string& out, uint32_t value) {
  char bytes[4];
  std::memcpy(bytes, &value, 4);  // the server runs on little-endian machines (x86-64, arm64)
  out.append(bytes, 4);
}

void AppendFloats(std::string& out, const float* values, size_t count) {
  out.append(reinterpret_cast<const char*>(values), count * sizeof(float));
}

Json WithId(Json message, std::optional<int64_t> id) {
  if (id) message["id"] = *id;
  return message;
}

// A number JSON can hold: NaN and infinities become null.
Json Finite(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }

}  // namespace

struct PageSession::Group {
  std::string name;
  std::vector<Index> vertices;
  Positions base;  ///< the group's targets when it was made; moves transform these
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  /// A scenario handle's `weight` (finite: a soft pull); groups added on the page are hard.
  double weight = Constraints::kHardWeight;

  Positions Targets() const {
    Positions targets = base * rotation.transpose();
    targets.rowwise() += translation.transpose();
    return targets;
  }
};

PageSession::PageSession(const Registries& registries, const ViewSource& source, Send send,
                         const PageOptions& options, NewerMessageWaiting newer_message_waiting)
    : registries_(registries),
      source_(source),
      send_(std::move(send)),
      options_(options),
      newer_message_waiting_(std::move(newer_message_waiting)),
      config_(source.run_config) {
  for (const ScenarioHandle& handle : source_.scenario.handles) {
    Group group;
    group.name = handle.name;
    group.vertices = handle.vertices;
    group.base = handle.targets;
    group.weight = handle.weight;
    groups_.push_back(std::move(group));
    ++next_group_number_;
  }
}

PageSession::~PageSession() = default;

MessageLimits PageSession::limits() const {
  MessageLimits limits;
  limits.num_vertices = source_.scenario.mesh.num_vertices();
  limits.num_groups = static_cast<int>(groups_.size());
  limits.num_levels = session_ ? session_->session().num_levels() : 0;
  return limits;
}

void PageSession::SendText(const std::string& json) { send_(Outgoing{false, json}); }

void PageSession::SendError(const std::string& message, std::optional<int64_t> id) {
  SendText(WithId({{"type", "error"}, {"message", message}}, id).dump());
}

void PageSession::Start() {
  const Mesh& mesh = source_.scenario.mesh;
  const Index budget = options_.display_vertices > 0
                           ? std::min(options_.display_vertices, source_.display_vertices)
                           : source_.display_vertices;
  if (mesh.num_vertices() > budget) {
    SendText(Json{{"type", "status"},
                  {"stage", fmt::format("decimating the display to at most {} vertices", budget)}}
                 .dump());
  }
  display_ = MakeDisplayMesh(mesh, budget);
  {
    // The mesh first, so the page draws while the session is set up.
    std::string frame;
    AppendU32(frame, static_cast<uint32_t>(FrameKind::kMesh));
    AppendU32(frame, static_cast<uint32_t>(display_.vertices.size()));
    AppendU32(frame, static_cast<uint32_t>(display_.triangles.rows()));
    AppendU32(frame, static_cast<uint32_t>(mesh.num_vertices()));
    for (const Index v : display_.vertices) {
      const Eigen::RowVector3f rest = mesh.vertices.row(v).cast<float>();
      AppendFloats(frame, rest.data(), 3);
    }
    for (Eigen::Index f = 0; f < display_.triangles.rows(); ++f) {
      for (int k = 0; k < 3; ++k) AppendU32(frame, static_cast<uint32_t>(display_.triangles(f, k)));
    }
    for (const Index v : display_.vertices) AppendU32(frame, static_cast<uint32_t>(v));
    send_(Outgoing{true, std::move(frame)});
  }
  Json options;
  options["optimizers"] = Json::array({"classic", "hierarchical"});
  options["energies"] = registries_.energies.Names();
  options["solvers"] = registries_.linear_solvers.Names();
  Json presets = Json::array({""});
  for (const Preset& preset : Presets()) presets.push_back(preset.name);
  options["presets"] = presets;
  SendText(Json{{"type", "mesh"},
                {"source", source_.scenario.mesh_source},
                {"vertices", mesh.num_vertices()},
                {"elements", mesh.num_elements()},
                {"tetrahedral", mesh.kind() == ElementKind::kTetrahedron},
                {"display_vertices", display_.vertices.size()},
                {"display_triangles", display_.triangles.rows()},
                {"choices", options}}
               .dump());
  try {
    Build(config_);
    if (!groups_.empty()) Solve(true, std::nullopt);
  } catch (const std::exception& error) {
    SendError(fmt::format("setting up the session failed: {}", error.what()), std::nullopt);
  }
}

void PageSession::Build(const ConfigNode& config) {
  const Clock::time_point start = Clock::now();
  SendText(
      Json{{"type", "status"}, {"stage", "setting up: hierarchy, precomputation and factorization"}}
          .dump());
  std::unique_ptr<ConfiguredSession> session =
      MakeSession(registries_, source_.scenario.mesh, config, source_.threads,
                  SessionOptions::FrameStart::kCorrected, source_.scenario.ElementStiffness());
  const Positions previous = session_ ? session_->session().positions() : Positions();
  session_ = std::move(session);
  config_ = config;
  session_has_handles_ = false;
  if (previous.rows() > 0) session_->session().SetPositions(previous);
  Json edit = nullptr;
  if (!groups_.empty()) {
    ApplyGroupsAsHandles();
  }
  const DeformationSession& s = session_->session();
  const PhaseTimings& setup = s.setup_timings();
  SendText(Json{{"type", "ready"},
                {"optimizer", session_->optimizer()},
                {"energy", session_->energy_name()},
                {"solver", session_->solver_name()},
                {"levels", s.num_levels()},
                {"solved_levels", s.solved_levels()},
                {"config", session_->resolved_config()},
                {"mesh_summary", session_->mesh_summary()},
                {"setup",
                 {{"hierarchy", setup.hierarchy},
                  {"precompute", setup.precompute},
                  {"seconds", SecondsSince(start)}}}}
               .dump());
  SendText(GroupsJson());
}

std::string PageSession::GroupsJson() const {
  Json groups = Json::array();
  for (size_t g = 0; g < groups_.size(); ++g) {
    const Group& group = groups_[g];
    unsigned char rgb[3];
    std::string color_name;
    HandleColor(g, rgb, &color_name);
    const Eigen::Vector3d center = group.base.colwise().mean().transpose();
    groups.push_back(
        {{"name", group.name},
         {"vertices", group.vertices},
         {"color", {rgb[0], rgb[1], rgb[2]}},
         {"color_name", color_name},
         {"center", {center.x(), center.y(), center.z()}},
         {"rotation",
          {group.rotation(0, 0), group.rotation(0, 1), group.rotation(0, 2), group.rotation(1, 0),
           group.rotation(1, 1), group.rotation(1, 2), group.rotation(2, 0), group.rotation(2, 1),
           group.rotation(2, 2)}},
         {"translation", {group.translation.x(), group.translation.y(), group.translation.z()}}});
  }
  return Json{{"type", "handles"}, {"groups", groups}}.dump();
}

Positions PageSession::HandleTargets() const {
  // Each session handle's target from the first group that holds the vertex.
  std::map<Index, Eigen::RowVector3d> target_of;
  for (const Group& group : groups_) {
    const Positions targets = group.Targets();
    for (size_t i = 0; i < group.vertices.size(); ++i)
      target_of.emplace(group.vertices[i], targets.row(static_cast<Eigen::Index>(i)));
  }
  const std::vector<Index>& handles = session_->session().handles();
  Positions targets(static_cast<Eigen::Index>(handles.size()), 3);
  for (size_t i = 0; i < handles.size(); ++i)
    targets.row(static_cast<Eigen::Index>(i)) = target_of.at(handles[i]);
  return targets;
}

void PageSession::ApplyGroupsAsHandles() {
  DeformationSession& session = session_->session();
  std::set<Index> wanted;
  std::map<Index, Eigen::RowVector3d> target_of;
  std::map<Index, double> weight_of;  // as the target: the first group's
  for (const Group& group : groups_) {
    const Positions targets = group.Targets();
    for (size_t i = 0; i < group.vertices.size(); ++i) {
      wanted.insert(group.vertices[i]);
      target_of.emplace(group.vertices[i], targets.row(static_cast<Eigen::Index>(i)));
      weight_of.emplace(group.vertices[i], group.weight);
    }
  }
  if (wanted.empty()) throw InputError("at least one handle must stay");
  const auto targets_of = [&](const std::vector<Index>& indices) {
    Positions targets(static_cast<Eigen::Index>(indices.size()), 3);
    for (size_t i = 0; i < indices.size(); ++i)
      targets.row(static_cast<Eigen::Index>(i)) = target_of.at(indices[i]);
    return targets;
  };
  Json edits = Json::array();
  const Clock::time_point start = Clock::now();
  if (!session_has_handles_) {
    const std::vector<Index> indices(wanted.begin(), wanted.end());
    // The scenario's soft handles stay soft (handles added later on the page are hard).
    std::vector<double> weights;
    for (Index v : indices) weights.push_back(weight_of.at(v));
    edits.push_back(
        Json::parse(HandleEditJson(session.SetHandles(indices, targets_of(indices), weights))));
    session_has_handles_ = true;
  } else {
    const std::set<Index> current(session.handles().begin(), session.handles().end());
    std::vector<Index> added, removed;
    std::set_difference(wanted.begin(), wanted.end(), current.begin(), current.end(),
                        std::back_inserter(added));
    std::set_difference(current.begin(), current.end(), wanted.begin(), wanted.end(),
                        std::back_inserter(removed));
    // Add first, so that "at least one handle stays" holds during the removal.
    if (!added.empty())
      edits.push_back(Json::parse(HandleEditJson(session.AddHandles(added, targets_of(added)))));
    if (!removed.empty())
      edits.push_back(Json::parse(HandleEditJson(session.RemoveHandles(removed))));
    session.SetTargets(HandleTargets());
  }
  SendText(Json{{"type", "edit"}, {"edits", edits}, {"seconds", SecondsSince(start)}}.dump());
}

void PageSession::HandleBinary(size_t size) { SendError(BinaryMessageRefusal(size), std::nullopt); }

void PageSession::HandleText(std::string_view text) { HandleTexts({std::string(text)}); }

void PageSession::HandleTexts(const std::vector<std::string>& texts) {
  std::vector<ParsedMessage> parsed;
  // A message before the batch's last superseding one (SupersedesFullSolve) has its full solve
  // made pointless by it.
  size_t superseding_end = 0;
  for (const std::string& text : texts) {
    try {
      parsed.push_back(ParseClientMessage(text, limits()));
    } catch (const std::exception& error) {
      SendError(error.what(), MessageIdOf(text));
      continue;
    }
    if (SupersedesFullSolve(text)) superseding_end = parsed.size() - 1;
  }
  for (size_t i = 0; i < parsed.size(); ++i) {
    const auto* move = std::get_if<MoveMessage>(&parsed[i].message);
    if (move && !move->full && i + 1 < parsed.size()) {
      const auto* next = std::get_if<MoveMessage>(&parsed[i + 1].message);
      if (next && next->group == move->group) {
        // A newer move of the same group follows: it supersedes this one's targets.
        if (!next->full) continue;
      }
    }
    try {
      // Messages parsed in one batch were checked against the limits before it; an earlier
      // message of the batch may have removed a group.
      const MessageLimits now = limits();
      if (const auto* m = std::get_if<MoveMessage>(&parsed[i].message);
          m && m->group >= now.num_groups)
        throw InputError(fmt::format("message 'move': group {} no longer exists", m->group));
      if (const auto* r = std::get_if<RemoveHandleMessage>(&parsed[i].message);
          r && r->group >= now.num_groups)
        throw InputError(
            fmt::format("message 'remove_handle': group {} no longer exists", r->group));
      superseded_within_batch_ = i < superseding_end;
      Apply(parsed[i]);
    } catch (const std::exception& error) {
      SendError(error.what(), parsed[i].id);
    }
  }
  superseded_within_batch_ = false;
  // A superseding message that stopped a full solve was carried out after it (later in this
  // batch) or waits for the next batch. If it was refused (a move of a group that no longer
  // exists, say), nothing superseded the solve: it continues from the positions it reached, once
  // no superseding message waits.
  if (full_solve_owed_ && !SupersedingMessageWaits()) {
    try {
      Solve(true, owed_solve_id_);
    } catch (const std::exception& error) {
      SendError(error.what(), owed_solve_id_);
    }
  }
}

void PageSession::Apply(const ParsedMessage& parsed) {
  const std::optional<int64_t> id = parsed.id;
  if (!session_) throw InputError("the session is not set up (see the error above)");
  std::visit(
      [&](const auto& message) {
        using T = std::decay_t<decltype(message)>;
        if constexpr (std::is_same_v<T, MoveMessage>) {
          Move(message, id);
        } else if constexpr (std::is_same_v<T, AddHandleMessage>) {
          AddHandle(message, id);
        } else if constexpr (std::is_same_v<T, RemoveHandleMessage>) {
          RemoveHandle(message, id);
        } else if constexpr (std::is_same_v<T, ConfigureMessage>) {
          Configure(message, id);
        } else if constexpr (std::is_same_v<T, SolveMessage>) {
          if (groups_.empty()) throw InputError("message 'solve': there is no handle yet");
          Solve(true, id);
        } else if constexpr (std::is_same_v<T, ScenarioMessage>) {
          SendText(WithId({{"type", "scenario"}, {"toml", ScenarioToml()}}, id).dump());
        } else if constexpr (std::is_same_v<T, LevelMessage>) {
          SendClusters(message.level);
        }
      },
      parsed.message);
}

void PageSession::Move(const MoveMessage& move, std::optional<int64_t> id) {
  Group& group = groups_[static_cast<size_t>(move.group)];
  group.rotation = move.rotation;
  group.translation = move.translation;
  session_->session().SetTargets(HandleTargets());
  Solve(move.full, id);
}

void PageSession::AddHandle(const AddHandleMessage& add, std::optional<int64_t> id) {
  const Mesh& mesh = source_.scenario.mesh;
  const std::vector<bool> referenced = ReferencedVertices(mesh);
  const Eigen::RowVector3d center = mesh.vertices.row(add.vertex);
  Group group;
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (referenced[static_cast<size_t>(v)] && (mesh.vertices.row(v) - center).norm() <= add.radius)
      group.vertices.push_back(v);
  }
  if (group.vertices.empty()) group.vertices.push_back(add.vertex);
  // The new handle holds its vertices where they are now.
  const Positions& current = session_->session().positions();
  group.base.resize(static_cast<Eigen::Index>(group.vertices.size()), 3);
  for (size_t i = 0; i < group.vertices.size(); ++i)
    group.base.row(static_cast<Eigen::Index>(i)) = current.row(group.vertices[i]);
  group.name = fmt::format("handle {}", next_group_number_++);
  groups_.push_back(std::move(group));
  try {
    ApplyGroupsAsHandles();
  } catch (...) {
    groups_.pop_back();
    throw;
  }
  SendText(WithId(Json::parse(GroupsJson()), id).dump());
}

void PageSession::RemoveHandle(const RemoveHandleMessage& remove, std::optional<int64_t> id) {
  if (groups_.size() == 1) throw InputError("message 'remove_handle': the last handle must stay");
  const auto it = groups_.begin() + remove.group;
  Group removed = std::move(*it);
  groups_.erase(it);
  try {
    ApplyGroupsAsHandles();
  } catch (...) {
    groups_.insert(groups_.begin() + remove.group, std::move(removed));
    throw;
  }
  SendText(WithId(Json::parse(GroupsJson()), id).dump());
  Solve(true, id);
}

void PageSession::Configure(const ConfigureMessage& configure, std::optional<int64_t> id) {
  // A copy: the page may configure again, from the source's options, not from these.
  ConfigNode config = source_.run_config.Clone();
  const auto set_type = [&](const char* table, const std::string& name) {
    if (!name.empty()) config.Set(fmt::format("{}.type", table), Json(name).dump());
  };
  set_type("optimizer", configure.optimizer);
  set_type("energy", configure.energy);
  set_type("solver", configure.solver);
  if (configure.tolerance > 0.0)
    config.Set("optimizer.tolerance", fmt::format("{:.17g}", configure.tolerance));
  ApplyPreset(config, configure.preset);
  Build(config);
  if (!groups_.empty()) Solve(true, id);
}

bool PageSession::SupersedingMessageWaits() const {
  return newer_message_waiting_ && newer_message_waiting_();
}

void PageSession::Solve(bool full, std::optional<int64_t> id) {
  DeformationSession& session = session_->session();
  full_solve_owed_ = false;  // this solve supersedes a stopped one
  Json trace = Json::array();
  const Clock::time_point start = Clock::now();
  session.set_iteration_callback([&](const IterationSummary& s) {
    trace.push_back({s.seconds, Finite(s.energy), s.level});
    // A full solve after a release can take seconds; a drag, a removal or another solve that the
    // page sent meanwhile must not wait for it. The session keeps the positions the stop leaves.
    const bool give_way = full && (superseded_within_batch_ || SupersedingMessageWaits());
    return give_way ? CallbackAction::kStop : CallbackAction::kContinue;
  });
  const OptimizeResult result = full ? session.Solve() : session.Preview();
  session.set_iteration_callback({});
  const double seconds = SecondsSince(start);
  const bool interrupted = full && result.stopped_by_callback;
  if (interrupted) {
    full_solve_owed_ = true;
    owed_solve_id_ = id;
  }
  SendPositions(result.positions, id.value_or(0));
  Json levels = Json::array();
  for (const LevelResult& level : result.levels)
    levels.push_back({{"level", level.level}, {"iterations", level.iterations}});
  SendText(WithId({{"type", "solved"},
                   {"mode", full ? "full" : "preview"},
                   {"energy", Finite(result.energy)},
                   {"iterations", result.iterations},
                   {"total_iterations", result.total_iterations},
                   {"converged", result.converged},
                   {"interrupted", interrupted},
                   {"seconds", seconds},
                   {"levels", levels},
                   {"trace", trace},
                   {"notes", result.notes}},
                  id)
               .dump());
}

void PageSession::SendClusters(int level) {
  // The session's own hierarchy (the paper's i ~_l j composed down to the finest level).
  const MeshHierarchy& hierarchy = session_->session().hierarchy();
  std::string frame;
  AppendU32(frame, static_cast<uint32_t>(FrameKind::kClusters));
  AppendU32(frame, static_cast<uint32_t>(level));
  AppendU32(frame, static_cast<uint32_t>(display_.vertices.size()));
  for (const Index v : display_.vertices) {
    const Index coarse =
        level < hierarchy.num_levels() ? session_->session().CoarseVertex(v, level) : v;
    AppendU32(frame, coarse == kNoVertex ? 0xffffffffu : static_cast<uint32_t>(coarse));
  }
  send_(Outgoing{true, std::move(frame)});
}

void PageSession::SendPositions(const Positions& positions, int64_t solve_id) {
  // Only the display's vertices: the page draws nothing else.
  const size_t n = display_.vertices.size();
  std::vector<float> now(3 * n);
  for (size_t v = 0; v < n; ++v) {
    for (int k = 0; k < 3; ++k)
      now[3 * v + static_cast<size_t>(k)] = static_cast<float>(positions(display_.vertices[v], k));
  }
  std::vector<uint32_t> changed;
  if (sent_.size() == now.size()) {
    for (size_t v = 0; v < n; ++v) {
      if (std::memcmp(&now[3 * v], &sent_[3 * v], 3 * sizeof(float)) != 0)
        changed.push_back(static_cast<uint32_t>(v));
    }
  }
  std::string frame;
  AppendU32(frame, static_cast<uint32_t>(FrameKind::kPositions));
  AppendU32(frame, static_cast<uint32_t>(solve_id & 0xffffffff));
  // Indices and positions cost 16 bytes a vertex, the whole array 12: past 3/4 changed, send all.
  if (sent_.size() != now.size() || changed.size() * 4 > n * 3) {
    AppendU32(frame, static_cast<uint32_t>(n));
    AppendFloats(frame, now.data(), now.size());
  } else {
    AppendU32(frame, static_cast<uint32_t>(changed.size()));
    for (const uint32_t v : changed) AppendU32(frame, v);
    for (const uint32_t v : changed) AppendFloats(frame, &now[3 * v], 3);
  }
  sent_ = std::move(now);
  send_(Outgoing{true, std::move(frame)});
}

std::string PageSession::ScenarioToml() const {
  std::string toml =
      "# Written by `harap view`: the mesh and the handles with their targets as the page left "
      "them.\n# `harap deform` on this file solves the same problem.\n";
  toml += source_.mesh_toml;
  for (const Group& group : groups_) {
    const Positions targets = group.Targets();
    // The group's motion as the scenario's rigid motion: target = R p + t with `rest` p.
    const Mesh& mesh = source_.scenario.mesh;
    Positions rest(static_cast<Eigen::Index>(group.vertices.size()), 3);
    for (size_t i = 0; i < group.vertices.size(); ++i)
      rest.row(static_cast<Eigen::Index>(i)) = mesh.vertices.row(group.vertices[i]);
    // Kabsch: the rotation and translation that map the rest positions to the targets best.
    const Eigen::RowVector3d rest_mean = rest.colwise().mean(),
                             target_mean = targets.colwise().mean();
    const Eigen::Matrix3d covariance =
        (rest.rowwise() - rest_mean).transpose() * (targets.rowwise() - target_mean);
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
    d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
    const Eigen::Matrix3d rotation = svd.matrixV() * d * svd.matrixU().transpose();
    const Eigen::Vector3d translation = target_mean.transpose() - rotation * rest_mean.transpose();
    Positions fitted = rest * rotation.transpose();
    fitted.rowwise() += translation.transpose();
    const double residual = (fitted - targets).rowwise().norm().maxCoeff();
    if (!(residual <= 1e-9 * std::max(1.0, BoundingBoxDiagonal(mesh)))) {
      throw InputError(fmt::format(
          "handle '{}': its targets are not a rigid motion of its rest vertices (off by {:.3g}), "
          "which a scenario's rotate and translate cannot write",
          group.name, residual));
    }
    const Eigen::AngleAxisd angle_axis(rotation);
    toml += fmt::format("\n[[handle]]\nname = {}\nunits = \"absolute\"\nselect.indices = [",
                        Json(group.name).dump());
    for (size_t i = 0; i < group.vertices.size(); ++i)
      toml += fmt::format("{}{}", i ? ", " : "", group.vertices[i]);
    toml += "]\n";
    const Eigen::Vector3d axis = angle_axis.axis();
    toml += fmt::format(
        "rotate = {{ axis = [{:.17g}, {:.17g}, {:.17g}], degrees = {:.17g}, center = [0.0, 0.0, "
        "0.0] }}\ntranslate = [{:.17g}, {:.17g}, {:.17g}]\n",
        axis.x(), axis.y(), axis.z(), angle_axis.angle() * 180.0 / M_PI, translation.x(),
        translation.y(), translation.z());
    if (group.weight != Constraints::kHardWeight) {
      toml += fmt::format("weight = {:.17g}\n", group.weight);
    }
  }
  return toml;
}

DisplayMesh MakeDisplayMesh(const Mesh& mesh, Index budget) {
  const Elements surface = SurfaceTriangles(mesh);
  std::vector<unsigned int> indices(static_cast<size_t>(surface.size()));
  for (Eigen::Index f = 0; f < surface.rows(); ++f) {
    for (int k = 0; k < 3; ++k)
      indices[3 * static_cast<size_t>(f) + static_cast<size_t>(k)] =
          static_cast<unsigned int>(surface(f, k));
  }
  const auto count_vertices = [&](const std::vector<unsigned int>& triangles) {
    std::vector<bool> used(static_cast<size_t>(mesh.num_vertices()), false);
    Index count = 0;
    for (const unsigned int v : triangles) {
      if (!used[v]) ++count;
      used[v] = true;
    }
    return count;
  };
  const Index surface_vertices = count_vertices(indices);
  if (surface_vertices > budget && budget >= 3) {
    const Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor> positions =
        mesh.vertices.cast<float>();
    std::vector<unsigned int> simplified(indices.size());
    // A surface has about twice as many triangles as vertices: ask for the budget's share of the
    // indices; edge collapses can stop short of it (borders, thin parts), then the sloppy
    // simplifier (vertex clustering) reaches it, and a smaller target is asked while it does not.
    double fraction = static_cast<double>(budget) / static_cast<double>(surface_vertices);
    for (int attempt = 0; attempt < 8; ++attempt) {
      const size_t target = std::max<size_t>(
          3, 3 * static_cast<size_t>(fraction * static_cast<double>(indices.size() / 3)));
      size_t count = meshopt_simplify(simplified.data(), indices.data(), indices.size(),
                                      positions.data(), static_cast<size_t>(positions.rows()),
                                      3 * sizeof(float), target, 1.0f, 0, nullptr);
      if (count > target + target / 10) {
        count = meshopt_simplifySloppy(simplified.data(), indices.data(), indices.size(),
                                       positions.data(), static_cast<size_t>(positions.rows()),
                                       3 * sizeof(float), target, 1.0f, nullptr);
      }
      simplified.resize(count);
      const Index kept = count_vertices(simplified);
      if (kept <= budget && count > 0) {
        indices = std::move(simplified);
        break;
      }
      fraction *= 0.8 * static_cast<double>(budget) / static_cast<double>(std::max<Index>(kept, 1));
      simplified.resize(indices.size());
    }
  }
  DisplayMesh display;
  std::vector<Index> display_index(static_cast<size_t>(mesh.num_vertices()), -1);
  for (const unsigned int v : indices) display_index[v] = 0;
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (display_index[static_cast<size_t>(v)] < 0) continue;
    display_index[static_cast<size_t>(v)] = static_cast<Index>(display.vertices.size());
    display.vertices.push_back(v);
  }
  display.triangles.resize(static_cast<Eigen::Index>(indices.size() / 3), 3);
  for (size_t i = 0; i < indices.size(); ++i)
    display.triangles(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3)) =
        display_index[indices[i]];
  return display;
}

Elements SurfaceTriangles(const Mesh& mesh) {
  if (mesh.kind() == ElementKind::kTriangle) return mesh.elements;
  // Each tetrahedron's faces, oriented outwards for a positively oriented tetrahedron (the
  // readers orient them so); a face shared by two tetrahedra is inside.
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::map<std::array<Index, 3>, std::pair<int, std::array<Index, 3>>> faces;
  for (Eigen::Index t = 0; t < mesh.elements.rows(); ++t) {
    for (const auto& face : kFaces) {
      std::array<Index, 3> oriented{mesh.elements(t, face[0]), mesh.elements(t, face[1]),
                                    mesh.elements(t, face[2])};
      std::array<Index, 3> key = oriented;
      std::sort(key.begin(), key.end());
      auto [it, inserted] = faces.try_emplace(key, 0, oriented);
      ++it->second.first;
    }
  }
  std::vector<std::array<Index, 3>> surface;
  for (const auto& [key, value] : faces) {
    if (value.first == 1) surface.push_back(value.second);
  }
  Elements triangles(static_cast<Eigen::Index>(surface.size()), 3);
  for (size_t f = 0; f < surface.size(); ++f) {
    for (int k = 0; k < 3; ++k) triangles(static_cast<Eigen::Index>(f), k) = surface[f][k];
  }
  return triangles;
}

}  // namespace harap::view
