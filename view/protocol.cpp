// SPDX-License-Identifier: MIT
#include "view/protocol.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

#include "framework/error.h"

namespace harap::view {

namespace {

using Json = nlohmann::json;

// A rotation from the page is a float32 matrix that went through three.js' quaternion: columns
// orthonormal to about 1e-7. 1e-4 accepts that and refuses shears and scales.
constexpr double kRotationTolerance = 1e-4;
// Coordinates beyond this are not a mesh's; refusing them keeps float32 frames finite.
constexpr double kMaxCoordinate = 1e30;

struct Fields {
  const Json& object;
  std::string type;
  std::set<std::string> allowed{"type", "id"};

  const Json& Required(const std::string& key) {
    allowed.insert(key);
    const auto it = object.find(key);
    if (it == object.end())
      throw InputError(fmt::format("message '{}': missing field '{}'", type, key));
    return *it;
  }
  const Json* Optional(const std::string& key) {
    allowed.insert(key);
    const auto it = object.find(key);
    return it == object.end() ? nullptr : &*it;
  }
  void RejectUnknown() const {
    for (const auto& [key, value] : object.items()) {
      if (!allowed.count(key)) {
        std::string valid;
        for (const auto& name : allowed) valid += (valid.empty() ? "" : ", ") + name;
        throw InputError(
            fmt::format("message '{}': unknown field '{}' (valid: {})", type, key, valid));
      }
    }
  }
  int64_t Integer(const std::string& key, int64_t lowest, int64_t highest) {
    const Json& value = Required(key);
    if (!value.is_number_integer())
      throw InputError(fmt::format("message '{}': '{}' must be an integer", type, key));
    const int64_t number = value.is_number_unsigned() && value.get<uint64_t>() > INT64_MAX
                               ? INT64_MAX
                               : value.get<int64_t>();
    if (number < lowest || number > highest) {
      throw InputError(fmt::format("message '{}': '{}' = {} is out of range [{}, {}]", type, key,
                                   number, lowest, highest));
    }
    return number;
  }
  double Number(const Json& value, const std::string& what) const {
    if (!value.is_number())
      throw InputError(fmt::format("message '{}': {} must be a number", type, what));
    const double number = value.get<double>();
    if (!std::isfinite(number) || std::abs(number) > kMaxCoordinate)
      throw InputError(
          fmt::format("message '{}': {} = {} is not a finite coordinate", type, what, number));
    return number;
  }
  std::string String(const std::string& key) {
    const Json* value = Optional(key);
    if (!value) return {};
    if (!value->is_string())
      throw InputError(fmt::format("message '{}': '{}' must be a string", type, key));
    std::string text = value->get<std::string>();
    if (text.size() > 64)
      throw InputError(fmt::format("message '{}': '{}' is longer than 64 characters", type, key));
    return text;
  }
};

MoveMessage ParseMove(Fields& fields, const MessageLimits& limits) {
  MoveMessage move;
  if (limits.num_groups == 0) throw InputError("message 'move': there is no handle to move");
  move.group = static_cast<int>(fields.Integer("group", 0, limits.num_groups - 1));
  const Json& transform = fields.Required("transform");
  if (!transform.is_array() || transform.size() != 12) {
    throw InputError(
        "message 'move': 'transform' must be an array of 12 numbers (a 3×4 matrix [R | t], "
        "row by row)");
  }
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      const double value = fields.Number(transform[static_cast<size_t>(4 * r + c)],
                                         fmt::format("transform[{}]", 4 * r + c));
      if (c < 3)
        move.rotation(r, c) = value;
      else
        move.translation[r] = value;
    }
  }
  const double orthogonality =
      (move.rotation.transpose() * move.rotation - Eigen::Matrix3d::Identity()).norm();
  if (!(orthogonality <= kRotationTolerance) || move.rotation.determinant() <= 0.0) {
    throw InputError(fmt::format(
        "message 'move': the 3×3 part of 'transform' is not a rotation (‖RᵀR − I‖ = {:.3g}, "
        "det = {:.3g}); handles move rigidly",
        orthogonality, move.rotation.determinant()));
  }
  if (const Json* solve = fields.Optional("solve")) {
    if (!solve->is_string() || (*solve != "preview" && *solve != "full"))
      throw InputError("message 'move': 'solve' must be \"preview\" or \"full\"");
    move.full = *solve == "full";
  }
  return move;
}

AddHandleMessage ParseAddHandle(Fields& fields, const MessageLimits& limits) {
  AddHandleMessage add;
  add.vertex = static_cast<Index>(fields.Integer("vertex", 0, limits.num_vertices - 1));
  add.radius = fields.Number(fields.Required("radius"), "'radius'");
  if (add.radius < 0.0)
    throw InputError(fmt::format("message 'add_handle': 'radius' = {} is negative", add.radius));
  return add;
}

ConfigureMessage ParseConfigure(Fields& fields) {
  ConfigureMessage configure;
  configure.optimizer = fields.String("optimizer");
  configure.energy = fields.String("energy");
  configure.solver = fields.String("solver");
  configure.preset = fields.String("preset");
  if (const Json* tolerance = fields.Optional("tolerance")) {
    configure.tolerance = fields.Number(*tolerance, "'tolerance'");
    if (!(configure.tolerance > 0.0 && configure.tolerance < 1.0)) {
      throw InputError(fmt::format("message 'configure': 'tolerance' = {} is not in (0, 1)",
                                   configure.tolerance));
    }
  }
  return configure;
}

}  // namespace

ParsedMessage ParseClientMessage(std::string_view text, const MessageLimits& limits) {
  if (text.size() > limits.max_bytes) {
    throw InputError(
        fmt::format("message of {} bytes refused (at most {})", text.size(), limits.max_bytes));
  }
  Json object = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (object.is_discarded()) throw InputError("message is not valid JSON");
  if (!object.is_object()) throw InputError("message is not a JSON object");
  const auto type_it = object.find("type");
  if (type_it == object.end() || !type_it->is_string())
    throw InputError("message has no string field 'type'");
  Fields fields{object, type_it->get<std::string>()};
  ParsedMessage parsed;
  if (const Json* id = fields.Optional("id")) {
    if (!id->is_number_integer() ||
        (id->is_number_integer() && !id->is_number_unsigned() && id->get<int64_t>() < 0))
      throw InputError(
          fmt::format("message '{}': 'id' must be a non-negative integer", fields.type));
    parsed.id = id->is_number_unsigned() && id->get<uint64_t>() > INT64_MAX ? INT64_MAX
                                                                            : id->get<int64_t>();
  }
  const std::string& type = fields.type;
  if (type == "move") {
    parsed.message = ParseMove(fields, limits);
  } else if (type == "add_handle") {
    parsed.message = ParseAddHandle(fields, limits);
  } else if (type == "remove_handle") {
    if (limits.num_groups == 0) throw InputError("message 'remove_handle': there is no handle");
    parsed.message =
        RemoveHandleMessage{static_cast<int>(fields.Integer("group", 0, limits.num_groups - 1))};
  } else if (type == "configure") {
    parsed.message = ParseConfigure(fields);
  } else if (type == "solve") {
    parsed.message = SolveMessage{};
  } else if (type == "scenario") {
    parsed.message = ScenarioMessage{};
  } else if (type == "level") {
    if (limits.num_levels < 1) throw InputError("message 'level': the session is not set up");
    parsed.message =
        LevelMessage{static_cast<int>(fields.Integer("level", 0, limits.num_levels - 1))};
  } else {
    throw InputError(fmt::format(
        "unknown message type '{}' (valid: move, add_handle, remove_handle, configure, solve, "
        "scenario, level)",
        type.substr(0, 64)));
  }
  fields.RejectUnknown();
  return parsed;
}

PageOptions ParsePageQuery(std::string_view query) {
  PageOptions options;
  bool display_seen = false;
  while (!query.empty()) {
    const size_t end = query.find('&');
    const std::string_view pair = query.substr(0, end);
    query = end == std::string_view::npos ? std::string_view() : query.substr(end + 1);
    if (pair.empty()) continue;  // "a&&b", a trailing '&': as a browser's URLSearchParams
    const size_t equals = pair.find('=');
    const std::string_view key = pair.substr(0, equals);
    const std::string_view value =
        equals == std::string_view::npos ? std::string_view() : pair.substr(equals + 1);
    if (key != "display_vertices") {
      throw InputError(fmt::format(
          "the page's WebSocket address: unknown parameter '{}'; valid: display_vertices",
          key.substr(0, 64)));
    }
    if (display_seen) {
      throw InputError("the page's WebSocket address: display_vertices is given twice");
    }
    display_seen = true;
    Index vertices = 0;
    const auto [rest, error] = std::from_chars(value.data(), value.data() + value.size(), vertices);
    if (value.empty() || error != std::errc() || rest != value.data() + value.size() ||
        vertices < kMinDisplayVertices) {
      throw InputError(fmt::format(
          "the page's WebSocket address: display_vertices = '{}' is not an integer in [{}, {}]",
          value.substr(0, 64), kMinDisplayVertices, std::numeric_limits<Index>::max()));
    }
    options.display_vertices = vertices;
  }
  return options;
}

std::string BinaryMessageRefusal(size_t size) {
  return fmt::format("binary message of {} bytes refused: the page sends JSON text messages", size);
}

std::optional<int64_t> MessageIdOf(std::string_view text) {
  const Json object = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!object.is_object()) return std::nullopt;
  const auto it = object.find("id");
  if (it == object.end() || !it->is_number_unsigned() || it->get<uint64_t>() > INT64_MAX)
    return std::nullopt;
  return it->get<int64_t>();
}

bool SupersedesFullSolve(std::string_view text) {
  const Json object = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!object.is_object()) return false;
  const auto it = object.find("type");
  if (it == object.end() || !it->is_string()) return false;
  const std::string& type = it->get_ref<const std::string&>();
  return type == "move" || type == "solve" || type == "configure" || type == "remove_handle";
}

}  // namespace harap::view
