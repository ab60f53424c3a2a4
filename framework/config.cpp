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

struct ConfigNode::State {
  toml::table root;
  std::string source;
  bool describing = false;
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

std::string DescribeSource(const toml::source_region& region, const std::string& source) {
  return TomlReader(source).Where(region);
}

void RecordOption(ConfigNode::State& state, const std::string& path, std::string_view key,
                  std::string default_value, std::string_view help) {
  state.read_keys[path].insert(std::string(key));
  auto& list = state.options[path];
  for (const auto& option : list) {
    if (option.key == key) return;
  }
  list.push_back({std::string(key), std::move(default_value), std::string(help)});
}

}  // namespace

ConfigNode::ConfigNode() : state_(std::make_shared<State>()) { state_->source = "<defaults>"; }
ConfigNode::~ConfigNode() = default;
ConfigNode::ConfigNode(const ConfigNode&) = default;
ConfigNode& ConfigNode::operator=(const ConfigNode&) = default;
ConfigNode::ConfigNode(std::shared_ptr<State> state, std::string path)
    : state_(std::move(state)), path_(std::move(path)) {}

ConfigNode ConfigNode::Parse(std::string_view toml_text, std::string source) {
  ConfigNode node;
  node.state_->root = TomlReader(source).Parse(toml_text);
  node.state_->source = std::move(source);
  return node;
}

ConfigNode ConfigNode::ParseFile(const std::filesystem::path& file) {
  std::ifstream stream(file, std::ios::binary);
  if (!stream) throw ConfigError(fmt::format("{}: cannot open configuration file", file.string()));
  std::stringstream buffer;
  buffer << stream.rdbuf();
  return Parse(buffer.str(), file.string());
}

ConfigNode ConfigNode::Describing() {
  ConfigNode node;
  node.state_->describing = true;
  return node;
}

std::string ConfigNode::FullKey(std::string_view key) const { return JoinPath(path_, key); }

std::string ConfigNode::source() const { return state_->source; }

std::string ConfigNode::Where(std::string_view key) const {
  const toml::table* table = FindTable(state_->root, path_);
  if (table) {
    if (const toml::node* node = table->get(key)) {
      return DescribeSource(node->source(), state_->source);
    }
  }
  return state_->source;
}

void ConfigNode::Fail(std::string_view key, std::string_view problem) const {
  throw ConfigError(fmt::format("{}: option '{}' {}", Where(key), FullKey(key), problem));
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

template <class T>
T ReadValue(const ConfigNode::State& state, const toml::table* table, const std::string& path,
            std::string_view key, T default_value) {
  if (!table) return default_value;
  const toml::node* node = table->get(key);
  if (!node) return default_value;
  auto fail = [&](std::string_view expected) -> T {
    throw ConfigError(fmt::format("{}: option '{}' must be {}",
                                  DescribeSource(node->source(), state.source), JoinPath(path, key),
                                  expected));
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

}  // namespace

double ConfigNode::Get(std::string_view key, double default_value, std::string_view help) const {
  RecordOption(*state_, path_, key, DefaultText(default_value), help);
  return ReadValue<double>(*state_, FindTable(state_->root, path_), path_, key, default_value);
}

int ConfigNode::Get(std::string_view key, int default_value, std::string_view help) const {
  RecordOption(*state_, path_, key, DefaultText(default_value), help);
  return ReadValue<int>(*state_, FindTable(state_->root, path_), path_, key, default_value);
}

bool ConfigNode::Get(std::string_view key, bool default_value, std::string_view help) const {
  RecordOption(*state_, path_, key, DefaultText(default_value), help);
  return ReadValue<bool>(*state_, FindTable(state_->root, path_), path_, key, default_value);
}

std::string ConfigNode::Get(std::string_view key, const std::string& default_value,
                            std::string_view help) const {
  RecordOption(*state_, path_, key, DefaultText(default_value), help);
  return ReadValue<std::string>(*state_, FindTable(state_->root, path_), path_, key, default_value);
}

std::string ConfigNode::Get(std::string_view key, const char* default_value,
                            std::string_view help) const {
  return Get(key, std::string(default_value), help);
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

namespace {

// "... which is not in [0, 1)" / "... which is not >= 1".
template <class T>
T CheckRange(const ConfigNode& node, std::string_view key, T value, const Range& range) {
  if (range.Contains(static_cast<double>(value))) return value;
  node.Fail(key, fmt::format("is {}, which is not {}", value, range.ToString()));
}

}  // namespace

double ConfigNode::Get(std::string_view key, double default_value, std::string_view help,
                       const Range& range) const {
  const std::string full_help = fmt::format("{} ({})", help, range.ToString());
  return CheckRange(*this, key, Get(key, default_value, std::string_view(full_help)), range);
}

int ConfigNode::Get(std::string_view key, int default_value, std::string_view help,
                    const Range& range) const {
  const std::string full_help = fmt::format("{} ({})", help, range.ToString());
  return CheckRange(*this, key, Get(key, default_value, std::string_view(full_help)), range);
}

std::string ConfigNode::GetChoice(std::string_view key, std::string_view default_value,
                                  const std::vector<std::string>& choices,
                                  std::string_view help) const {
  std::string full_help = fmt::format("{} (one of: {})", help, fmt::join(choices, ", "));
  std::string value = Get(key, std::string(default_value), full_help);
  for (const auto& choice : choices) {
    if (choice == value) return value;
  }
  throw ConfigError(fmt::format("{}: option '{}' is \"{}\", which is not one of: {}", Where(key),
                                FullKey(key), value, fmt::join(choices, ", ")));
}

ConfigNode ConfigNode::Child(std::string_view key) const { return Child(key, ""); }

ConfigNode ConfigNode::Child(std::string_view key, std::string_view help) const {
  RecordOption(*state_, path_, key, "(table)", help);
  const toml::table* table = FindTable(state_->root, path_);
  if (table) {
    if (const toml::node* node = table->get(key); node && !node->is_table()) {
      throw ConfigError(fmt::format("{}: '{}' must be a table", Where(key), FullKey(key)));
    }
  }
  return ConfigNode(state_, FullKey(key));
}

bool ConfigNode::Has(std::string_view key) const {
  const toml::table* table = FindTable(state_->root, path_);
  return table && table->contains(key);
}

std::vector<std::string> ConfigNode::Keys() const {
  std::vector<std::string> keys;
  if (const toml::table* table = FindTable(state_->root, path_)) {
    for (const auto& [key, value] : *table) keys.emplace_back(key.str());
  }
  return keys;
}

void ConfigNode::RejectUnknownKeys() const {
  if (state_->describing) return;
  const auto& read = state_->read_keys[path_];
  std::vector<std::string> unknown;
  for (const auto& key : Keys()) {
    if (!read.count(key)) unknown.push_back(key);
  }
  if (unknown.empty()) return;
  std::vector<std::string> valid;
  for (const auto& option : state_->options[path_]) valid.push_back(option.key);
  std::string table = path_.empty() ? std::string("the top level") : fmt::format("[{}]", path_);
  throw ConfigError(
      fmt::format("{}: unknown option '{}' in {}; valid options: {}", Where(unknown.front()),
                  FullKey(unknown.front()), table,
                  valid.empty() ? std::string("none") : fmt::format("{}", fmt::join(valid, ", "))));
}

std::vector<OptionInfo> ConfigNode::Options() const {
  auto it = state_->options.find(path_);
  return it == state_->options.end() ? std::vector<OptionInfo>{} : it->second;
}

void ConfigNode::Set(std::string_view dotted_key, std::string_view value_literal) {
  std::string full = FullKey(dotted_key);
  // Walk/create the tables on the way.
  toml::table* table = &state_->root;
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

std::string ConfigNode::ToToml() const {
  const toml::table* table = FindTable(state_->root, path_);
  if (!table) return "";
  std::stringstream out;
  out << *table;
  return out.str();
}

}  // namespace harap
