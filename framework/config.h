// SPDX-License-Identifier: MIT
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace harap {

/// One option an implementation reads: its key, default and help text (drives `harap list`).
struct OptionInfo {
  std::string key;
  std::string default_value;
  std::string help;
};

/// A view of one table of a configuration (a TOML document), e.g. the `[energy]` table.
///
/// Implementations read their options with Get(key, default, help) and finish with
/// RejectUnknownKeys(), so a typo fails loudly listing the valid keys. The parser (toml++) is
/// hidden behind this class. Errors name the source file, line and dotted key.
///
///   double lambda = node.Get("lambda", 0.99, "weight of the smoothness term, in [0, 1)");
///   node.RejectUnknownKeys();
///
/// Copies are cheap views that share the document (and its record of which keys were read).
class ConfigNode {
 public:
  /// An empty document (every option at its default).
  ConfigNode();
  ~ConfigNode();
  ConfigNode(const ConfigNode&);
  ConfigNode& operator=(const ConfigNode&);

  /// Parses TOML text; `source` names it in error messages. Throws ConfigError with the line.
  static ConfigNode Parse(std::string_view toml_text, std::string source);
  static ConfigNode ParseFile(const std::filesystem::path& file);

  /// A node that returns defaults for every read and records the options read (for `list`).
  static ConfigNode Describing();

  /// Reads an option; absent keys give `default_value`. A present value of the wrong type is a
  /// ConfigError (integers are accepted where a floating-point number is expected).
  double Get(std::string_view key, double default_value, std::string_view help) const;
  int Get(std::string_view key, int default_value, std::string_view help) const;
  bool Get(std::string_view key, bool default_value, std::string_view help) const;
  std::string Get(std::string_view key, const char* default_value, std::string_view help) const;
  std::string Get(std::string_view key, const std::string& default_value,
                  std::string_view help) const;

  /// A string option restricted to `choices` (the error lists them).
  std::string GetChoice(std::string_view key, std::string_view default_value,
                        const std::vector<std::string>& choices, std::string_view help) const;

  /// The sub-table `key` (an empty table if absent). Its keys count as read.
  ConfigNode Child(std::string_view key) const;
  /// The same, with a help text for the table (listed like an option's).
  ConfigNode Child(std::string_view key, std::string_view help) const;

  bool Has(std::string_view key) const;
  /// Keys present in this table, in document order.
  std::vector<std::string> Keys() const;

  /// Throws ConfigError if this table holds a key no Get()/Child() has read, listing valid keys.
  void RejectUnknownKeys() const;

  /// Options read from this node so far (key, default, help), in reading order.
  std::vector<OptionInfo> Options() const;

  /// Sets `dotted_key` (relative to this node, e.g. "energy.lambda") from a TOML value literal;
  /// text that is not a TOML value is taken as a string ("cholmod"). Creates tables as needed.
  void Set(std::string_view dotted_key, std::string_view value_literal);

  /// Where `key` of this table was written: "file:line:column" (or the file alone).
  std::string Where(std::string_view key) const;
  /// Throws ConfigError "<where key was written>: option '<dotted key>' <problem>", e.g.
  /// node.Fail("tolerance", "must be >= 0, got -1") in an implementation's option validation.
  [[noreturn]] void Fail(std::string_view key, std::string_view problem) const;
  /// The dotted path of this table from the document root ("" for the root).
  const std::string& path() const { return path_; }
  /// The document's source name (file path or "<command line>").
  std::string source() const;

  /// The whole table as TOML text (for resolved configs).
  std::string ToToml() const;

  /// Implementation detail shared by the .cpp.
  struct State;

 private:
  ConfigNode(std::shared_ptr<State> state, std::string path);
  std::string FullKey(std::string_view key) const;

  std::shared_ptr<State> state_;
  std::string path_;
};

}  // namespace harap
