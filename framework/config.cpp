// SPDX-License-Identifier: MIT
#include "framework/config.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>

#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "framework/error.h"
#include "framework/toml_reading.h"

namespace harap {

struct ConfigNode::Document {
  toml::table root;
  std::string source;
};

struct OptionReader::Record {
  // Per table path: the keys read and the options described, in order.
  std::map<std::string, std::set<std::string>> read_keys;
  std::map<std::string, std::vector<OptionInfo>> options;
};

namespace {

std::string JoinPath(const std::string& path, std::string_view key) {
  return path.empty() ? std::string(key) : fmt::format("{}.{}", path, key);
}

// The table at `path`, or nullptr if some part is absent.
const toml::table* FindTable(const toml::table& root, const std::string& path) {
  if (path.empty()) return &root;
  const toml::node* node = root.at_path(path).node();
  return node ? node->as_table() : nullptr;
}

// The value of `key` in the table at `path` (nullptr if absent).
const toml::node* FindValue(const toml::table& root, const std::string& path,
                            std::string_view key) {
  const toml::table* table = FindTable(root, path);
  return table ? table->get(key) : nullptr;
}

}  // namespace

ConfigNode::ConfigNode() : document_(std::make_shared<Document>()) {
  document_->source = "<defaults>";
}
ConfigNode::~ConfigNode() = default;
ConfigNode::ConfigNode(const ConfigNode&) = default;
ConfigNode& ConfigNode::operator=(const ConfigNode&) = default;
ConfigNode::ConfigNode(std::shared_ptr<Document> document, std::string path)
    : document_(std::move(document)), path_(std::move(path)) {}

ConfigNode ConfigNode::Parse(std::string_view toml_text, std::string source) {
  ConfigNode node;
  node.document_->root = TomlReader(source).Parse(toml_text);
  node.document_->source = std::move(source);
  return node;
}

ConfigNode ConfigNode::ParseFile(const std::filesystem::path& file) {
  std::ifstream stream(file, std::ios::binary);
  if (!stream) throw ConfigError(fmt::format("{}: cannot open configuration file", file.string()));
  std::stringstream buffer;
  buffer << stream.rdbuf();
  return Parse(buffer.str(), file.string());
}

ConfigNode ConfigNode::Clone() const {
  return ConfigNode(std::make_shared<Document>(*document_), path_);
}

std::string ConfigNode::FullKey(std::string_view key) const { return JoinPath(path_, key); }

std::string ConfigNode::source() const { return document_->source; }

std::string ConfigNode::Where(std::string_view key) const {
  if (const toml::node* node = FindValue(document_->root, path_, key)) {
    return TomlReader(document_->source).Where(node->source());
  }
  return document_->source;
}

void ConfigNode::Fail(std::string_view key, std::string_view problem) const {
  throw ConfigError(fmt::format("{}: option '{}' {}", Where(key), FullKey(key), problem));
}

ConfigNode ConfigNode::Child(std::string_view key) const {
  if (const toml::node* node = FindValue(document_->root, path_, key); node && !node->is_table()) {
    throw ConfigError(fmt::format("{}: '{}' must be a table", Where(key), FullKey(key)));
  }
  return ConfigNode(document_, FullKey(key));
}

bool ConfigNode::Has(std::string_view key) const {
  return FindValue(document_->root, path_, key) != nullptr;
}

std::vector<std::string> ConfigNode::Keys() const {
  std::vector<std::string> keys;
  if (const toml::table* table = FindTable(document_->root, path_)) {
    for (const auto& [key, value] : *table) keys.emplace_back(key.str());
  }
  return keys;
}

template <class T>
T ConfigNode::Value(std::string_view key, T default_value) const {
  const toml::node* node = FindValue(document_->root, path_, key);
  if (!node) return default_value;
  auto fail = [&](std::string_view expected) -> T {
    Fail(key, fmt::format("must be {}", expected));
  };
  if constexpr (std::is_same_v<T, double>) {
    if (auto v = node->value<double>()) {
      if (!std::isfinite(*v)) return fail("a finite number");
      return *v;
    }
    return fail("a number");
  } else if constexpr (std::is_same_v<T, int>) {
    if (const auto* v = node->as_integer()) {
      const int64_t value = v->get();
      if (value < std::numeric_limits<int>::min() || value > std::numeric_limits<int>::max()) {
        return fail("an integer in the 32-bit range");
      }
      return static_cast<int>(value);
    }
    return fail("an integer");
  } else if constexpr (std::is_same_v<T, bool>) {
    if (const auto* v = node->as_boolean()) return v->get();
    return fail("true or false");
  } else {
    if (const auto* v = node->as_string()) return v->get();
    return fail("a string");
  }
}

template double ConfigNode::Value<double>(std::string_view, double) const;
template int ConfigNode::Value<int>(std::string_view, int) const;
template bool ConfigNode::Value<bool>(std::string_view, bool) const;
template std::string ConfigNode::Value<std::string>(std::string_view, std::string) const;

void ConfigNode::Set(std::string_view dotted_key, std::string_view value_literal) {
  std::string full = FullKey(dotted_key);
  // Walk/create the tables on the way.
  toml::table* table = &document_->root;
  size_t start = 0;
  while (true) {
    size_t dot = full.find('.', start);
    if (dot == std::string::npos) break;
    std::string part = full.substr(start, dot - start);
    if (part.empty()) throw ConfigError(fmt::format("invalid option key '{}'", full));
    toml::node* node = table->get(part);
    if (!node) {
      table->insert_or_assign(part, toml::table{});
      node = table->get(part);
    }
    if (!node->is_table()) {
      throw ConfigError(fmt::format("cannot set '{}': '{}' is not a table", full, part));
    }
    table = node->as_table();
    start = dot + 1;
  }
  std::string leaf = full.substr(start);
  if (leaf.empty()) throw ConfigError(fmt::format("invalid option key '{}'", full));
  // Parse the literal as a TOML value; anything else is a plain string.
  bool is_value = false;
  try {
    const std::string text = fmt::format("v = {}", value_literal);
    auto doc = toml::parse(std::string_view(text), std::string_view("<command line>"));
    if (auto* node = doc.get("v")) {
      node->visit([&](auto&& v) { table->insert_or_assign(leaf, v); });
      is_value = true;
    }
  } catch (const toml::parse_error&) {
  }
  if (!is_value) table->insert_or_assign(leaf, std::string(value_literal));
}

void ConfigNode::Remove(std::string_view key) {
  toml::table* table = path_.empty() ? &document_->root : document_->root.at_path(path_).as_table();
  if (table) table->erase(key);
}

std::string ConfigNode::ToToml() const {
  const toml::table* table = FindTable(document_->root, path_);
  if (!table) return "";
  std::stringstream out;
  out << *table;
  return out.str();
}

std::string Range::ToString() const {
  const bool has_min = min > -kInfinity, has_max = max < kInfinity;
  if (has_min && has_max) {
    return fmt::format("in {}{}, {}{}", min_open ? '(' : '[', min, max, max_open ? ')' : ']');
  }
  if (has_min) return fmt::format("{} {}", min_open ? ">" : ">=", min);
  if (has_max) return fmt::format("{} {}", max_open ? "<" : "<=", max);
  return "any number";
}

std::vector<std::string> RangeProblems(std::initializer_list<RangeCheck> checks) {
  std::vector<std::string> problems;
  for (const auto& check : checks) {
    if (!check.range.Contains(check.value)) {
      problems.push_back(
          fmt::format("{} is {}, which is not {}", check.key, check.value, check.range.ToString()));
    }
  }
  return problems;
}

OptionReader::OptionReader(ConfigNode table)
    : OptionReader(std::move(table), std::make_shared<Record>()) {}

OptionReader::OptionReader(ConfigNode table, std::shared_ptr<Record> record)
    : table_(std::move(table)), record_(std::move(record)) {}

OptionReader OptionReader::Describing() { return OptionReader(ConfigNode()); }

void OptionReader::Note(std::string_view key, std::string default_value, std::string_view help) {
  record_->read_keys[table_.path()].insert(std::string(key));
  auto& list = record_->options[table_.path()];
  for (const auto& option : list) {
    if (option.key == key) return;
  }
  list.push_back({std::string(key), std::move(default_value), std::string(help)});
}

namespace {

template <class T>
std::string DefaultText(const T& value) {
  if constexpr (std::is_same_v<T, bool>) {
    return value ? "true" : "false";
  } else if constexpr (std::is_same_v<T, std::string>) {
    return fmt::format("\"{}\"", value);
  } else {
    return fmt::format("{}", value);
  }
}

// "... which is not in [0, 1)" / "... which is not >= 1".
template <class T>
T CheckRange(const ConfigNode& table, std::string_view key, T value, const Range& range) {
  if (range.Contains(static_cast<double>(value))) return value;
  table.Fail(key, fmt::format("is {}, which is not {}", value, range.ToString()));
}

}  // namespace

double OptionReader::Get(std::string_view key, double default_value, std::string_view help) {
  Note(key, DefaultText(default_value), help);
  return table_.Value(key, default_value);
}

int OptionReader::Get(std::string_view key, int default_value, std::string_view help) {
  Note(key, DefaultText(default_value), help);
  return table_.Value(key, default_value);
}

bool OptionReader::Get(std::string_view key, bool default_value, std::string_view help) {
  Note(key, DefaultText(default_value), help);
  return table_.Value(key, default_value);
}

std::string OptionReader::Get(std::string_view key, const std::string& default_value,
                              std::string_view help) {
  Note(key, DefaultText(default_value), help);
  return table_.Value(key, default_value);
}

std::string OptionReader::Get(std::string_view key, const char* default_value,
                              std::string_view help) {
  return Get(key, std::string(default_value), help);
}

double OptionReader::Get(std::string_view key, double default_value, std::string_view help,
                         const Range& range) {
  const std::string full_help = fmt::format("{} ({})", help, range.ToString());
  return CheckRange(table_, key, Get(key, default_value, std::string_view(full_help)), range);
}

int OptionReader::Get(std::string_view key, int default_value, std::string_view help,
                      const Range& range) {
  const std::string full_help = fmt::format("{} ({})", help, range.ToString());
  return CheckRange(table_, key, Get(key, default_value, std::string_view(full_help)), range);
}

std::string OptionReader::GetChoice(std::string_view key, std::string_view default_value,
                                    const std::vector<std::string>& choices,
                                    std::string_view help) {
  std::string full_help = fmt::format("{} (one of: {})", help, fmt::join(choices, ", "));
  std::string value = Get(key, std::string(default_value), full_help);
  for (const auto& choice : choices) {
    if (choice == value) return value;
  }
  table_.Fail(key,
              fmt::format("is \"{}\", which is not one of: {}", value, fmt::join(choices, ", ")));
}

OptionReader OptionReader::Child(std::string_view key) { return Child(key, ""); }

OptionReader OptionReader::Child(std::string_view key, std::string_view help) {
  Note(key, "(table)", help);
  return OptionReader(table_.Child(key), record_);
}

void OptionReader::RejectUnknownKeys() const {
  const auto read = record_->read_keys.find(table_.path());
  std::vector<std::string> unknown;
  for (const auto& key : table_.Keys()) {
    if (read == record_->read_keys.end() || !read->second.count(key)) unknown.push_back(key);
  }
  if (unknown.empty()) return;
  std::vector<std::string> valid;
  for (const auto& option : Options()) valid.push_back(option.key);
  const std::string& path = table_.path();
  const std::string table = path.empty() ? std::string("the top level") : fmt::format("[{}]", path);
  throw ConfigError(
      fmt::format("{}: unknown option '{}' in {}; valid options: {}", Where(unknown.front()),
                  table_.FullKey(unknown.front()), table,
                  valid.empty() ? std::string("none") : fmt::format("{}", fmt::join(valid, ", "))));
}

std::vector<OptionInfo> OptionReader::Options() const {
  const auto it = record_->options.find(table_.path());
  return it == record_->options.end() ? std::vector<OptionInfo>{} : it->second;
}

}  // namespace harap
