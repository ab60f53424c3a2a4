// SPDX-License-Identifier: MIT
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <limits>
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

/// The values a numeric option may take: an interval whose ends may be open or infinite. Read
/// with ConfigNode::Get(key, default, help, range), which rejects other values naming the range.
///
///   node.Get("lambda", 0.99, "weight of the smoothness term", Range::HalfOpen(0, 1));  // [0, 1)
///   node.Get("max_iterations", 10, "iterations per solve", Range::AtLeast(1));         // >= 1
struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;  ///< min itself excluded
  bool max_open = false;  ///< max itself excluded

  static constexpr Range AtLeast(double min) { return {min, kInfinity, false, false}; }
  static constexpr Range Above(double min) { return {min, kInfinity, true, false}; }
  static constexpr Range Closed(double min, double max) { return {min, max, false, false}; }
  /// [min, max)
  static constexpr Range HalfOpen(double min, double max) { return {min, max, false, true}; }
  /// (min, max]
  static constexpr Range LeftOpen(double min, double max) { return {min, max, true, false}; }
  static constexpr Range Open(double min, double max) { return {min, max, true, true}; }

  /// False for NaN.
  bool Contains(double value) const {
    return (min_open ? value > min : value >= min) && (max_open ? value < max : value <= max);
  }
  /// "in [0, 1)", ">= 1", "> 0", "<= 5".
  std::string ToString() const;

  static constexpr double kInfinity = std::numeric_limits<double>::infinity();
};

/// One numeric field of an options struct built in code (not read from a configuration), checked
/// against the range its configuration key is read with.
struct RangeCheck {
  std::string_view key;
  double value;
  Range range;
};
/// "ratio is 1, which is not in [0, 1)" for every check whose value lies outside its range (the
/// wording ConfigNode::Get uses), for an options struct's Validate().
std::vector<std::string> RangeProblems(std::initializer_list<RangeCheck> checks);

/// One value of an enum option and its name in configurations: an implementation keeps one
/// table per enum, and both ConfigNode::GetEnum and its own name lookups (reports) use it.
///
///   constexpr EnumNames<Sweep, 2> kSweepNames = {{{Sweep::kForward, "forward"},
///                                                 {Sweep::kSymmetric, "symmetric"}}};
template <class Enum>
struct EnumName {
  Enum value;
  std::string_view name;
};
template <class Enum, std::size_t N>
using EnumNames = std::array<EnumName<Enum>, N>;

/// The name of `value` in `names` ("?" if it has none).
template <class Enum, std::size_t N>
constexpr std::string_view NameOf(const EnumNames<Enum, N>& names, Enum value) {
  for (const auto& entry : names) {
    if (entry.value == value) return entry.name;
  }
  return "?";
}

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

  /// A numeric option restricted to `range`: a value outside it is a ConfigError "<where>:
  /// option '<key>' is <value>, which is not in [0, 1)" (or "... which is not >= 1"). The help
  /// shown by `harap list` gets the range appended, e.g. "(in [0, 1))".
  double Get(std::string_view key, double default_value, std::string_view help,
             const Range& range) const;
  int Get(std::string_view key, int default_value, std::string_view help, const Range& range) const;

  /// A string option restricted to `choices` (the error lists them; so does the help).
  std::string GetChoice(std::string_view key, std::string_view default_value,
                        const std::vector<std::string>& choices, std::string_view help) const;

  /// An enum option named by `names` (GetChoice with the names as choices):
  ///   options.sweep = node.GetEnum("sweep", options.sweep, kSweepNames, "...");
  template <class Enum, std::size_t N>
  Enum GetEnum(std::string_view key, Enum default_value, const EnumNames<Enum, N>& names,
               std::string_view help) const {
    std::vector<std::string> choices;
    for (const auto& entry : names) choices.emplace_back(entry.name);
    const std::string chosen = GetChoice(key, NameOf(names, default_value), choices, help);
    for (const auto& entry : names) {
      if (entry.name == chosen) return entry.value;
    }
    return default_value;  // unreachable: GetChoice accepts only the names
  }

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
