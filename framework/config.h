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

/// A view of one table of a configuration (a TOML document), e.g. the `[energy]` table: the
/// document alone. Its const members only look (nothing is recorded), so a ConfigNode may be read
/// from several threads at once. The parser (toml++) is hidden behind this class. Options are
/// read through an OptionReader, which records the keys read.
///
/// Copies are cheap views that share the document (Set() changes it for every copy).
class ConfigNode {
 public:
  /// An empty document (every option at its default).
  ConfigNode();
  ~ConfigNode();
  ConfigNode(const ConfigNode&);
  ConfigNode& operator=(const ConfigNode&);

  /// A view of the same table in a copy of the whole document (the file positions kept), for
  /// changes (Set, Remove) that must not reach this document's other views.
  ConfigNode Clone() const;

  /// Parses TOML text; `source` names it in error messages. Throws ConfigError with the line.
  static ConfigNode Parse(std::string_view toml_text, std::string source);
  static ConfigNode ParseFile(const std::filesystem::path& file);

  /// The sub-table `key` (an empty table if absent). A present `key` that is not a table is a
  /// ConfigError.
  ConfigNode Child(std::string_view key) const;

  bool Has(std::string_view key) const;
  /// Keys present in this table, in document order.
  std::vector<std::string> Keys() const;

  /// Sets `dotted_key` (relative to this node, e.g. "energy.lambda") from a TOML value literal;
  /// text that is not a TOML value is taken as a string ("cholmod"). Creates tables as needed.
  void Set(std::string_view dotted_key, std::string_view value_literal);
  /// Removes `key` of this table (nothing if absent).
  void Remove(std::string_view key);

  /// Where `key` of this table was written: "file:line:column" (or the file alone).
  std::string Where(std::string_view key) const;
  /// Throws ConfigError "<where key was written>: option '<dotted key>' <problem>", e.g.
  /// node.Fail("tolerance", "must be >= 0, got -1") in an implementation's option validation.
  [[noreturn]] void Fail(std::string_view key, std::string_view problem) const;
  /// The dotted path of this table from the document root ("" for the root).
  const std::string& path() const { return path_; }
  /// The document's source name (file path or "<command line>").
  std::string source() const;
  /// The dotted key of `key` in this table ("energy.lambda").
  std::string FullKey(std::string_view key) const;

  /// The whole table as TOML text (for resolved configs).
  std::string ToToml() const;

  /// Implementation detail shared by the .cpp.
  struct Document;

 private:
  friend class OptionReader;
  ConfigNode(std::shared_ptr<Document> document, std::string path);
  /// The value of `key` (`default_value` if absent); a present value of another type throws.
  template <class T>
  T Value(std::string_view key, T default_value) const;

  std::shared_ptr<Document> document_;
  std::string path_;
};

/// Reads the options of one table of a configuration and records which keys it read, so that
/// RejectUnknownKeys() can name a typo and `harap list` can show every option with its default
/// and help. Implementations read their options with Get(key, default, help) and finish with
/// RejectUnknownKeys():
///
///   Options FromConfig(OptionReader node) {
///     Options options;
///     options.lambda = node.Get("lambda", options.lambda, "weight of the smoothness term",
///                               Range::HalfOpen(0.0, 1.0));
///     node.RejectUnknownKeys();
///     return options;
///   }
///
/// One record serves a reader, its copies and the readers its Child() makes (several functions
/// may read one table: a registry reads `type`, the implementation the rest). Made explicitly
/// from a ConfigNode where a configuration is resolved (once, before a run); a reader and its
/// record belong to the thread that resolves, and nothing reads options during a run.
class OptionReader {
 public:
  /// A reader of `table` with a new, empty record.
  explicit OptionReader(ConfigNode table);
  /// A reader of an empty document: every read returns its default and is recorded (for `list`).
  static OptionReader Describing();

  /// Reads an option; absent keys give `default_value`. A present value of the wrong type is a
  /// ConfigError (integers are accepted where a floating-point number is expected).
  double Get(std::string_view key, double default_value, std::string_view help);
  int Get(std::string_view key, int default_value, std::string_view help);
  bool Get(std::string_view key, bool default_value, std::string_view help);
  std::string Get(std::string_view key, const char* default_value, std::string_view help);
  std::string Get(std::string_view key, const std::string& default_value, std::string_view help);

  /// A numeric option restricted to `range`: a value outside it is a ConfigError "<where>:
  /// option '<key>' is <value>, which is not in [0, 1)" (or "... which is not >= 1"). The help
  /// shown by `harap list` gets the range appended, e.g. "(in [0, 1))".
  double Get(std::string_view key, double default_value, std::string_view help, const Range& range);
  int Get(std::string_view key, int default_value, std::string_view help, const Range& range);

  /// A string option restricted to `choices` (the error lists them; so does the help).
  std::string GetChoice(std::string_view key, std::string_view default_value,
                        const std::vector<std::string>& choices, std::string_view help);

  /// An enum option named by `names` (GetChoice with the names as choices):
  ///   options.sweep = node.GetEnum("sweep", options.sweep, kSweepNames, "...");
  template <class Enum, std::size_t N>
  Enum GetEnum(std::string_view key, Enum default_value, const EnumNames<Enum, N>& names,
               std::string_view help) {
    std::vector<std::string> choices;
    for (const auto& entry : names) choices.emplace_back(entry.name);
    const std::string chosen = GetChoice(key, NameOf(names, default_value), choices, help);
    for (const auto& entry : names) {
      if (entry.name == chosen) return entry.value;
    }
    return default_value;  // unreachable: GetChoice accepts only the names
  }

  /// A reader of the sub-table `key` (an empty table if absent), sharing this reader's record.
  /// Its key counts as read.
  OptionReader Child(std::string_view key);
  /// The same, with a help text for the table (listed like an option's).
  OptionReader Child(std::string_view key, std::string_view help);

  /// Throws ConfigError if this table holds a key no Get()/Child() of this record has read,
  /// listing the valid keys.
  void RejectUnknownKeys() const;
  /// Options read from this table so far (key, default, help), in reading order.
  std::vector<OptionInfo> Options() const;

  /// The table read.
  const ConfigNode& table() const { return table_; }
  bool Has(std::string_view key) const { return table_.Has(key); }
  std::vector<std::string> Keys() const { return table_.Keys(); }
  std::string Where(std::string_view key) const { return table_.Where(key); }
  [[noreturn]] void Fail(std::string_view key, std::string_view problem) const {
    table_.Fail(key, problem);
  }
  const std::string& path() const { return table_.path(); }

 private:
  struct Record;
  OptionReader(ConfigNode table, std::shared_ptr<Record> record);
  void Note(std::string_view key, std::string default_value, std::string_view help);

  ConfigNode table_;
  std::shared_ptr<Record> record_;
};

}  // namespace harap
