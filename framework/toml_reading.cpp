// SPDX-License-Identifier: MIT
#include "framework/toml_reading.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "framework/error.h"

namespace harap {

namespace {

template <class Keys>
void CheckKeysIn(const TomlReader& reader, const toml::table& table, const Keys& valid,
                 std::string_view what) {
  for (const auto& [key, value] : table) {
    if (std::find(valid.begin(), valid.end(), key.str()) != valid.end()) continue;
    reader.Fail(reader.Where(key.source()), fmt::format("unknown key '{}' in {}; valid keys: {}",
                                                        key.str(), what, fmt::join(valid, ", ")));
  }
}

}  // namespace

toml::table TomlReader::Parse(std::string_view text) const {
  try {
    return toml::parse(text, std::string_view(source_));
  } catch (const toml::parse_error& error) {
    throw ConfigError(
        fmt::format("{}: TOML syntax error: {}", Where(error.source()), error.description()));
  }
}

std::string TomlReader::Where(const toml::source_region& region) const {
  const std::string file = region.path ? std::string(*region.path) : source_;
  if (region.begin.line == 0) return file;
  return fmt::format("{}:{}:{}", file, region.begin.line, region.begin.column);
}

void TomlReader::Fail(std::string_view where, std::string_view problem) const {
  if (context_.empty()) throw ConfigError(fmt::format("{}: {}", where, problem));
  throw ConfigError(fmt::format("{}: {}: {}", where, context_, problem));
}

void TomlReader::CheckKeys(const toml::table& table, std::initializer_list<std::string_view> valid,
                           std::string_view what) const {
  CheckKeysIn(*this, table, valid, what);
}

void TomlReader::CheckKeys(const toml::table& table, const std::vector<std::string>& valid,
                           std::string_view what) const {
  CheckKeysIn(*this, table, valid, what);
}

const toml::node& TomlReader::Required(const toml::table& table, std::string_view key,
                                       std::string_view what) const {
  const toml::node* node = table.get(key);
  if (!node) Fail(Where(table), fmt::format("{} needs '{}'", what, key));
  return *node;
}

double TomlReader::Number(const toml::node& node, std::string_view what) const {
  double value = 0.0;
  if (const auto* integer = node.as_integer()) {
    value = static_cast<double>(integer->get());
  } else if (const auto* floating = node.as_floating_point()) {
    value = floating->get();
  } else {
    Fail(node, fmt::format("{} must be a number", what));
  }
  if (!std::isfinite(value)) {
    Fail(node, fmt::format("{} is a non-finite number ({})", what, value));
  }
  return value;
}

std::array<double, 3> TomlReader::Vector3(const toml::node& node, std::string_view what) const {
  const toml::array* array = node.as_array();
  if (!array || array->size() != 3) {
    Fail(node, fmt::format("{} must be an array of three numbers", what));
  }
  std::array<double, 3> vector{};
  for (size_t d = 0; d < 3; ++d) vector[d] = Number(*array->get(d), what);
  return vector;
}

std::string TomlReader::String(const toml::table& table, std::string_view key,
                               std::string fallback) const {
  const toml::node* node = table.get(key);
  if (!node) return fallback;
  if (!node->is_string()) Fail(*node, fmt::format("'{}' must be a string", key));
  return node->as_string()->get();
}

std::vector<std::string> TomlReader::Strings(const toml::table& table, std::string_view key) const {
  std::vector<std::string> values;
  const toml::node* node = table.get(key);
  if (!node) return values;
  if (node->is_string()) return {node->as_string()->get()};
  const toml::array* array = node->as_array();
  if (!array) Fail(*node, fmt::format("'{}' must be a string or an array of strings", key));
  for (const toml::node& entry : *array) {
    if (!entry.is_string()) Fail(entry, fmt::format("'{}' must hold strings", key));
    values.push_back(entry.as_string()->get());
  }
  return values;
}

}  // namespace harap
