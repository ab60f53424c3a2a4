// SPDX-License-Identifier: MIT
// The TOML toolkit of harap's three TOML readers: configurations (ConfigNode, config.cpp),
// scenario files (io/scenario_reading.cpp) and experiment configs (runner/experiment.cpp).
// One error style for all: every message is a ConfigError that starts with where the problem is
// written, "file:line:column" (the file alone where no position is known), then the context
// (e.g. "handle 'feet'") if any, then the problem naming the key.
//
// Internal: it exposes toml++, which harap's installed interface does not (the header is not
// installed); users link tomlplusplus themselves, as io and experiments do.
#pragma once

#include <toml++/toml.h>

#include <array>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace harap {

class TomlReader {
 public:
  /// `source` names the document in messages (a file path, "<command line>", ...).
  explicit TomlReader(std::string source, std::string context = "")
      : source_(std::move(source)), context_(std::move(context)) {}

  /// The same document with errors prefixed by `context` ("handle 'feet'").
  TomlReader In(std::string context) const { return TomlReader(source_, std::move(context)); }

  const std::string& source() const { return source_; }

  /// Parses `text`; a syntax error is a ConfigError "file:line:column: TOML syntax error: ...".
  toml::table Parse(std::string_view text) const;

  /// "file:line:column" of `region` (its own file name if it has one, else the source), or the
  /// file alone where the region has no position.
  std::string Where(const toml::source_region& region) const;
  std::string Where(const toml::node& node) const { return Where(node.source()); }

  /// Throws ConfigError "<where>: <context>: <problem>" (no context part without a context).
  [[noreturn]] void Fail(std::string_view where, std::string_view problem) const;
  [[noreturn]] void Fail(const toml::node& node, std::string_view problem) const {
    Fail(Where(node), problem);
  }

  /// Rejects the first key of `table` not in `valid`: "unknown key 'k' in <what>; valid keys:
  /// a, b, c", at the key's position.
  void CheckKeys(const toml::table& table, std::initializer_list<std::string_view> valid,
                 std::string_view what) const;
  void CheckKeys(const toml::table& table, const std::vector<std::string>& valid,
                 std::string_view what) const;

  /// `table[key]`, or "<what> needs '<key>'" at the table's position.
  const toml::node& Required(const toml::table& table, std::string_view key,
                             std::string_view what) const;

  /// A finite number (integers accepted): "<what> must be a number" / "<what> is a non-finite
  /// number (nan)".
  double Number(const toml::node& node, std::string_view what) const;
  /// [x, y, z] of numbers: "<what> must be an array of three numbers".
  std::array<double, 3> Vector3(const toml::node& node, std::string_view what) const;

  /// `table[key]` as a string, `fallback` if absent; "'<key>' must be a string" otherwise.
  std::string String(const toml::table& table, std::string_view key, std::string fallback) const;
  /// `table[key]` as a string or an array of strings (none if absent).
  std::vector<std::string> Strings(const toml::table& table, std::string_view key) const;

 private:
  std::string source_;
  std::string context_;
};

}  // namespace harap
